"""Reading a filtered HDF5 dataset chunk by chunk, each decoded within its declared size.

libhdf5 sizes nothing it decompresses: its deflate filter doubles its output buffer
until the stream ends, whatever the chunk's declared size. A chunk of ten values whose
stream inflates to a gigabyte (a few kB when deflated twice) is decoded whole, inside
the C library, before h5py returns, so no check of the dataset's shape or type can
bound it. The chunks of a filtered dataset are therefore read raw here
(``H5Dread_chunk``, no filter applied) and their filters undone in Python with an
output limit: each chunk must decode to exactly the bytes its chunk shape declares, or
the dataset is refused, naming the chunk and what it decodes to. The decoded chunks
are the dataset's values (a Fletcher-32 checksum verified as libhdf5 verifies it);
a dataset stored in a type other than the numpy type h5py reads it as (an n-bit
integer, a custom float) is read by libhdf5 once every chunk is known to decode within
its size.

Only the filters whose output can be bounded this way are accepted: deflate (gzip),
shuffle, the Fletcher-32 checksum and LZF, what h5py's ``compression="gzip"`` and
``compression="lzf"`` and MATLAB v7.3 files use (LZF is decoded here as liblzf's
``lzf_decompress`` does, stopping at the chunk's bytes). A dataset with another filter
(szip, n-bit, scale-offset, a plugin) is refused by name: their decoders size their
output from the filter's stored parameters or from the stream.
``h5repack -f GZIP=4 in.h5 out.h5`` rewrites such a file.
"""

from __future__ import annotations

import itertools
import math
import zlib
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.budget import ReadBudget, _mb

__all__ = ["BOUNDED_FILTERS", "read_dataset"]

#: HDF5 filter identifiers whose decoded size is checked here, by name.
BOUNDED_FILTERS = {1: "deflate", 2: "shuffle", 3: "fletcher32", 32000: "lzf"}
#: Bytes the Fletcher-32 filter appends to a chunk [bytes].
FLETCHER_BYTES = 4
_DEFLATE, _SHUFFLE, _FLETCHER, _LZF = 1, 2, 3, 32000
#: Fletcher-32's sums are kept modulo this [-].
_FLETCHER_MODULUS = 65535


class _Refused(Exception):
    """A chunk that does not decode to its declared bytes; the message says why."""


def _filters(dcpl: Any) -> list[tuple[int, tuple[int, ...], str]]:
    """The dataset's filter pipeline, in the order it was applied when writing: each
    filter's identifier, parameters and name."""
    out = []
    for k in range(dcpl.get_nfilters()):
        code, _flags, values, name = dcpl.get_filter(k)
        label = name.decode("ascii", "replace") if isinstance(name, bytes) else str(name)
        out.append((int(code), tuple(int(v) for v in values), label))
    return out


