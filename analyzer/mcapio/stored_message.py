"""A message as a recording stores it, and the role of the channel it is on."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from analyzer.mcapio.channels import RAW_TOPICS, ROLE_EVENT, ROLE_KEY, ROLE_RAW, ROLE_VIEW
from analyzer.mcapio.foxglove import VIEW_SCHEMAS

# tally(topic, role, log_time): called for every message a sequential read meets
MessageTally = Callable[[str, str, int], None]
# wanted(topic, role): whether a read yields the messages of a channel
ChannelFilter = Callable[[str, str], bool]


@dataclass(frozen=True, slots=True)
class RawMessage:
    """One message as stored: channel topic and role, log time (ns) and the JSON bytes."""

    topic: str
    role: str
    log_time: int
    data: bytes


def channel_role(topic: str, metadata: dict[str, str]) -> str:
    """Role of a channel: from its metadata, else guessed from the topic (other writers)."""
    role = metadata.get(ROLE_KEY)
    if role:
        return role
    if topic in RAW_TOPICS:
        return ROLE_RAW
    if topic in VIEW_SCHEMAS:
        return ROLE_VIEW
    return ROLE_EVENT
