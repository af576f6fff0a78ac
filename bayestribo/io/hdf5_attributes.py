"""Reading an HDF5 attribute of variable length once the lengths it stores are checked.

A variable-length string (h5py's ``str`` attributes, so most ``units``) is stored as a
length and a reference into the file's global heap. libhdf5 allocates and clears a
buffer of the stored length before it looks the value up in the heap (and finds it
shorter): a length field set to 2^31 in a file of a few kB makes the reading process
take 2 GB. So before such an attribute is read, its stored lengths are read here from
the attribute message in the object's header (version 1 or 2, with its continuation
blocks) and each must be at most the file's size; and each global heap collection they
refer to must hold its objects within it (libhdf5 loops on one that does not).

An attribute this walk does not find in its object's header (one kept in dense storage,
past eight attributes of a file written for HDF5 1.8 or later, or a shared message) is
refused by name rather than read unchecked.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import Any, BinaryIO

from bayestribo.errors import RunFormatError

__all__ = ["FileLayout", "checked_attribute"]

#: Header message types: continuation, attribute, attribute info (dense storage).
_CONTINUATION, _ATTRIBUTE, _ATTRIBUTE_INFO = 0x10, 0x0C, 0x15
#: Most header blocks followed for one object [-].
MAX_BLOCKS = 256
#: Largest header block read [bytes].
MAX_BLOCK_BYTES = 1 << 24


class _Unreadable(Exception):
    """The header does not hold the attribute where this walk looks for it."""


@dataclass(frozen=True)
class FileLayout:
    """What the header walk needs of an HDF5 file.

    Parameters
    ----------
    fh : binary file
        The file, open for reading.
    base : int
        Where its addresses count from (its user block's size) [bytes].
    offset_size, length_size : int
        Bytes of an address and of a length in the file [bytes].
    file_size : int
        The file's size [bytes].
    """

    fh: BinaryIO
    base: int
    offset_size: int
    length_size: int
    file_size: int

    @classmethod
    def of(cls, handle: Any, fh: BinaryIO, file_size: int) -> FileLayout:
        """The layout of an open ``h5py.File`` whose bytes ``fh`` reads."""
        offset_size, length_size = handle.id.get_create_plist().get_sizes()
        return cls(fh, int(handle.userblock_size), offset_size, length_size, file_size)

    def read(self, address: int, size: int) -> bytes:
        """``size`` bytes at ``address``; :class:`_Unreadable` past the file's end."""
        if size > MAX_BLOCK_BYTES or address < 0 or self.base + address + size > self.file_size:
            raise _Unreadable(f"a header block of {size} bytes at {address} is out of the file")
        self.fh.seek(self.base + address)
        return self.fh.read(size)

    def unsigned(self, data: bytes, at: int, size: int) -> int:
        if at + size > len(data):
            raise _Unreadable("a header message runs past its block")
        return int.from_bytes(data[at : at + size], "little")


def _messages(layout: FileLayout, address: int) -> list[tuple[int, int, bytes]]:
    """Every message ``(type, flags, body)`` of the object header at ``address``."""
    out: list[tuple[int, int, bytes]] = []
    prefix = layout.read(address, 16)
    if prefix[:4] == b"OHDR":
        version, flags = 2, prefix[5]
        at = 6 + (16 if flags & 0x20 else 0) + (4 if flags & 0x10 else 0)
        width = 1 << (flags & 0x03)
        head = layout.read(address, at + width)
        size = layout.unsigned(head, at, width)
        blocks = [(address + at + width, size)]
    elif prefix[0] == 1:
        version, flags = 1, 0
        blocks = [(address + 16, layout.unsigned(prefix, 8, 4))]
    else:
        raise _Unreadable(f"no object header at {address}")
    seen = 0
    while blocks:
        seen += 1
        if seen > MAX_BLOCKS:
            raise _Unreadable(f"more than {MAX_BLOCKS} header blocks")
        start, size = blocks.pop(0)
        data = layout.read(start, size)
        at, end = 0, len(data)
        if version == 2 and seen > 1:  # a continuation block: signature, messages, checksum
            if data[:4] != b"OCHK":
                raise _Unreadable(f"no continuation block at {start}")
            at, end = 4, len(data) - 4
        head = 8 if version == 1 else 4 + (2 if flags & 0x04 else 0)
        while at + head <= end:
            if version == 1:
                kind, length, mflags = struct.unpack_from("<HHB", data, at)
            else:
                kind, length, mflags = struct.unpack_from("<BHB", data, at)
            body = data[at + head : at + head + length]
            if len(body) < length:
                raise _Unreadable("a header message runs past its block")
            out.append((kind, mflags, body))
            if kind == _CONTINUATION:
                blocks.append(
                    (
                        layout.unsigned(body, 0, layout.offset_size),
                        layout.unsigned(body, layout.offset_size, layout.length_size),
                    )
                )
            at += head + length
    return out


def _attribute_data(body: bytes, name: str) -> bytes | None:
    """The stored values of an attribute message called ``name``; None for another."""
    if len(body) < 8:
        raise _Unreadable("an attribute message shorter than its header")
    version = body[0]
    name_size, type_size, space_size = struct.unpack_from("<HHH", body, 2)

    def pad(n: int) -> int:
        return (n + 7) // 8 * 8 if version == 1 else n

    if version not in (1, 2, 3):
        raise _Unreadable(f"attribute message version {version}")
    at = 8 if version < 3 else 9
    stored = body[at : at + name_size].split(b"\0", 1)[0]
    if stored.decode("utf-8", "replace") != name:
        return None
    return body[at + pad(name_size) + pad(type_size) + pad(space_size) :]


def _stored_values(
    layout: FileLayout, address: int, name: str, count: int
) -> list[tuple[int, int]]:
    """The length and global heap collection stored for each of the ``count``
    variable-length values of attribute ``name`` of the object whose header is at
    ``address``."""
    dense = False
    for kind, mflags, body in _messages(layout, address):
        dense |= kind == _ATTRIBUTE_INFO
        if kind != _ATTRIBUTE or mflags & 0x02:  # another message, or a shared one
            continue
        data = _attribute_data(body, name)
        if data is None:
            continue
        element = 4 + layout.offset_size + 4  # length, heap collection, index
        if len(data) < count * element:
            raise _Unreadable(f"its message holds {len(data)} bytes for {count} values")
        return [
            (
                layout.unsigned(data, k * element, 4),
                layout.unsigned(data, k * element + 4, layout.offset_size),
            )
            for k in range(count)
        ]
    raise _Unreadable("kept in dense storage" if dense else "not in its object's header")


def _collection_fault(layout: FileLayout, address: int) -> str | None:
    """What is wrong with the global heap collection at ``address`` (its objects each
    within it, it within the file), or None. libhdf5 loops on an object whose size
    runs past its collection."""
    try:
        head = layout.read(address, 8 + layout.length_size)
    except _Unreadable:
        return f"its global heap collection at {address} is out of the file"
    if head[:4] != b"GCOL":
        return f"no global heap collection at {address}"
    size = layout.unsigned(head, 8, layout.length_size)
    try:
        data = layout.read(address, size)
    except _Unreadable:
        return f"its global heap collection at {address} claims {size} bytes, past the file"
    at = 8 + layout.length_size
    header = 8 + layout.length_size  # index, references, reserved, size
    while at + header <= size:
        index = layout.unsigned(data, at, 2)
        length = layout.unsigned(data, at + 8, layout.length_size)
        if index == 0:  # the free space, to the collection's end
            break
        if length > size - at - header:
            return (
                f"its global heap collection at {address} holds an object of {length} bytes "
                f"in {size} bytes"
            )
        at += header + (length + 7) // 8 * 8
    return None


def _variable_length(attribute_id: Any) -> bool:
    import h5py

    kind = attribute_id.get_type()
    if kind.get_class() == h5py.h5t.VLEN:
        return True
    return isinstance(kind, h5py.h5t.TypeStringID) and kind.is_variable_str()


def checked_attribute(obj: Any, key: str, name: str, layout: FileLayout, where: str) -> Any:
    """The value of attribute ``key`` of ``obj``, read once any variable-length values
    it stores are known to be no longer than the file.

    Parameters
    ----------
    obj : h5py.Dataset or h5py.Group
        The object holding the attribute.
    key : str
        The attribute's name.
    name : str
        The object's path in the file, for messages.
    layout : FileLayout
        The file's layout (:meth:`FileLayout.of`).
    where : str
        The file, for messages.

    Returns
    -------
    object
        ``obj.attrs[key]``.

    Raises
    ------
    RunFormatError
        For a variable-length attribute whose stored length exceeds the file's size, or
        whose stored lengths cannot be found in its object's header.
    """
    import h5py

    attribute = obj.attrs.get_id(key)
    if _variable_length(attribute):
        count = math.prod(attribute.shape) if attribute.shape is not None else 0
        what = f"dataset {name!r}: attribute {key!r}"
        try:
            address = h5py.h5o.get_info(obj.id).addr
            values = _stored_values(layout, address, key, count)
        except _Unreadable as exc:
            raise RunFormatError(
                f"{what} is of variable length and its stored lengths could not be checked "
                f"({exc}); expected it in its object's header (write it as a fixed-length "
                "string, e.g. numpy.bytes_)",
                where,
            ) from None
        longest = max((length for length, _ in values), default=0)
        if longest > layout.file_size:
            raise RunFormatError(
                f"{what} claims a value of {longest} bytes, more than the file's "
                f"{layout.file_size}; a damaged or hostile reference into the global heap",
                where,
            )
        for collection in sorted({heap for length, heap in values if length}):
            fault = _collection_fault(layout, collection)
            if fault is not None:
                raise RunFormatError(f"{what}: {fault}; a damaged global heap", where)
    return obj.attrs[key]
