"""What an HDF5 dataset's stored chunks decode to, checked before libhdf5 decodes them.

libhdf5 sizes nothing it decompresses: its deflate filter doubles its output buffer
until the stream ends, whatever the chunk's declared size. A chunk of ten values whose
stream inflates to a gigabyte (a few kB when deflated twice) is decoded whole, inside
the C library, before h5py returns, so no check of the dataset's shape or type can
bound it. The chunks of a filtered dataset are therefore read raw here
(``H5Dread_chunk``, no filter applied) and their filters undone in Python with an
output limit: each chunk must decode to exactly the bytes its chunk shape declares, or
the dataset is refused, naming the chunk and what it decodes to. Only then does
libhdf5 read the dataset (and verify its checksums); what it decompresses is then
known to be no larger than the chunk it fills.

Only the filters whose output can be bounded this way are accepted: deflate (gzip),
shuffle and the Fletcher-32 checksum, what h5py's ``compression="gzip"`` and MATLAB
v7.3 files use. A dataset with another filter (szip, n-bit, scale-offset, LZF, a
plugin) is refused by name: their decoders size their output from the filter's stored
parameters or from the stream. ``h5repack -f GZIP=4 in.h5 out.h5`` rewrites such a file.
"""

from __future__ import annotations

import itertools
import math
import zlib
from typing import Any

from bayestribo.errors import RunFormatError
from bayestribo.io.budget import ReadBudget, _mb

__all__ = ["BOUNDED_FILTERS", "check_storage"]

#: HDF5 filter identifiers whose decoded size is checked here, by name.
BOUNDED_FILTERS = {1: "deflate", 2: "shuffle", 3: "fletcher32"}
#: Bytes the Fletcher-32 filter appends to a chunk [bytes].
FLETCHER_BYTES = 4
#: Filter identifiers of deflate and Fletcher-32 (the two that change a chunk's size).
_DEFLATE, _FLETCHER = 1, 3


def _filters(dcpl: Any) -> list[tuple[int, str]]:
    """The dataset's filter pipeline, in the order it was applied when writing."""
    out = []
    for k in range(dcpl.get_nfilters()):
        code, _flags, _values, name = dcpl.get_filter(k)
        out.append(
            (int(code), name.decode("ascii", "replace") if isinstance(name, bytes) else str(name))
        )
    return out


def _decoded_size(raw: bytes, pipeline: list[int], mask: int, chunk_bytes: int) -> int:
    """The bytes ``raw`` decodes to through ``pipeline`` (filter ids in writing order,
    those whose bit is set in ``mask`` skipped), each inflation stopped one byte past
    what the chunk can hold at that stage; -1 when a stream inflates past it.

    Raises
    ------
    zlib.error
        For a stream that is not deflate data.
    """
    applied = [code for k, code in enumerate(pipeline) if not mask & (1 << k)]
    # the size each stage writes, in writing order: a checksum adds its four bytes
    sizes = [chunk_bytes]
    for code in applied:
        sizes.append(sizes[-1] + (FLETCHER_BYTES if code == _FLETCHER else 0))
    data = raw
    for k in reversed(range(len(applied))):
        code, limit = applied[k], sizes[k]
        if code == _FLETCHER:
            data = data[:-FLETCHER_BYTES]
        elif code == _DEFLATE:
            stream = zlib.decompressobj()
            data = stream.decompress(data, limit + 1)
            if len(data) > limit:
                return -1
    return len(data)


def check_storage(dataset: Any, name: str, budget: ReadBudget, file_size: int) -> None:
    """Refuse a dataset whose chunks would make libhdf5 allocate past what it declares.

    Checked from the dataset's storage alone, before it is read: its chunk (at most the
    read budget), its filters (only :data:`BOUNDED_FILTERS`) and, for a filtered
    dataset, every stored chunk (at most the file's size raw, decoding to exactly its
    chunk's bytes). An unfiltered dataset is read by libhdf5 straight into its array.

    Parameters
    ----------
    dataset : h5py.Dataset
        The dataset, open.
    name : str
        Its path in the file, for messages.
    budget : ReadBudget
        The file's read budget (:func:`bayestribo.io.budget.read_budget`).
    file_size : int
        The file's size [bytes].

    Raises
    ------
    RunFormatError
        Naming the dataset, the chunk and the size it declares or decodes to.
    """
    chunks = dataset.chunks
    if chunks is None:  # contiguous or compact: read straight into the array
        return
    where = budget.where
    chunk_bytes = math.prod(chunks) * dataset.dtype.itemsize
    if chunk_bytes > budget.limit:
        raise RunFormatError(
            f"dataset {name!r}: its chunks (shape {chunks}, {dataset.dtype}) declare "
            f"{_mb(chunk_bytes)} each, more than the read budget of {_mb(budget.limit)} "
            f"({budget.rule}); a damaged header",
            where,
        )
    dsid = dataset.id
    filters = _filters(dsid.get_create_plist())
    if not filters:
        return
    other = [
        f"{label or 'unnamed'} (filter {code})"
        for code, label in filters
        if code not in BOUNDED_FILTERS
    ]
    if other:
        raise RunFormatError(
            f"dataset {name!r} is stored with the filter {', '.join(other)}, whose decoded "
            f"size cannot be checked before it is decoded; expected only "
            f"{', '.join(BOUNDED_FILTERS.values())} (rewrite the file with "
            "'h5repack -f GZIP=4 in.h5 out.h5')",
            where,
        )
    pipeline = [code for code, _ in filters]
    shape = dataset.shape
    counts = [math.ceil(n / c) for n, c in zip(shape, chunks, strict=True)]
    for index in itertools.product(*(range(n) for n in counts)):
        offset = tuple(i * c for i, c in zip(index, chunks, strict=True))
        info = dsid.get_chunk_info_by_coord(offset)
        if info.byte_offset is None:  # not stored: libhdf5 fills it in the array
            continue
        if info.size > file_size:
            raise RunFormatError(
                f"dataset {name!r}: its chunk at {offset} is stored as {_mb(info.size)}, "
                f"more than the file's {_mb(file_size)}; a damaged chunk index",
                where,
            )
        mask, raw = dsid.read_direct_chunk(offset)
        try:
            size = _decoded_size(bytes(raw), pipeline, mask, chunk_bytes)
        except zlib.error as exc:
            raise RunFormatError(
                f"dataset {name!r}: its chunk at {offset} is not readable deflate data ({exc})",
                where,
            ) from None
        if size != chunk_bytes:
            decoded = f"more than {_mb(chunk_bytes)}" if size < 0 else _mb(size)
            raise RunFormatError(
                f"dataset {name!r}: its chunk at {offset} ({_mb(info.size)} stored, "
                f"filters {', '.join(label for _, label in filters)}) decodes to "
                f"{decoded}; expected the {_mb(chunk_bytes)} of its chunk shape "
                f"{chunks} ({dataset.dtype}), a damaged or hostile chunk",
                where,
            )
