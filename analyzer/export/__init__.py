"""Exports of the protocol tables for other tools: a DBC file and a Wireshark dissector."""

from __future__ import annotations
