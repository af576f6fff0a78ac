"""HDF5 files (``.h5``, ``.hdf5``), through h5py (the ``hdf5`` extra).

Every numeric dataset of the file (or of ``group``) is a candidate; a dataset's
``units`` (or ``unit``) attribute states its unit. See :mod:`bayestribo.io.arrays`
for how the signals are picked.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.arrays import MAX_SAMPLES, NamedArray, signals_from_arrays

__all__ = ["hdf5_arrays", "read_hdf5"]

#: Attributes that may hold a dataset's unit.
UNIT_ATTRIBUTES = ("units", "unit", "unit_string", "Units")


def _unit(attrs: Mapping) -> str | None:
    for key in UNIT_ATTRIBUTES:
        if key in attrs:
            value = attrs[key]
            if isinstance(value, bytes):
                value = value.decode("utf-8", "replace")
            if hasattr(value, "shape") and getattr(value, "shape", ()) != ():
                value = value.ravel()[0] if value.size else ""
                if isinstance(value, bytes):
                    value = value.decode("utf-8", "replace")
            text = str(value).strip()
            return text or None
    return None


#: Most address space an HDF5 read may add to the process [bytes]: a channel of
#: :data:`~bayestribo.io.arrays.MAX_SAMPLES` float64 values is 160 MB.
READ_ADDRESS_SPACE = 1 << 30


@contextlib.contextmanager
def _bounded_address_space(extra: int) -> Iterator[None]:
    """Limit the process's address space to its present size plus ``extra`` while the
    HDF5 library reads a file, and restore the limit after.

    The HDF5 C library takes the sizes a file states on trust: a damaged global heap
    made it allocate and fill 4 GB before failing on one file of 4400 mutants
    (``benchmarks/fuzz.py``). Under the limit that allocation fails at once and the
    library reports an error, which the reader turns into the package's error. Where
    the limit cannot be read or set (not Linux), nothing is limited.
    """
    try:
        import resource

        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        with open("/proc/self/statm") as fh:
            size = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (ImportError, OSError, ValueError):
        yield
        return
    limit = size + extra
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    if soft != resource.RLIM_INFINITY and soft <= limit:
        yield
        return
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def hdf5_arrays(path: str | Path, *, group: str | None, where: str) -> list[NamedArray]:
    """The numeric datasets of an HDF5 file (or of one group), with their units.

    Parameters
    ----------
    path : str or Path
        The file.
    group : str, optional
        Only the datasets under this group.
    where : str
        The file, for messages.

    Returns
    -------
    list of NamedArray
        Datasets by full path (without the leading ``/``).

    Raises
    ------
    RunFormatError
        For a file that is not HDF5 or a group that does not exist.
    MissingDependencyError
        When h5py is not installed.
    """
    h5py = require("h5py", "hdf5")
    with _bounded_address_space(READ_ADDRESS_SPACE):
        return _arrays(h5py, path, group, where)


def _arrays(h5py: Any, path: str | Path, group: str | None, where: str) -> list[NamedArray]:
    try:
        handle = h5py.File(path, "r")
    except OSError as exc:
        raise RunFormatError(f"not a readable HDF5 file ({exc})", where) from None
    arrays: list[NamedArray] = []
    with handle:
        root = handle
        if group is not None:
            if group not in handle or not isinstance(handle[group], h5py.Group):
                groups = sorted(k for k, v in handle.items() if isinstance(v, h5py.Group))
                raise RunFormatError(
                    f"group: no group {group!r} in the file; its groups are {groups}", where
                )
            root = handle[group]

        def visit(name: str, obj: object) -> None:
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "iuf" and obj.ndim <= 2:
                full = obj.name.lstrip("/")
                # what the dataset claims, checked before its data are read
                if obj.is_virtual or obj.external:
                    raise RunFormatError(
                        f"dataset {full!r} keeps its data in other files (an HDF5 "
                        f"{'virtual' if obj.is_virtual else 'external'} dataset), which are "
                        "not followed; copy the data into the file (h5repack, or write "
                        "the dataset again)",
                        where,
                    )
                if obj.size > MAX_SAMPLES:
                    raise RunFormatError(
                        f"dataset {full!r} claims {obj.size} values (shape {obj.shape}); "
                        f"expected at most {MAX_SAMPLES} samples per channel (a damaged "
                        "header, or a record to cut into runs)",
                        where,
                    )
                arrays.append(NamedArray(full, obj[()], _unit(obj.attrs)))

        root.visititems(visit)
    return arrays


def read_hdf5(
    path: str | Path,
    *,
    channels: Mapping[str, str] | None = None,
    group: str | None = None,
    scale: Mapping[str, float] | None = None,
) -> dict[str, NDArray]:
    """Read the signals of a run from an HDF5 file.

    Parameters
    ----------
    path : str or Path
        The ``.h5``/``.hdf5`` file.
    channels : mapping, optional
        Column name -> dataset path or name, e.g. ``{"time_s": "t", "displacement_m":
        "run1/x"}``. Without it, datasets named ``time_s``, ``displacement_m``,
        ``velocity_m_per_s``, with a unit in the name (``displacement_um``) or named
        ``time``/``displacement``/``velocity`` with a ``units`` attribute are used.
    group : str, optional
        Only the datasets under this group.
    scale : mapping, optional
        Extra factor per canonical column.

    Returns
    -------
    dict
        Arrays by canonical column name, in s, m and m/s.

    Raises
    ------
    RunFormatError
        For a file that is not HDF5, or signals that cannot be picked.
    """
    where = str(path)
    arrays = hdf5_arrays(path, group=group, where=where)
    return signals_from_arrays(arrays, channels=channels, scale=scale, where=where, kind="dataset")
