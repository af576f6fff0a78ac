"""Small files that declare huge arrays: MATLAB v5 variables compressed from zeros.

A zlib stream of N MB of zeros is built from one deflated MB repeated (each piece ends
with a full flush, so the pieces are independent) and its Adler-32 computed in closed
form: a file declaring gigabytes is written in milliseconds, never holding them.
"""

from __future__ import annotations

import struct
import zlib
from functools import cache
from pathlib import Path

MI_UINT8, MI_INT8, MI_INT32, MI_UINT32, MI_DOUBLE = 2, 1, 5, 6, 9
MI_MATRIX, MI_COMPRESSED = 14, 15
MX_STRUCT, MX_DOUBLE = 2, 6
MB = 1 << 20
_ADLER = 65521


def header() -> bytes:
    """The 128-byte header of a little-endian v5 file."""
    text = b"MATLAB 5.0 MAT-file, written by the bayestribo tests"
    return text.ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"


def element(mdtype: int, data: bytes) -> bytes:
    """A data element: tag, data, padding to 8 bytes."""
    return struct.pack("<II", mdtype, len(data)) + data + b"\0" * (-len(data) % 8)


@cache
def _deflated_mb() -> bytes:
    z = zlib.compressobj(9, zlib.DEFLATED, -15)
    return z.compress(bytes(MB)) + z.flush(zlib.Z_FULL_FLUSH)


def zlib_then_zeros(prefix: bytes, zero_mb: int) -> bytes:
    """The zlib stream of ``prefix`` followed by ``zero_mb`` MB of zero bytes."""
    z = zlib.compressobj(9, zlib.DEFLATED, -15)
    body = z.compress(prefix) + z.flush(zlib.Z_FULL_FLUSH) + _deflated_mb() * zero_mb
    body += zlib.compressobj(9, zlib.DEFLATED, -15).flush()  # an empty final block
    adler = zlib.adler32(prefix)
    low, high = adler & 0xFFFF, adler >> 16
    high = (high + zero_mb * MB * low) % _ADLER  # zeros leave the low sum as it is
    return b"\x78\xda" + body + struct.pack(">I", (high << 16) | low)


def _array_header(name: bytes, dims: tuple[int, ...], cls: int) -> bytes:
    flags = element(MI_UINT32, struct.pack("<II", cls, 0))
    shape = element(MI_INT32, struct.pack(f"<{len(dims)}i", *dims))
    return flags + shape + element(MI_INT8, name)


def zeros_variable(name: str, zero_mb: int, *, stored_as: int = MI_DOUBLE) -> bytes:
    """A compressed double variable of ``zero_mb`` MB of zero data stored as doubles
    (``MI_DOUBLE``) or as bytes (``MI_UINT8``: 8 times the values, as MATLAB does)."""
    count = zero_mb * MB // (8 if stored_as == MI_DOUBLE else 1)
    head = _array_header(name.encode(), (count, 1), MX_DOUBLE)
    data_tag = struct.pack("<II", stored_as, zero_mb * MB)
    matrix_tag = struct.pack("<II", MI_MATRIX, len(head) + 8 + zero_mb * MB)
    stream = zlib_then_zeros(matrix_tag + head + data_tag, zero_mb)
    return struct.pack("<II", MI_COMPRESSED, len(stream)) + stream


def struct_variable(name: str, field: str, zero_mb: int) -> bytes:
    """A compressed 1 x 1 structure with one double field of ``zero_mb`` MB of zeros."""
    count = zero_mb * MB // 8
    inner = _array_header(b"", (count, 1), MX_DOUBLE)
    inner_len = len(inner) + 8 + zero_mb * MB
    names = field.encode().ljust(32, b"\0")
    head = (
        _array_header(name.encode(), (1, 1), MX_STRUCT)
        + struct.pack("<HHI", MI_INT32, 4, 32)  # small element: field name length
        + element(MI_INT8, names)
    )
    prefix = (
        struct.pack("<II", MI_MATRIX, len(head) + 8 + inner_len)
        + head
        + struct.pack("<II", MI_MATRIX, inner_len)
        + inner
        + struct.pack("<II", MI_DOUBLE, zero_mb * MB)
    )
    stream = zlib_then_zeros(prefix, zero_mb)
    return struct.pack("<II", MI_COMPRESSED, len(stream)) + stream


def write_mat(path: Path, *variables: bytes, base: Path | None = None) -> Path:
    """A v5 file of the given variables (after those of the v5 file ``base``)."""
    start = base.read_bytes() if base is not None else header()
    path.write_bytes(start + b"".join(variables))
    return path
