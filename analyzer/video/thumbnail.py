"""Small JPEG pictures of keyframes (PyAV decodes the frame and encodes the JPEG)."""

from __future__ import annotations

from fractions import Fraction
from typing import cast

import av

THUMBNAIL_WIDTH = 320
DECODERS = {"h264": "h264", "h265": "hevc"}  # Foxglove's format names -> FFmpeg's decoders


def thumbnail_size(width: int, height: int, max_width: int = THUMBNAIL_WIDTH) -> tuple[int, int]:
    """The size of the thumbnail of a ``width`` x ``height`` picture (even numbers)."""
    scale = min(1.0, max_width / max(1, width))
    return max(2, int(width * scale) // 2 * 2), max(2, int(height * scale) // 2 * 2)


def jpeg_thumbnail(codec: str, access_unit: bytes, width: int = THUMBNAIL_WIDTH) -> bytes | None:
    """A JPEG of the keyframe in ``access_unit`` (Annex B with its parameter sets), at most
    ``width`` pixels wide; None when it does not decode."""
    try:
        decoder = cast(av.VideoCodecContext, av.CodecContext.create(DECODERS[codec], "r"))
        frames = [*decoder.decode(av.Packet(access_unit)), *decoder.decode(None)]
        if not frames:
            return None
        frame = frames[0]
        w, h = thumbnail_size(frame.width, frame.height, width)
        small = frame.reformat(width=w, height=h, format="yuvj420p")
        encoder = cast(av.VideoCodecContext, av.CodecContext.create("mjpeg", "w"))
        encoder.width, encoder.height = w, h
        encoder.pix_fmt = "yuvj420p"
        encoder.time_base = Fraction(1, 25)
        packets = [*encoder.encode(small), *encoder.encode(None)]
    except (av.error.FFmpegError, ValueError, KeyError):
        return None
    return bytes(packets[0]) if packets else None


def picture_size(codec: str, access_unit: bytes) -> tuple[int, int]:
    """Width and height of the picture in ``access_unit`` ((0, 0) when it does not decode)."""
    try:
        decoder = cast(av.VideoCodecContext, av.CodecContext.create(DECODERS[codec], "r"))
        frames = [*decoder.decode(av.Packet(access_unit)), *decoder.decode(None)]
    except (av.error.FFmpegError, ValueError, KeyError):
        return 0, 0
    return (frames[0].width, frames[0].height) if frames else (0, 0)