def _fletcher32(data: bytes) -> tuple[int, int]:
    """HDF5's Fletcher-32 sums of ``data`` (big-endian 16-bit words, an odd last byte
    as the high byte of a word), each modulo 65535."""
    words = np.frombuffer(data, ">u2", len(data) // 2).astype(np.uint64)
    if len(data) % 2:
        words = np.append(words, np.uint64(data[-1] << 8))
    n = words.size
    low = int(words.sum() % _FLETCHER_MODULUS)
    weights = (n - np.arange(n, dtype=np.uint64)) % _FLETCHER_MODULUS
    high = int((words * weights).sum() % _FLETCHER_MODULUS)
    return low, high


def _checksum_matches(data: bytes, stored: bytes) -> bool:
    """Whether ``stored`` is the Fletcher-32 checksum of ``data``, in the byte order
    HDF5 writes it or the one its versions 1.6.0-1.6.2 wrote (which libhdf5 accepts)."""
    low, high = _fletcher32(data)
    for value in (int.from_bytes(stored, "little"), int.from_bytes(stored, "big")):
        if (value & 0xFFFF) % _FLETCHER_MODULUS == low and (
            value >> 16
        ) % _FLETCHER_MODULUS == high:
            return True
    return False


def _unlzf(data: bytes, limit: int) -> bytes:
    """Undo LZF (liblzf's format: a control byte below 32 starts a run of that many
    plus one literal bytes; above, a back reference of length ``ctrl >> 5`` (+ a byte
    when 7) + 2 at an offset of 13 bits), stopping as soon as the output would exceed
    ``limit`` bytes.

    Raises
    ------
    _Refused
        For output past ``limit`` or a stream that is not LZF data (a run past its end,
        a reference before the start of the output).
    """
    out = bytearray()
    ip, n = 0, len(data)
    while ip < n:
        ctrl = data[ip]
        ip += 1
        if ctrl < 32:
            run = ctrl + 1
            if ip + run > n:
                raise _Refused("is not readable LZF data (a literal run past its end)")
            if len(out) + run > limit:
                raise _Refused(f"decodes to more than {_mb(limit)}")
            out += data[ip : ip + run]
            ip += run
            continue
        length = ctrl >> 5
        if ip >= n:
            raise _Refused("is not readable LZF data (a reference past its end)")
        if length == 7:
            length += data[ip]
            ip += 1
            if ip >= n:
                raise _Refused("is not readable LZF data (a reference past its end)")
        start = len(out) - ((ctrl & 0x1F) << 8) - 1 - data[ip]
        ip += 1
        length += 2
        if start < 0:
            raise _Refused("is not readable LZF data (a reference before its start)")
        if len(out) + length > limit:
            raise _Refused(f"decodes to more than {_mb(limit)}")
        while length > 0:  # the reference may overlap what it writes: copy by spans
            span = min(length, len(out) - start)
            out += out[start : start + span]
            start += span
            length -= span
    return bytes(out)


def _unshuffle(data: bytes, size: int) -> bytes:
    """Undo HDF5's shuffle filter of elements of ``size`` bytes (as libhdf5 does,
    nothing for elements of one byte or fewer, or for one element)."""
    if size <= 1 or len(data) // size <= 1:
        return data
    n = len(data) // size
    head = np.frombuffer(data, np.uint8, n * size).reshape(size, n).T.tobytes()
    return head + data[n * size :]


def _decode(
    raw: bytes, pipeline: list[tuple[int, tuple[int, ...], str]], mask: int, chunk_bytes: int
) -> bytes:
    """Undo ``pipeline`` (in writing order; a filter whose bit is set in ``mask`` was
    not applied), each inflation stopped one byte past what the chunk can hold at that
    stage.

    Raises
    ------
    _Refused
        For a stream that inflates past its stage's size, deflate data that are not,
        a checksum that does not match, or a chunk that decodes to other than
        ``chunk_bytes``.
    """
    applied = [f for k, f in enumerate(pipeline) if not mask & (1 << k)]
    # the bytes each filter was given when writing: a checksum adds its four bytes
    sizes = [chunk_bytes]
    for code, _, _ in applied:
        sizes.append(sizes[-1] + (FLETCHER_BYTES if code == _FLETCHER else 0))
    data = raw
    for k in reversed(range(len(applied))):
        code, values, _ = applied[k]
        if code == _FLETCHER:
            if len(data) < FLETCHER_BYTES or not _checksum_matches(
                data[:-FLETCHER_BYTES], data[-FLETCHER_BYTES:]
            ):
                raise _Refused("fails its Fletcher-32 checksum (damaged data)")
            data = data[:-FLETCHER_BYTES]
        elif code == _DEFLATE:
            try:
                data = zlib.decompressobj().decompress(data, sizes[k] + 1)
            except zlib.error as exc:
                raise _Refused(f"is not readable deflate data ({exc})") from None
            if len(data) > sizes[k]:
                raise _Refused(f"decodes to more than {_mb(sizes[k])}")
        elif code == _LZF:
            data = _unlzf(data, sizes[k])
        elif code == _SHUFFLE:
            data = _unshuffle(data, values[0] if values else 1)
    if len(data) != chunk_bytes:
        raise _Refused(f"decodes to {_mb(len(data))}")
    return data


def _stored_chunks(
    dsid: Any, chunks: tuple[int, ...], shape: tuple[int, ...], name: str, where: str
) -> list[Any]:
    """The chunks of a dataset that are stored (h5py ``StoreInfo``: offset in the
    dataset, filter mask, address, size), each at a chunk's place within its shape.

    Raises
    ------
    RunFormatError
        For an index listing more chunks than the shape holds, or one out of place.
    """
    counts = [math.ceil(n / c) for n, c in zip(shape, chunks, strict=True)]
    total = math.prod(counts)
    found: list[Any] = []
    try:  # one pass over the index (HDF5 1.10.10, 1.12.3, 1.14 or later)
        dsid.chunk_iter(lambda info: found.append(info) or (len(found) > total or None))
    except (AttributeError, NotImplementedError):  # one look-up per chunk of the shape
        found = []
        for index in itertools.product(*(range(n) for n in counts)):
            offset = tuple(i * c for i, c in zip(index, chunks, strict=True))
            info = dsid.get_chunk_info_by_coord(offset)
            if info.byte_offset is not None:  # else never written: the fill value
                found.append(info)
    if len(found) > total:
        raise RunFormatError(
            f"dataset {name!r}: its chunk index lists more than the {total} chunks its "
            f"shape {shape} holds in chunks of {chunks}; a damaged chunk index",
            where,
        )
    for info in found:
        offset = info.chunk_offset
        if offset is None or any(
            o % c or not 0 <= o < n for o, c, n in zip(offset, chunks, shape, strict=True)
        ):
            raise RunFormatError(
                f"dataset {name!r}: its chunk index places a chunk at {offset}, not at a "
                f"multiple of its chunk shape {chunks} within its shape {shape}; a damaged "
                "chunk index",
                where,
            )
    return found


def _read_as_stored(dataset: Any) -> bool:
    """Whether the dataset's stored type is, byte for byte, the numpy type h5py reads
    it as (so its decoded chunks are its values)."""
    import h5py

    try:
        return bool(dataset.id.get_type().equal(h5py.h5t.py_create(dataset.dtype)))
    except (TypeError, ValueError):
        return False


def read_dataset(dataset: Any, name: str, budget: ReadBudget, file_size: int) -> NDArray:
    """A dataset's values, read without libhdf5 decoding more than it declares.

    An unfiltered dataset is read by libhdf5 straight into its array, once its chunk
    (if chunked) is within the read budget. A filtered one is read chunk by chunk raw,
    each stored chunk (at most the file's size) decoded here within its chunk's bytes
    (:data:`BOUNDED_FILTERS` only); chunks never written hold the fill value, as
    libhdf5 gives them.

    Parameters
    ----------
    dataset : h5py.Dataset
        The dataset, open; its shape and type already checked against the read budget.
    name : str
        Its path in the file, for messages.
    budget : ReadBudget
        The file's read budget (:func:`bayestribo.io.budget.read_budget`).
    file_size : int
        The file's size [bytes].

    Returns
    -------
    numpy.ndarray
        The values, of the dataset's shape and numpy type, as ``dataset[()]`` reads them.

    Raises
    ------
    RunFormatError
        Naming the dataset, the chunk and the size it declares or decodes to, or the
        filter that cannot be bounded.
    """
    chunks = dataset.chunks
    if chunks is None:  # contiguous or compact: read straight into the array
        return dataset[()]
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
    pipeline = _filters(dsid.get_create_plist())
    if not pipeline:
        return dataset[()]
    other = [
        f"{label or 'unnamed'} (filter {code})"
        for code, _, label in pipeline
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
    shape = dataset.shape
    stored = _stored_chunks(dsid, chunks, shape, name, where)
    out = None
    if _read_as_stored(dataset):
        whole = len(stored) == math.prod(
            math.ceil(n / c) for n, c in zip(shape, chunks, strict=True)
        )
        # the fill value only where a chunk was never written (a damaged fill value
        # message can crash libhdf5 when it is asked for it)
        out = (
            np.empty(shape, dataset.dtype)
            if whole
            else np.full(shape, dataset.fillvalue, dataset.dtype)
        )
    for info in stored:
        offset = info.chunk_offset
        if info.size > file_size:
            raise RunFormatError(
                f"dataset {name!r}: its chunk at {offset} is stored as {_mb(info.size)}, "
                f"more than the file's {_mb(file_size)}; a damaged chunk index",
                where,
            )
        mask, raw = dsid.read_direct_chunk(offset)
        try:
            data = _decode(bytes(raw), pipeline, mask, chunk_bytes)
        except _Refused as exc:
            raise RunFormatError(
                f"dataset {name!r}: its chunk at {offset} ({_mb(info.size)} stored, "
                f"filters {', '.join(label for _, _, label in pipeline)}) {exc}; expected "
                f"the {_mb(chunk_bytes)} of its chunk shape {chunks} ({dataset.dtype}), a "
                "damaged or hostile chunk",
                where,
            ) from None
        if out is not None:
            block = tuple(
                slice(o, min(o + c, n)) for o, c, n in zip(offset, chunks, shape, strict=True)
            )
            values = np.frombuffer(data, dataset.dtype).reshape(chunks)
            out[block] = values[tuple(slice(0, b.stop - b.start) for b in block)]
    return out if out is not None else dataset[()]
