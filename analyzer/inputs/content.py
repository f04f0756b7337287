"""What a file's first bytes look like, in words, with the --format that reads them."""

from __future__ import annotations

from analyzer.inputs.detect import sniff_format

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


def describe(head: bytes) -> tuple[str, str | None] | None:
    """(what the bytes look like, the --format that reads them or None); None if unknown."""
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
