"""H.264 / H.265 Annex B access units: NAL units, parameter sets, keyframes (bytes only)."""

from __future__ import annotations

from dataclasses import dataclass, field

START_CODE = b"\x00\x00\x00\x01"

H264 = "h264"
H265 = "h265"
CODECS = (H264, H265)

# H.264 nal_unit_type (ITU-T H.264 table 7-1)
H264_IDR = 5
H264_SEI = 6
H264_SPS = 7
H264_PPS = 8
H264_AUD = 9
# H.265 nal_unit_type (ITU-T H.265 table 7-1)
H265_IRAP_FIRST, H265_IRAP_LAST = 16, 23
H265_VPS = 32
H265_SPS = 33
H265_PPS = 34
H265_AUD = 35


def split_nals(data: bytes) -> list[bytes]:
    """The NAL units of an Annex B byte string (start codes removed, empty units dropped).

    Bytes before the first start code (not Annex B) are returned as one unit, so nothing
    is lost; trailing zero bytes of a unit belong to the next start code and are cut."""
    find = data.find
    pos = find(b"\x00\x00\x01")
    if pos < 0:
        return [data] if data else []
    units: list[bytes] = []
    lead = data[:pos].rstrip(b"\x00")
    if lead:
        units.append(lead)
    start = pos + 3
    while True:
        end = find(b"\x00\x00\x01", start)
        if end < 0:
            if data[start:]:
                units.append(data[start:])
            return units
        unit = data[start:end].rstrip(b"\x00")
        if unit:
            units.append(unit)
        start = end + 3


def nal_type(codec: str, unit: bytes) -> int:
    if not unit:
        return -1
    if codec == H265:
        return (unit[0] >> 1) & 0x3F
    return unit[0] & 0x1F


def is_parameter_set(codec: str, kind: int) -> bool:
    if codec == H265:
        return kind in (H265_VPS, H265_SPS, H265_PPS)
    return kind in (H264_SPS, H264_PPS)


def is_aud(codec: str, kind: int) -> bool:
    return kind == (H265_AUD if codec == H265 else H264_AUD)


def is_vcl(codec: str, kind: int) -> bool:
    return 0 <= kind < 32 if codec == H265 else 1 <= kind <= 5


def is_key_slice(codec: str, kind: int) -> bool:
    if codec == H265:
        return H265_IRAP_FIRST <= kind <= H265_IRAP_LAST
    return kind == H264_IDR


def parameter_sets_from_extradata(codec: str, extradata: bytes) -> list[bytes]:
    """SPS / PPS (and VPS) of a stream's extradata: Annex B, avcC or hvcC."""
    if not extradata:
        return []
    if extradata[:3] == b"\x00\x00\x01" or extradata[:4] == START_CODE:
        return [u for u in split_nals(extradata) if is_parameter_set(codec, nal_type(codec, u))]
    try:
        return _hvcc(extradata) if codec == H265 else _avcc(extradata)
    except IndexError:  # truncated record: what was read so far is all there is
        return []


def _avcc(data: bytes) -> list[bytes]:
    """ISO/IEC 14496-15 AVCDecoderConfigurationRecord."""
    out: list[bytes] = []
    pos = 5
    for mask in (0x1F, 0xFF):  # numOfSequenceParameterSets, numOfPictureParameterSets
        end = _take_units(data, pos + 1, data[pos] & mask, out)
        if end is None:
            break
        pos = end
    return out


def _hvcc(data: bytes) -> list[bytes]:
    """ISO/IEC 14496-15 HEVCDecoderConfigurationRecord."""
    out: list[bytes] = []
    arrays = data[22]
    pos = 23
    for _ in range(arrays):
        pos += 1  # array_completeness, NAL_unit_type
        end = _take_units(data, pos + 2, int.from_bytes(data[pos : pos + 2], "big"), out)
        if end is None:
            break
        pos = end
    return out


def _take_units(data: bytes, pos: int, count: int, out: list[bytes]) -> int | None:
    """Append ``count`` units of 2-byte length + bytes from ``pos``; the position after
    them, or None when the record is cut short inside one (what was read is kept)."""
    for _ in range(count):
        size = int.from_bytes(data[pos : pos + 2], "big")
        unit = data[pos + 2 : pos + 2 + size]
        if len(unit) != size:
            return None
        out.append(unit)
        pos += 2 + size
    return pos


@dataclass(slots=True)
class AccessUnit:
    """One picture's NAL units, with its stream time (``pts`` in time-base units)."""

    pts: int | None
    arrival: float
    wallclock: float | None = None  # capture time from an RTCP sender report, if any
    units: list[bytes] = field(default_factory=list)
    restart: bool = False  # a keyframe whose timestamp went back: the camera started over

    def keyframe(self, codec: str) -> bool:
        return any(is_key_slice(codec, nal_type(codec, u)) for u in self.units)

    def has_picture(self, codec: str) -> bool:
        return any(is_vcl(codec, nal_type(codec, u)) for u in self.units)


class ParameterSets:
    """The stream's latest SPS / PPS (/ VPS): what a keyframe needs in front of it."""

    def __init__(self, codec: str, initial: list[bytes] | None = None) -> None:
        self.codec = codec
        self._sets: dict[bytes, bytes] = {}
        for unit in initial or ():
            self.note(unit)

    def note(self, unit: bytes) -> None:
        # One set of each type (a new SPS replaces the old); PPS by their first payload
        # byte, where a picture parameter set id of a few bits lives.
        header = 2 if self.codec == H265 else 1
        pps = nal_type(self.codec, unit) in (H264_PPS, H265_PPS)
        key = bytes([nal_type(self.codec, unit)]) + (unit[header : header + 1] if pps else b"")
        self._sets[key] = unit

    def units(self) -> list[bytes]:
        order = (H265_VPS, H265_SPS, H265_PPS) if self.codec == H265 else (H264_SPS, H264_PPS)
        known = list(self._sets.values())
        return sorted(known, key=lambda u: order.index(nal_type(self.codec, u)))

    def __bool__(self) -> bool:
        return bool(self._sets)


def annex_b(codec: str, unit_list: list[bytes], params: ParameterSets) -> tuple[bytes, bool]:
    """One access unit in Annex B order (AUD, parameter sets, SEI, slices) and whether it is
    a keyframe. A keyframe gets the stream's parameter sets in front when it lacks them;
    sets repeated inside the unit are written once."""
    aud: list[bytes] = []
    own: list[bytes] = []
    rest: list[bytes] = []
    key = False
    for unit in unit_list:
        kind = nal_type(codec, unit)
        if is_aud(codec, kind):
            aud = aud or [unit]
        elif is_parameter_set(codec, kind):
            params.note(unit)
            if unit not in own:
                own.append(unit)
        else:
            key = key or is_key_slice(codec, kind)
            rest.append(unit)
    sets = params.units() if key else own
    return b"".join(START_CODE + u for u in (*aud, *sets, *rest)), key
