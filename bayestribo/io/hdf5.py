"""HDF5 files (``.h5``, ``.hdf5``), through h5py (the ``hdf5`` extra).

Every numeric dataset of the file (or of ``group``) is a candidate; a dataset's
``units`` (or ``unit``) attribute states its unit. See :mod:`bayestribo.io.arrays`
for how the signals are picked. The signals are picked from the datasets' names, shapes
and types alone; only the picked datasets are read, each once what it declares fits
the read budget (:mod:`bayestribo.io.budget`); a filtered dataset's chunks are decoded
each within the bytes its chunk shape declares (:mod:`bayestribo.io.hdf5_storage`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.arrays import MAX_SAMPLES, NamedArray, signals_from_arrays
from bayestribo.io.budget import FLOAT_BYTES, ReadBudget, read_budget
from bayestribo.io.hdf5_attributes import FileLayout, checked_attribute
from bayestribo.io.hdf5_storage import read_dataset

__all__ = ["hdf5_signals", "read_hdf5"]

#: Attributes that may hold a dataset's unit.
UNIT_ATTRIBUTES = ("units", "unit", "unit_string", "Units")


def _unit(obj: Any, name: str, layout: FileLayout, where: str) -> str | None:
    """The unit a dataset's attribute states (:data:`UNIT_ATTRIBUTES`), or None."""
    for key in UNIT_ATTRIBUTES:
        if key in obj.attrs:
            value = checked_attribute(obj, key, name, layout, where)
            if isinstance(value, bytes):
                value = value.decode("utf-8", "replace")
            if hasattr(value, "shape") and getattr(value, "shape", ()) != ():
                value = value.ravel()[0] if value.size else ""
                if isinstance(value, bytes):
                    value = value.decode("utf-8", "replace")
            text = str(value).strip()
            return text or None
    return None


def _placeholder(shape: tuple[int, ...], dtype: Any) -> NDArray:
    """An array of a dataset's shape and type that holds no data (every element is one
    zero), for picking the signals by name before any dataset is read."""
    return np.lib.stride_tricks.as_strided(np.zeros(1, dtype), shape, (0,) * len(shape))


def _datasets(h5py: Any, root: Any) -> dict[str, Any]:
    """The numeric datasets (at most 2-D) under ``root``, by path, none of them read."""
    found: dict[str, Any] = {}

    def visit(name: str, obj: object) -> None:
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "iuf" and obj.ndim <= 2:
            found[obj.name.lstrip("/")] = obj

    root.visititems(visit)
    return found


def _reader(
    datasets: Mapping[str, Any], budget: ReadBudget, file_size: int
) -> Callable[[NamedArray], NDArray]:
    """Read a picked dataset once what it declares is checked: where its data are, its
    count of values and, with the datasets read before it, the read budget; its chunks
    are decoded within their declared size (:func:`~bayestribo.io.hdf5_storage.read_dataset`)."""

    def load(item: NamedArray) -> NDArray:
        obj = datasets[item.name]
        full = item.name
        if obj.is_virtual or obj.external:
            raise RunFormatError(
                f"dataset {full!r} keeps its data in other files (an HDF5 "
                f"{'virtual' if obj.is_virtual else 'external'} dataset), which are "
                "not followed; copy the data into the file (h5repack, or write "
                "the dataset again)",
                budget.where,
            )
        if obj.size > MAX_SAMPLES:
            raise RunFormatError(
                f"dataset {full!r} claims {obj.size} values (shape {obj.shape}); "
                f"expected at most {MAX_SAMPLES} samples per channel (a damaged "
                "header, or a record to cut into runs)",
                budget.where,
            )
        budget.claim(
            f"dataset {full!r}",
            int(obj.size) * max(FLOAT_BYTES, obj.dtype.itemsize),
            f"shape {obj.shape}, {obj.dtype}",
        )
        return read_dataset(obj, full, budget, file_size)

    return load


def hdf5_signals(
    path: str | Path,
    *,
    group: str | None,
    channels: Mapping[str, str] | None,
    scale: Mapping[str, float] | None,
    where: str,
    kind: str = "dataset",
) -> dict[str, NDArray]:
    """The signals of a run in an HDF5 file, reading only the datasets picked.

    The datasets are picked by name and unit (:func:`~bayestribo.io.arrays.signals_from_arrays`)
    from what the file declares; each picked dataset is read only once its shape and
    type fit the read budget (:func:`bayestribo.io.budget.read_budget`), so a small
    file that declares a huge dataset is refused before anything is allocated.

    Parameters
    ----------
    path : str or Path
        The file.
    group : str, optional
        Only the datasets under this group.
    channels, scale : mapping, optional
        As for :func:`read_hdf5`.
    where : str
        The file, for messages.
    kind : str
        What the arrays are called in messages.

    Returns
    -------
    dict
        Arrays by canonical column name, in s, m and m/s.

    Raises
    ------
    RunFormatError
        For a file that is not HDF5, a group that does not exist, signals that cannot
        be picked, or datasets past the read budget.
    MissingDependencyError
        When h5py is not installed.
    """
    h5py = require("h5py", "hdf5")
    try:
        size = Path(path).stat().st_size
        handle = h5py.File(path, "r")
    except OSError as exc:
        raise RunFormatError(f"not a readable HDF5 file ({exc})", where) from None
    budget = read_budget(size, where)
    with handle, open(path, "rb") as fh:
        layout = FileLayout.of(handle, fh, size)
        root = handle
        if group is not None:
            if group not in handle or not isinstance(handle[group], h5py.Group):
                groups = sorted(k for k, v in handle.items() if isinstance(v, h5py.Group))
                raise RunFormatError(
                    f"group: no group {group!r} in the file; its groups are {groups}", where
                )
            root = handle[group]
        datasets = _datasets(h5py, root)
        arrays = [
            NamedArray(name, _placeholder(obj.shape, obj.dtype), _unit(obj, name, layout, where))
            for name, obj in datasets.items()
        ]
        return signals_from_arrays(
            arrays,
            channels=channels,
            scale=scale,
            where=where,
            kind=kind,
            load=_reader(datasets, budget, size),
        )


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
    return hdf5_signals(path, group=group, channels=channels, scale=scale, where=where)
