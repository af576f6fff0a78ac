"""What the variables of a MATLAB v5 (.mat version 5 to 7) file declare, from their headers.

A v5 file is a sequence of elements; a variable is a ``miMATRIX`` element, usually
wrapped in a ``miCOMPRESSED`` (zlib) element. Each array states its class and
dimensions in its header; a structure or cell array holds further arrays. This module
walks those headers, decompressing a piece at a time and never keeping more than a
piece, and adds up what loading each variable would allocate (every numeric element
counted as float64, :data:`~bayestribo.io.budget.FLOAT_BYTES`), so that
:func:`bayestribo.io.matlab.read_mat` can refuse a file before ``scipy.io.loadmat``
decompresses it. The walk stops as soon as the budget is exceeded: its time is bounded
by the budget, not by what the file declares.

Format: MathWorks, "MAT-File Format", version 7 (2019), chapter 1.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from typing import BinaryIO

from bayestribo.io.budget import FLOAT_BYTES

__all__ = ["MatVariable", "declared_bytes", "v5_variables"]

MI_INT8, MI_INT32, MI_UINT32 = 1, 5, 6
MI_MATRIX, MI_COMPRESSED = 14, 15
MX_CELL, MX_STRUCT, MX_OBJECT, MX_CHAR, MX_SPARSE = 1, 2, 3, 4, 5
#: Numeric classes (double to uint64); a logical array is a uint8 array with a flag.
MX_NUMERIC = range(6, 16)
#: Every array class a v5 file may hold (16, a function handle, and 17, an opaque
#: object such as a string or table, are read by ``loadmat`` as objects).
MX_CLASSES = range(1, 18)
#: Bytes of one value of each numeric data type (miINT8 to miUINT64) [bytes].
NUMERIC_BYTES = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8}
#: Integer data types (miINT8 to miUINT32, miINT64, miUINT64).
INTEGER_TYPES = frozenset({1, 2, 3, 4, 5, 6, 12, 13})
#: Data types of a character array's text (the integer types and miUTF8 to miUTF32).
CHAR_TYPES = frozenset({1, 2, 3, 4, 5, 6, 16, 17, 18})
#: Bytes a character takes once loaded (numpy's ``U`` strings) [bytes].
CHAR_BYTES = 4
#: Bytes an element of a cell or structure array takes (an object pointer) [bytes].
OBJECT_BYTES = 8
#: Bytes decompressed at a time [bytes].
PIECE = 1 << 16
#: Longest header sub-element read whole (dimensions, names) [bytes].
MAX_HEADER_ELEMENT = 1 << 16
#: Deepest nesting of structures and cells followed.
MAX_DEPTH = 32


class DamagedHeader(ValueError):
    """The headers do not follow the v5 format (left for ``loadmat`` to name)."""


class OverBudget(Exception):
    """The walk passed the bytes it was allowed (raised to stop it early)."""


@dataclass(frozen=True)
class MatVariable:
    """A top-level variable of a v5 file, found from its element's tag and header.

    Attributes
    ----------
    name : str
        The variable's name.
    offset : int
        Where its element starts in the file [bytes].
    mdtype : int
        ``miMATRIX`` or ``miCOMPRESSED``.
    nbytes : int
        Length of the element's data [bytes].
    """

    name: str
    offset: int
    mdtype: int
    nbytes: int


class _Source:
    """Bytes of one element, from the file or inflated, read in bounded pieces."""

    def __init__(self, fh: BinaryIO, nbytes: int, compressed: bool, ceiling: int) -> None:
        self._fh = fh
        self._left = nbytes
        self._zlib = zlib.decompressobj() if compressed else None
        self._tail = b""
        self._buffer = bytearray()
        self.produced = 0  # bytes of the element read (inflated) so far
        self.ceiling = ceiling  # most bytes that may be produced

    def _piece(self, want: int) -> bytes:
        want = min(want, PIECE)
        if self._zlib is None:
            data = self._fh.read(min(want, self._left))
            self._left -= len(data)
        else:
            data = b""
            while not data:
                if not self._tail:
                    if self._left <= 0 or self._zlib.eof:
                        break
                    self._tail = self._fh.read(min(PIECE, self._left))
                    if not self._tail:
                        break
                    self._left -= len(self._tail)
                try:
                    data = self._zlib.decompress(self._tail, want)
                except zlib.error as exc:
                    raise DamagedHeader(f"compressed data: {exc}") from None
                self._tail = self._zlib.unconsumed_tail
        self.produced += len(data)
        if self.produced > self.ceiling:
            raise OverBudget
        return data

    @property
    def position(self) -> int:
        """Bytes of the element consumed so far [bytes]."""
        return self.produced - len(self._buffer)

    def read(self, n: int) -> bytes:
        while len(self._buffer) < n:
            piece = self._piece(n - len(self._buffer))
            if not piece:
                raise DamagedHeader("the element ends before its header")
            self._buffer += piece
        out = bytes(self._buffer[:n])
        del self._buffer[:n]
        return out

    def skip(self, n: int) -> None:
        dropped = min(n, len(self._buffer))
        del self._buffer[:dropped]
        n -= dropped
        while n > 0:
            piece = self._piece(n)
            if not piece:
                return  # shorter than declared: loadmat names it
            n -= len(piece)


class _Walk:
    def __init__(self, source: _Source, endian: str, check: Callable[[int], None]) -> None:
        self.s = source
        self.e = endian
        self.check = check  # called with the bytes declared so far
        self.declared = 0

    def tag(self) -> tuple[int, int, bytes | None]:
        """(type, byte count, data of a small element or None)."""
        mdtype, nbytes = struct.unpack(self.e + "II", self.s.read(8))
        if mdtype >> 16:  # small data element: data in the tag's last 4 bytes
            return mdtype & 0xFFFF, mdtype >> 16, struct.pack(self.e + "I", nbytes)[: mdtype >> 16]
        return mdtype, nbytes, None

    def element(self) -> tuple[int, bytes]:
        mdtype, nbytes, small = self.tag()
        if small is not None:
            return mdtype, small
        if nbytes > MAX_HEADER_ELEMENT:
            raise DamagedHeader(f"a header element of {nbytes} bytes")
        data = self.s.read(nbytes)
        self.s.skip(-nbytes % 8)
        return mdtype, data

    def add(self, n: int) -> None:
        self.declared += n
        self.check(self.declared)

    def matrix(self, nbytes: int, depth: int, label: str = "") -> str:
        """Walk one miMATRIX element's content (``nbytes`` long); return its name
        (``label``, where it is in its structure or cell, for an unnamed one)."""
        if nbytes == 0:
            return ""
        if depth > MAX_DEPTH:
            raise DamagedHeader(f"arrays nested more than {MAX_DEPTH} deep")
        start = self.s.position
        _, flags = self.element()
        if len(flags) < 8:
            raise DamagedHeader("array flags shorter than 8 bytes")
        word, nzmax = struct.unpack(self.e + "II", flags[:8])
        cls, is_complex = word & 0xFF, bool(word & 0x800)
        dtype, dims_raw = self.element()
        if dtype not in (MI_INT32, MI_UINT32) or len(dims_raw) % 4:
            raise DamagedHeader("array dimensions are not int32")
        # int32 by the format; uint32 as some writers store them, which loadmat reads
        kind = "i" if dtype == MI_INT32 else "I"
        dims = struct.unpack(f"{self.e}{len(dims_raw) // 4}{kind}", dims_raw)
        if any(d < 0 for d in dims):
            raise DamagedHeader(f"negative array dimensions {dims}")
        count = 1
        for d in dims:
            count *= d
        _, name_raw = self.element()
        name = name_raw.decode("latin-1") or label
        if cls not in MX_CLASSES:
            raise DamagedHeader(f"array {name!r} of class {cls}, not a MATLAB class")
        parts = 2 if is_complex else 1
        if cls in MX_NUMERIC:
            self.add(count * FLOAT_BYTES * parts)
            for _part in range(parts):  # the real part, then the imaginary one
                self.data(name, NUMERIC_BYTES.keys(), count)
        elif cls == MX_CHAR:
            self.add(count * CHAR_BYTES)
            self.data(name, CHAR_TYPES, None)
        elif cls == MX_SPARSE:
            columns = dims[1] if len(dims) > 1 else 1
            self.add(nzmax * (FLOAT_BYTES * parts + 4) + (columns + 1) * 4)
            self.data(name, INTEGER_TYPES, None)  # row indices
            self.data(name, INTEGER_TYPES, columns + 1)  # column starts
            for _part in range(parts):
                self.data(name, NUMERIC_BYTES.keys(), None)
        elif cls in (MX_CELL, MX_STRUCT, MX_OBJECT):
            fields, labels = 1, [""]
            if cls != MX_CELL:
                if cls == MX_OBJECT:
                    self.element()  # class name
                _, length_raw = self.element()
                (length,) = struct.unpack(self.e + "i", length_raw[:4].ljust(4, b"\0"))
                _, names = self.element()
                fields = len(names) // length if length > 0 else 0
                labels = [
                    "." + names[k * length : (k + 1) * length].split(b"\0")[0].decode("latin-1")
                    for k in range(fields)
                ]
            self.add(count * fields * OBJECT_BYTES)
            for j in range(count * fields):
                mdtype, sub, _small = self.tag()
                if mdtype != MI_MATRIX:
                    raise DamagedHeader(f"an element of type {mdtype} inside {name!r}")
                where = f"{{{j + 1}}}" if cls == MX_CELL else labels[j % fields]
                if cls != MX_CELL and count > 1:
                    where = f"({j // fields + 1}){where}"
                self.matrix(sub, depth + 1, name + where)
        used = self.s.position - start
        if used > nbytes:
            raise DamagedHeader(f"array {name!r} holds more than its {nbytes} bytes")
        self.s.skip(nbytes - used)
        return name

    def data(self, name: str, types: Collection[int], count: int | None) -> None:
        """Skip one data element of array ``name``, refused unless of one of ``types``
        and, with ``count``, holding exactly that many values (``loadmat`` reads what
        the array's header says is there: a part missing, or of another size, is read
        past the element's end, which has crashed the interpreter)."""
        mdtype, nbytes, small = self.tag()
        size = NUMERIC_BYTES.get(mdtype, 1)
        if mdtype not in types or (count is not None and nbytes != count * size):
            held = f"{nbytes} bytes of type {mdtype}"
            wanted = "" if count is None else f" for {count} values"
            raise DamagedHeader(f"the data of array {name!r}: {held}{wanted}")
        if small is None:
            self.s.skip(nbytes + (-nbytes % 8))


def _endian(header: bytes) -> str | None:
    """The byte order of a v5 file's header, or None for another version."""
    if len(header) < 128:
        return None
    for order, mark in (("<", b"IM"), (">", b"MI")):
        if header[126:128] == mark and struct.unpack(order + "H", header[124:126])[0] == 0x0100:
            return order
    return None


def v5_variables(fh: BinaryIO) -> Iterator[MatVariable]:
    """The top-level variables of an open v5 file (their names, where they are).

    Yields nothing for a file that is not v5 (version 4, or 7.3, which is HDF5).

    Raises
    ------
    DamagedHeader
        When an element's header cannot be read.
    """
    fh.seek(0)
    endian = _endian(fh.read(128))
    if endian is None:
        return
    offset = 128
    while True:
        fh.seek(offset)
        tag = fh.read(8)
        if len(tag) < 8:
            return
        mdtype, nbytes = struct.unpack(endian + "II", tag)
        if mdtype not in (MI_MATRIX, MI_COMPRESSED):
            raise DamagedHeader(f"a top-level element of type {mdtype} at byte {offset}")
        source = _Source(fh, nbytes, mdtype == MI_COMPRESSED, MAX_HEADER_ELEMENT * 4)
        walk = _Walk(source, endian, lambda _: None)
        try:
            if mdtype == MI_COMPRESSED:
                mdtype_in, _, _ = walk.tag()
                if mdtype_in != MI_MATRIX:
                    raise DamagedHeader(f"a compressed element of type {mdtype_in}")
            walk.element()  # array flags
            walk.element()  # dimensions
            _, name = walk.element()
        except OverBudget:
            raise DamagedHeader(f"an array header longer than {source.ceiling} bytes") from None
        yield MatVariable(name.decode("latin-1"), offset, mdtype, nbytes)
        offset += 8 + nbytes + (0 if mdtype == MI_COMPRESSED else -nbytes % 8)


def declared_bytes(fh: BinaryIO, variable: MatVariable, ceiling: int) -> tuple[int, bool]:
    """What loading one variable would allocate [bytes], from its headers.

    The larger of what its arrays declare (numbers as float64, characters, cell and
    structure elements) and the bytes its element inflates to.

    Parameters
    ----------
    fh : binary file
        The open file.
    variable : MatVariable
        The variable (:func:`v5_variables`).
    ceiling : int
        Stop as soon as the count passes this many bytes [bytes].

    Returns
    -------
    bytes : int
        The bytes counted.
    complete : bool
        False when the walk stopped past ``ceiling`` (``bytes`` is then a lower bound).

    Raises
    ------
    DamagedHeader
        When its headers cannot be read.
    """
    fh.seek(0)
    endian = _endian(fh.read(128))
    if endian is None:
        raise DamagedHeader("not a version 5 file")
    fh.seek(variable.offset + 8)
    source = _Source(fh, variable.nbytes, variable.mdtype == MI_COMPRESSED, ceiling)

    def check(declared: int) -> None:
        if declared > ceiling:
            raise OverBudget

    walk = _Walk(source, endian, check)
    try:
        nbytes = variable.nbytes
        if variable.mdtype == MI_COMPRESSED:
            _, nbytes, _ = walk.tag()
        walk.matrix(nbytes, 0)
        source.skip(1 << 62)  # whatever the element holds beyond its matrix
    except OverBudget:
        return max(walk.declared, source.produced, ceiling + 1), False
    return max(walk.declared, source.produced), True
