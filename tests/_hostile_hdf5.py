"""Small HDF5 files whose stored chunks make libhdf5 allocate far past what they declare.

Each holds a run's ``time`` and ``displacement`` (ten samples each, with units) under a
group, the displacement chunked and filtered; its one stored chunk is written raw
(``write_direct_chunk``) so that it decodes to more than its chunk shape declares, or
its chunk shape or its filter's parameters are out of all proportion. The deflate
streams are built in closed form (:func:`_hostile.zlib_then_zeros`): a file declaring a
gigabyte is written in milliseconds, never holding it.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
from _hostile import MB, zlib_then_zeros

#: Samples of each dataset.
SAMPLES = 10
#: The 128-byte MATLAB v7.3 header, written into the file's 512-byte user block.
V73_HEADER = (
    b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(116, b" ")
    + b"\0" * 8
    + b"\x00\x02IM"
)


def _time(group, name: str = "time") -> None:
    group.create_dataset(name, data=np.arange(SAMPLES) / 1000.0).attrs["units"] = "s"


def _filtered(group, name: str, chunk: int, filters: list[str], *, extendable: bool = False):
    """A float64 dataset of :data:`SAMPLES` values in metres, chunked by ``chunk``, with
    the ``filters`` (``"deflate"``, ``"shuffle"``, ``"fletcher32"``) in that order
    (``extendable``: its length unlimited, so its chunk may be longer)."""
    import h5py

    space = h5py.h5s.create_simple((SAMPLES,), (h5py.h5s.UNLIMITED if extendable else SAMPLES,))
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_chunk((chunk,))
    setters = {
        "deflate": lambda: dcpl.set_deflate(6),
        "shuffle": dcpl.set_shuffle,
        "fletcher32": dcpl.set_fletcher32,
    }
    for kind in filters:
        setters[kind]()
    dsid = h5py.h5d.create(group.id, name.encode(), h5py.h5t.IEEE_F64LE, space, dcpl=dcpl)
    group[name].attrs["units"] = "m"
    return dsid


def inflating_chunk(path: Path, inflated_mb: int, *, passes: int = 1, v73: bool = False) -> Path:
    """A displacement of ten values in one 80-byte chunk, deflated ``passes`` times,
    whose stream inflates to ``inflated_mb`` MB of zeros (``v73``: a MATLAB v7.3 file,
    its datasets ``time_s`` and ``displacement_m`` at the root)."""
    import h5py

    stream = zlib_then_zeros(b"", inflated_mb)
    for _ in range(passes - 1):
        stream = zlib.compress(stream, 9)
    names = ("time_s", "displacement_m") if v73 else ("time", "displacement")
    with h5py.File(path, "w", userblock_size=512 if v73 else 0) as handle:
        group = handle if v73 else handle.create_group("run1")
        _time(group, names[0])
        dsid = _filtered(group, names[1], SAMPLES, ["deflate"] * passes)
        dsid.write_direct_chunk((0,), stream, 0)
        if v73:  # MATLAB states no units: the names carry them
            for name in names:
                del group[name].attrs["units"]
    if v73:
        with open(path, "r+b") as fh:
            fh.write(V73_HEADER)
    return path


def huge_chunk(path: Path, chunk_mb: int) -> Path:
    """A displacement of ten values whose (extendable) dataset is chunked by
    ``chunk_mb`` MB, its one chunk a deflated stream of exactly that many zero bytes."""
    import h5py

    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        _time(group)
        dsid = _filtered(group, "displacement", chunk_mb * MB // 8, ["deflate"], extendable=True)
        dsid.write_direct_chunk((0,), zlib_then_zeros(b"", chunk_mb), 0)
    return path


def scaleoffset_count(path: Path, count: int) -> Path:
    """An integer displacement stored with the scale-offset filter whose parameters
    claim ``count`` values per chunk (its chunk holds 12345)."""
    import h5py

    n = 12345
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        group.create_dataset("time", data=np.arange(n) / 1000.0).attrs["units"] = "s"
        group.create_dataset(
            "displacement", data=np.arange(n, dtype="i4"), chunks=(n,), scaleoffset=0
        ).attrs["units"] = "m"
    data = bytearray(path.read_bytes())
    at = data.index(struct.pack("<I", n), data.index(b"scaleoffset"))
    data[at : at + 4] = struct.pack("<I", count)
    path.write_bytes(bytes(data))
    return path


def vlen_unit_length(path: Path, length: int) -> Path:
    """A run (old-style headers, no checksums) whose ``units`` attributes, variable-length
    strings of one character, state a length of ``length`` bytes."""
    import h5py

    with h5py.File(path, "w", libver="earliest") as handle:
        group = handle.create_group("run1")
        _time(group)
        group.create_dataset("displacement", data=np.zeros(SAMPLES)).attrs["units"] = "m"
    data = bytearray(path.read_bytes())
    heap = struct.pack("<Q", data.index(b"GCOL"))
    # each value: its length (4 bytes), the heap collection's address, its index
    at = data.find(struct.pack("<I", 1) + heap)
    while at >= 0:
        data[at : at + 4] = struct.pack("<I", length)
        at = data.find(struct.pack("<I", 1) + heap, at + 4)
    path.write_bytes(bytes(data))
    return path


def heap_object_size(path: Path) -> Path:
    """A run (old-style headers) whose global heap's first object, a ``units`` value,
    states a size of 2^64 - 1 bytes (libhdf5 loops on it)."""
    import h5py

    with h5py.File(path, "w", libver="earliest") as handle:
        group = handle.create_group("run1")
        _time(group)
        group.create_dataset("displacement", data=np.zeros(SAMPLES)).attrs["units"] = "m"
    data = bytearray(path.read_bytes())
    heap = data.index(b"GCOL")
    # the collection: signature, version, reserved, size (8); each object: index,
    # references, reserved, size (8)
    first = heap + 16
    data[first + 8 : first + 16] = b"\xff" * 8
    path.write_bytes(bytes(data))
    return path
