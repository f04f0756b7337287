"""Where the decoder sends the frames of each protocol CAN ID: the one routing table.

The decoder's frame-by-frame dispatch (``Decoder._frame``) and its columnar path
(``vector_decode``) both route by this table, so a frame goes the same way whether it
comes alone or in a block of columns.
"""

from __future__ import annotations

from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, TEXT_END_ID, TEXT_ID
from analyzer.protocol.uav import STATUS_FRAMES

COMMAND = "command"  # a ground station command: decoded by the command table
FEEDBACK = "feedback"  # a segment of a 4-segment feedback message: reassembled per channel
TEXT = "text"  # a frame of a UAV text message: assembled per channel
STATUS = "status"  # a UAV status frame (GPS, altitude, attitude)

ROUTES: dict[int, str] = {
    CONTROL_ID: COMMAND,
    FEEDBACK_ID: FEEDBACK,
    TEXT_ID: TEXT,
    TEXT_END_ID: TEXT,
    **dict.fromkeys(STATUS_FRAMES, STATUS),
}

STATUS_TOPICS: dict[int, str] = {can_id: status.topic for can_id, status in STATUS_FRAMES.items()}
