"""Reproduce a flight on the bench: its ground station's frames sent again with its timing."""
