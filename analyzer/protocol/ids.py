"""CAN identifiers, frame types and addresses named by the protocol document."""

from __future__ import annotations

CONTROL_ID = 0x00000F01  # ground station -> gimbal commands (chapter 2.1)
FEEDBACK_ID = 0x030F0001  # gimbal -> ground station, 32-byte messages in 4 segments (2.2)
GPS_ID = 0x0000FF15  # UAV GPS position (2.3.1)
ALTITUDE_ID = 0x0000FF16  # UAV altitude (2.3.2)
UAV_ATTITUDE_ID = 0x0000FF13  # UAV attitude (2.3.3)
TEXT_ID = 0x02008201  # ASCII text, start / middle frames (2.3.4)
TEXT_END_ID = 0x02008202  # ASCII text, end frame (2.3.4)

PROTOCOL_IDS = frozenset(
    {CONTROL_ID, FEEDBACK_ID, GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID, TEXT_ID, TEXT_END_ID}
)

HEADER = b"\xeb\x90"

# Byte 2 of a framed message: frame type on TCP/UART, length byte in feedback.
FRAME_CONTROL = 0x0A  # a control command (CAN data of 0x00000F01 inside)
FRAME_CAN = 0x0B  # a forwarded CAN frame (ID in bytes 3-6)
FRAME_ATTITUDE = 0x0C  # gimbal attitude feedback
FRAME_RANGING = 0x10  # laser ranging feedback

FEEDBACK_MESSAGE_SIZE = 32  # four 8-byte CAN segments
TCP_FRAME_SIZE = 24
TCP_MARKER = b"\x40\x88"  # fixed bytes 12-13 of TCP frames

COMPONENT_GIMBAL = 0x0F
COMPONENT_DUAL_SENSOR = 0x1F
COMPONENT_NAMES = {COMPONENT_GIMBAL: "gimbal", COMPONENT_DUAL_SENSOR: "dual_sensor"}

IDU_ADDRESS = "192.168.42.200"
TCP_PORT = 2000
CAMERA_ADDRESS = "192.168.42.108"
CAN_BITRATE = 1_000_000
