"""Reading recordings back: indexed, sequential and damaged files, stored messages, `info`."""
