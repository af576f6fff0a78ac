"""The bayestribo acquisition wire protocol: frame encoding, decoding and a streaming parser.

The protocol is documented for firmware authors in ``docs/protocol.md``. In short,
the device sends binary frames and the host sends short ASCII command lines::

    offset  size  field
    0       2     sync bytes 0xA5 0x5A
    2       1     frame type
    3       2     payload length L (unsigned, little-endian, L <= MAX_PAYLOAD)
    5       4     sequence number (unsigned, little-endian)
    9       L     payload
    9+L     4     CRC-32 (zlib/IEEE 802.3) of bytes 2 .. 9+L-1, little-endian

All multi-byte fields are little-endian. A DATA frame carries the index of its first
sample and interleaved signed 16-bit counts (displacement, velocity).

The :class:`FrameParser` accepts bytes in arbitrary chunks, resynchronises after
garbage and never skips a position that could start a valid frame: a candidate that
fails its checksum is abandoned one byte at a time, so a valid frame that follows
garbage is always found.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from bayestribo.acquisition.faults import FrameError, HeaderError

__all__ = [
    "COMMANDS",
    "CRC_SIZE",
    "FRAME_TYPES",
    "HEADER_LIMITS",
    "MAX_FRAME_LENGTH",
    "MAX_LABEL_BYTES",
    "MAX_PAYLOAD",
    "PREFIX_SIZE",
    "PROTOCOL_VERSION",
    "SYNC",
    "Frame",
    "FrameParser",
    "FrameType",
    "RunEnd",
    "RunHeader",
    "decode_data",
    "decode_end",
    "decode_release",
    "decode_text",
    "encode_data",
    "encode_end",
    "encode_frame",
    "encode_release",
]

#: Two bytes that start every frame.
SYNC = b"\xa5\x5a"
#: Protocol version carried in the run header.
PROTOCOL_VERSION = 1
#: Largest payload a frame may carry [bytes] (1024 sample pairs plus the index).
MAX_PAYLOAD = 4100
#: Largest payload length a frame's 16-bit length field can state [bytes].
MAX_FRAME_LENGTH = 0xFFFF
#: Longest range label of a run header [bytes of UTF-8].
MAX_LABEL_BYTES = 256
#: Plausible bounds of the run header's numbers: beyond them the header is refused,
#: so that no run file is written that the package's own reader would reject.
HEADER_LIMITS: dict[str, tuple[float, float]] = {
    "sample_rate_Hz": (1.0, 1e7),
    "displacement_scale_m": (1e-15, 1e-2),
    "velocity_scale_m_per_s": (1e-15, 1e1),
    "displacement_range_m": (1e-9, 10.0),
    "velocity_range_m_per_s": (1e-9, 1e3),
}
#: Bytes before the payload: sync, type, length, sequence number.
PREFIX_SIZE = 9
#: Bytes of the trailing checksum.
CRC_SIZE = 4

_PREFIX = struct.Struct("<2sBHI")
_CRC = struct.Struct("<I")
_U32 = struct.Struct("<I")
_END = struct.Struct("<II")
_HEADER = struct.Struct("<BBHddddd")


class FrameType:
    """Frame type codes sent by the device."""

    IDENT = 0x01
    HEADER = 0x02
    ACK = 0x03
    ERROR = 0x04
    DATA = 0x10
    RELEASE = 0x11
    END = 0x1F


#: Names of the known frame types, by code.
FRAME_TYPES: dict[int, str] = {
    FrameType.IDENT: "IDENT",
    FrameType.HEADER: "HEADER",
    FrameType.ACK: "ACK",
    FrameType.ERROR: "ERROR",
    FrameType.DATA: "DATA",
    FrameType.RELEASE: "RELEASE",
    FrameType.END: "END",
}

#: Host commands (ASCII lines ending in ``\n``) and the frame each one is answered with.
COMMANDS: dict[str, str] = {
    "ID?": "IDENT",
    "CFG?": "HEADER",
    "RATE <Hz>": "ACK or ERROR",
    "SPF <n>": "ACK or ERROR",
    "DUR <s>": "ACK or ERROR",
    "ARM": "HEADER, then DATA frames",
    "FIRE": "RELEASE",
    "STOP": "END",
}


class Frame(NamedTuple):
    """One frame that passed its checksum.

    Attributes
    ----------
    type : int
        Frame type code (:class:`FrameType`).
    seq : int
        Sequence number.
    payload : bytes
        Payload bytes.
    offset : int
        Offset of the frame's first sync byte in the byte stream given to the parser.
    """

    type: int
    seq: int
    payload: bytes
    offset: int

    @property
    def size(self) -> int:
        """Size of the whole frame on the wire [bytes]."""
        return PREFIX_SIZE + len(self.payload) + CRC_SIZE


def encode_frame(frame_type: int, seq: int, payload: bytes = b"") -> bytes:
    """Encode one frame: sync, type, length, sequence number, payload, CRC-32.

    Parameters
    ----------
    frame_type : int
        A :class:`FrameType` code.
    seq : int
        Sequence number, 0 <= seq < 2**32.
    payload : bytes
        At most :data:`MAX_PAYLOAD` bytes.

    Returns
    -------
    bytes
        The frame as sent on the wire.
    """
    if frame_type not in FRAME_TYPES:
        raise FrameError(f"frame_type: unknown frame type {frame_type!r}")
    if len(payload) > MAX_PAYLOAD:
        raise FrameError(f"payload: {len(payload)} bytes, at most {MAX_PAYLOAD} allowed")
    if not 0 <= seq < 2**32:
        raise FrameError(f"seq: {seq} is not an unsigned 32-bit number")
    body = _PREFIX.pack(SYNC, frame_type, len(payload), seq) + bytes(payload)
    return body + _CRC.pack(zlib.crc32(body[2:]))


class FrameParser:
    """Streaming frame parser that resynchronises after garbage.

    Feed it bytes in chunks of any size; it returns the frames completed by each
    chunk. Bytes that cannot belong to a valid frame are counted in
    :attr:`discarded_bytes`, candidates that fail their checksum in
    :attr:`rejected_candidates`. It never raises on the content of the bytes.

    Notes
    -----
    A candidate is a sync pair followed by a known type and a length of at most
    :data:`MAX_PAYLOAD`. A candidate whose checksum fails is abandoned by one byte
    only, so every later position is still tried: a valid frame is lost only if a
    false candidate that overlaps it passes CRC-32, a chance of 2⁻³² per candidate.
    A false candidate can delay the frames it overlaps until enough bytes arrive to
    check it (or until :meth:`finish`), never drop them.

    Parameters
    ----------
    max_header_payload : int
        Longest HEADER payload taken as a candidate [bytes]. The default,
        :data:`MAX_PAYLOAD`, bounds the delay a false candidate can cause while
        streaming; a parser of a whole raw log takes :data:`MAX_FRAME_LENGTH`, so a run
        header with an oversized label is found and refused with its reason.
    """

    def __init__(self, *, max_header_payload: int = MAX_PAYLOAD) -> None:
        if not MAX_PAYLOAD <= max_header_payload <= MAX_FRAME_LENGTH:
            raise FrameError(
                f"max_header_payload: expected {MAX_PAYLOAD} to {MAX_FRAME_LENGTH} bytes, "
                f"got {max_header_payload!r}"
            )
        self.max_header_payload = max_header_payload
        self._buf = bytearray()
        self._base = 0  # stream offset of self._buf[0]
        self.discarded_bytes = 0
        self.rejected_candidates = 0
        self.frames_parsed = 0

    @property
    def pending_bytes(self) -> int:
        """Bytes held back, waiting for the rest of a possible frame."""
        return len(self._buf)

    def feed(self, data: bytes | bytearray | memoryview) -> list[Frame]:
        """Add bytes from the stream; return the frames they complete, in stream order."""
        self._buf += data
        return self._scan(final=False)

    def finish(self) -> list[Frame]:
        """Declare the end of the stream: return any frames left, discard the rest."""
        frames = self._scan(final=True)
        self.discarded_bytes += len(self._buf)
        self._base += len(self._buf)
        self._buf.clear()
        return frames

    def _scan(self, final: bool) -> list[Frame]:
        buf = self._buf
        frames: list[Frame] = []
        pos = 0
        n = len(buf)
        while True:
            i = buf.find(SYNC, pos)
            if i < 0:
                # Keep a trailing first sync byte: its partner may be in the next chunk.
                stop = n - 1 if (n > pos and buf[n - 1] == SYNC[0] and not final) else n
                self.discarded_bytes += stop - pos
                pos = stop
                break
            self.discarded_bytes += i - pos
            pos = i
            if n - i < PREFIX_SIZE:
                if final:
                    self.discarded_bytes += 1
                    pos = i + 1
                    continue
                break
            _, ftype, length, seq = _PREFIX.unpack_from(buf, i)
            limit = self.max_header_payload if ftype == FrameType.HEADER else MAX_PAYLOAD
            if ftype not in FRAME_TYPES or length > limit:
                self.discarded_bytes += 1
                pos = i + 1
                continue
            end = i + PREFIX_SIZE + length + CRC_SIZE
            if end > n:
                if final:
                    self.rejected_candidates += 1
                    self.discarded_bytes += 1
                    pos = i + 1
                    continue
                break
            (crc,) = _CRC.unpack_from(buf, end - CRC_SIZE)
            if zlib.crc32(memoryview(buf)[i + 2 : end - CRC_SIZE]) != crc:
                self.rejected_candidates += 1
                self.discarded_bytes += 1
                pos = i + 1
                continue
            payload = bytes(buf[i + PREFIX_SIZE : end - CRC_SIZE])
            frames.append(Frame(ftype, seq, payload, self._base + i))
            pos = end
        del buf[:pos]
        self._base += pos
        self.frames_parsed += len(frames)
        return frames


@dataclass(frozen=True)
class RunHeader:
    """The device's run header: scale factors, sample rate and vibrometer ranges.

    Attributes
    ----------
    sample_rate_Hz : float
        Sample rate of both channels [Hz].
    displacement_scale_m : float
        Metres per displacement count [m].
    velocity_scale_m_per_s : float
        Metres per second per velocity count [m/s].
    displacement_range_m : float
        Full-scale displacement range of the vibrometer setting (± this) [m].
    velocity_range_m_per_s : float
        Full-scale velocity range of the vibrometer setting (± this) [m/s].
    samples_per_frame : int
        Sample pairs in a full DATA frame (the last one may be shorter).
    range_label : str
        Free text naming the vibrometer range settings (e.g. ``"DD-500 2mm; VD-06 0.5m/s"``).
    channels : int
        Number of channels (2: displacement and velocity).
    version : int
        Protocol version.
    """

    sample_rate_Hz: float
    displacement_scale_m: float
    velocity_scale_m_per_s: float
    displacement_range_m: float
    velocity_range_m_per_s: float
    samples_per_frame: int
    range_label: str = ""
    channels: int = 2
    version: int = PROTOCOL_VERSION

    def to_payload(self) -> bytes:
        """Encode as a HEADER payload (44 fixed bytes, then the UTF-8 range label)."""
        return _HEADER.pack(
            self.version,
            self.channels,
            self.samples_per_frame,
            self.sample_rate_Hz,
            self.displacement_scale_m,
            self.velocity_scale_m_per_s,
            self.displacement_range_m,
            self.velocity_range_m_per_s,
        ) + self.range_label.encode("utf-8")

    @classmethod
    def from_payload(cls, payload: bytes) -> RunHeader:
        """Decode and check a HEADER payload.

        Raises
        ------
        HeaderError
            If the payload is too short, the version or channel count is not
            supported, a scale, rate or range is not positive and finite, or the label
            is not UTF-8.
        """
        if len(payload) < _HEADER.size:
            raise HeaderError(
                f"run header: payload of {len(payload)} bytes, expected at least {_HEADER.size}"
            )
        version, channels, spf, rate, dscale, vscale, drange, vrange = _HEADER.unpack_from(payload)
        if version != PROTOCOL_VERSION:
            raise HeaderError(
                f"run header: protocol version {version}, this host speaks {PROTOCOL_VERSION}"
            )
        if channels != 2:
            raise HeaderError(f"run header: {channels} channels, expected 2")
        if not 1 <= spf <= (MAX_PAYLOAD - 4) // 4:
            raise HeaderError(
                f"run header: samples_per_frame {spf}, expected 1..{(MAX_PAYLOAD - 4) // 4}"
            )
        for name, value in (
            ("sample_rate_Hz", rate),
            ("displacement_scale_m", dscale),
            ("velocity_scale_m_per_s", vscale),
            ("displacement_range_m", drange),
            ("velocity_range_m_per_s", vrange),
        ):
            low, high = HEADER_LIMITS[name]
            if not (math.isfinite(value) and low <= value <= high):
                raise HeaderError(
                    f"run header: {name} = {value!r}, expected a finite value in "
                    f"[{low:g}, {high:g}]"
                )
        raw_label = payload[_HEADER.size :]
        if len(raw_label) > MAX_LABEL_BYTES:
            raise HeaderError(
                f"run header: range label of {len(raw_label)} bytes, at most {MAX_LABEL_BYTES}"
            )
        try:
            label = raw_label.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise HeaderError(f"run header: range label is not UTF-8 ({exc})") from None
        return cls(rate, dscale, vscale, drange, vrange, spf, label, channels, version)

    def as_metadata(self) -> dict[str, object]:
        """The header as JSON-ready metadata."""
        return {
            "protocol_version": self.version,
            "channels": self.channels,
            "samples_per_frame": self.samples_per_frame,
            "sample_rate_Hz": self.sample_rate_Hz,
            "displacement_scale_m_per_count": self.displacement_scale_m,
            "velocity_scale_m_per_s_per_count": self.velocity_scale_m_per_s,
            "displacement_range_m": self.displacement_range_m,
            "velocity_range_m_per_s": self.velocity_range_m_per_s,
            "range_label": self.range_label,
        }


class RunEnd(NamedTuple):
    """Content of an END frame: frames sent in the run before END, samples sent."""

    frame_count: int
    sample_count: int


def encode_data(first_index: int, counts: NDArray[np.int16]) -> bytes:
    """DATA payload: first sample index (u32) and interleaved int16 (displacement, velocity).

    Parameters
    ----------
    first_index : int
        Index of the frame's first sample since ARM.
    counts : ndarray, shape (n, 2)
        Raw counts, column 0 displacement, column 1 velocity.
    """
    counts = np.asarray(counts)
    if counts.ndim != 2 or counts.shape[1] != 2:
        raise FrameError(f"counts: expected shape (n, 2), got {counts.shape}")
    return _U32.pack(first_index) + counts.astype("<i2").tobytes()


def decode_data(payload: bytes) -> tuple[int, NDArray[np.int16]]:
    """Decode a DATA payload into (first sample index, counts of shape (n, 2)).

    Raises
    ------
    FrameError
        If the payload is shorter than 8 bytes or not 4 + 4n bytes long.
    """
    if len(payload) < 8 or (len(payload) - 4) % 4:
        raise FrameError(
            f"DATA frame: payload of {len(payload)} bytes, expected 4 + 4n with n >= 1"
        )
    (first,) = _U32.unpack_from(payload)
    counts = np.frombuffer(payload, dtype="<i2", offset=4).reshape(-1, 2)
    return first, counts


def encode_release(sample_index: int) -> bytes:
    """RELEASE payload: index of the first sample after the release (u32)."""
    return _U32.pack(sample_index)


def decode_release(payload: bytes) -> int:
    """Decode a RELEASE payload; raise :class:`FrameError` if it is not 4 bytes."""
    if len(payload) != _U32.size:
        raise FrameError(f"RELEASE frame: payload of {len(payload)} bytes, expected 4")
    return _U32.unpack(payload)[0]


def encode_end(frame_count: int, sample_count: int) -> bytes:
    """END payload: frames sent in the run before END (u32), samples sent (u32)."""
    return _END.pack(frame_count, sample_count)


def decode_end(payload: bytes) -> RunEnd:
    """Decode an END payload; raise :class:`FrameError` if it is not 8 bytes."""
    if len(payload) != _END.size:
        raise FrameError(f"END frame: payload of {len(payload)} bytes, expected 8")
    return RunEnd(*_END.unpack(payload))


def decode_text(frame: Frame) -> str:
    """Text of an IDENT, ACK or ERROR frame (UTF-8, undecodable bytes replaced)."""
    return frame.payload.decode("utf-8", errors="replace")
