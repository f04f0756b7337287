"""Note 3 of the document: crc_fly16 is CRC-16/MODBUS, stored little-endian."""

from __future__ import annotations

from analyzer.protocol.crc import check_crc, crc16, crc_bytes


def crc_fly16_reference(buffer: bytes) -> int:
    """The vendor's nibble-table C code, transcribed line by line."""
    table = [
        0x0000, 0xCC01, 0xD801, 0x1400, 0xF001, 0x3C00, 0x2800, 0xE401,
        0xA001, 0x6C00, 0x7800, 0xB401, 0x5000, 0x9C01, 0x8801, 0x4400,
    ]  # fmt: skip
    crc = 0xFFFF
    for byte in buffer:
        tmp = table[(byte ^ crc) & 15] ^ (crc >> 4)
        crc = table[((byte >> 4) ^ tmp) & 15] ^ (tmp >> 4)
    return crc


def test_check_value_of_crc16_modbus() -> None:
    assert crc16(b"123456789") == 0x4B37


def test_matches_the_vendor_nibble_table_code() -> None:
    for sample in (b"", b"\x00", b"\xeb\x90\x0a", bytes(range(256)), b"123456789" * 7):
        assert crc16(sample) == crc_fly16_reference(sample)


def test_crc_is_stored_low_byte_first() -> None:
    assert crc_bytes(b"123456789") == b"\x37\x4b"


def test_checked_tcp_frames_of_the_notes() -> None:
    look_down = bytes.fromhex(
        "EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E"
    )
    pan_80 = bytes.fromhex(
        "EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 04 40 1F 00 00 00 00 C0 5C"
    )
    assert check_crc(look_down)
    assert check_crc(pan_80)
    assert not check_crc(look_down[:-1] + b"\x00")
    assert not check_crc(b"\x01")
