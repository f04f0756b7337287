"""Raw byte dumps of a TCP or UART stream (``.bin``): the bytes, in order, without timestamps."""

from __future__ import annotations

from collections.abc import Iterator

from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.content import describe
from analyzer.protocol.types import StreamChunk

CHUNK_SIZE = 1 << 16
MIN_BYTES = 64  # below this a stream says too little to judge
DAMAGE_SHARE = 0.5  # discarded bytes from which a stream counts as almost all damage
CRC_FAILED_SHARE = 0.9  # share of CRC-checked frames that failed


class RawStreamReader(InputReader):
    """A file of stream bytes; handed on in chunks, all at time 0.0 (a dump has no clock).

    ``direction`` (``gs_to_idu`` / ``idu_to_gs``) may be given when it is known which
    side of the link was dumped.
    """

    format_name = "stream"

    def __init__(self, path: str, *, direction: str = "", chunk_size: int = CHUNK_SIZE) -> None:
        super().__init__(path)
        self._handle = self._open_binary()
        self.direction = direction
        self.chunk_size = chunk_size
        self.chunks = 0
        head = self._handle.read(4096)
        self._handle.seek(0)
        # What the bytes look like when they are something else (a DataFlash log, a capture).
        self.looks_like = describe(head)
        if self.looks_like is not None and self.looks_like[1] is not None:
            words, fmt = self.looks_like
            self.notes.append(
                f"{self.source} looks like {words}, not a raw TCP/UART stream: "
                f"read it with --format {fmt}"
            )

    def __iter__(self) -> Iterator[InputItem]:
        read = self._handle.read
        while True:
            data = read(self.chunk_size)
            if not data:
                break
            self.position_bytes += len(data)
            self.chunks += 1
            yield StreamChunk(0.0, data, self.source, self.direction)

    @property
    def stats(self) -> dict[str, int]:
        return {"bytes": self.position_bytes, "chunks": self.chunks}


def raw_stream_mismatch(
    reader: InputReader, decoder_stats: dict[str, int], crc_checked: int, crc_errors: int
) -> list[str]:
    """A note when a file read as a raw TCP/UART stream gave almost nothing but damage,
    saying what the file looks like instead (text, an archive...) when the reader has not
    said so already (it names the formats this tool reads, see RawStreamReader)."""
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
