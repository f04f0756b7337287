"""What a file read as a raw stream looks like instead, for a note when it was all damage."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from analyzer.inputs.base import InputReader

# sniffed format -> (what it is, in words)
DESCRIPTIONS = {
    "dataflash": "an ArduPilot DataFlash log",
    "pcap": "a pcap / pcapng capture",
    "mcap": "an MCAP recording",
    "blf": "a Vector BLF log",
    "candump": "candump text",
    "asc": "a Vector ASC log",
    "trc": "a PCAN TRC log",
    "csv": "a python-can CSV log",
    "savvycan": "a SavvyCAN CSV log",
}
OTHER_MAGICS = (
    (b"\x1f\x8b", "gzip-compressed data"),
    (b"PK\x03\x04", "a ZIP archive"),
    (b"\x7fELF", "a program (ELF)"),
    (b"\x89PNG", "a PNG image"),
    (b"\xff\xd8\xff", "a JPEG image"),
)
MIN_BYTES = 64  # below this a stream says too little to judge
DAMAGE_SHARE = 0.5  # discarded bytes from which a stream counts as almost all damage
CRC_FAILED_SHARE = 0.9  # share of CRC-checked frames that failed


def describe(head: bytes) -> tuple[str, str | None] | None:
    """(what the bytes look like, the --format that reads them or None); None if unknown."""
    from analyzer.inputs import sniff_format

    found = sniff_format(head)
    if found in DESCRIPTIONS:
        return DESCRIPTIONS[found], found
    for magic, words in OTHER_MAGICS:
        if head.startswith(magic):
            return words, None
    sample = head[:512]
    if sample and sum(32 <= b < 127 or b in (9, 10, 13) for b in sample) > 0.95 * len(sample):
        return "text", None
    return None


def raw_stream_mismatch(
    reader: InputReader, decoder_stats: dict[str, int], crc_checked: int, crc_errors: int
) -> list[str]:
    """A note when a file read as a raw TCP/UART stream gave almost nothing but damage,
    saying what the file looks like instead (text, an archive...) when the reader has not
    said so already (it names the formats this tool reads, see RawStreamReader)."""
    from analyzer.inputs.raw_stream import RawStreamReader

    if not isinstance(reader, RawStreamReader):
        return []
    fed = decoder_stats.get("bytes_fed", 0)
    discarded = decoder_stats.get("bytes_discarded", 0)
    checked = crc_checked + crc_errors
    mostly_garbage = fed >= MIN_BYTES and discarded >= DAMAGE_SHARE * fed
    mostly_bad_crc = checked >= 4 and crc_errors >= CRC_FAILED_SHARE * checked
    if not (mostly_garbage or mostly_bad_crc):
        return []
    seen = f"read as a raw TCP/UART stream, {discarded:,} of its {fed:,} bytes were no frame"
    if checked:
        seen += f" and {crc_errors:,} of {checked:,} framed messages failed their CRC"
    looks = reader.looks_like
    if looks is None:
        return [
            f"{reader.source} is almost all damage ({seen}): it is probably not a dump of "
            "the gimbal's stream; check the file or give --format"
        ]
    words, fmt = looks
    if fmt is not None:  # the reader has said what it is and which --format reads it
        return [f"the damage in {reader.source} is no damage ({seen}): it is {words}"]
    return [f"{reader.source} looks like {words}, not a raw stream ({seen})"]
