"""HDF5 files (``.h5``, ``.hdf5``), through h5py (the ``hdf5`` extra).

Every numeric dataset of the file (or of ``group``) is a candidate; a dataset's
``units`` (or ``unit``) attribute states its unit. See :mod:`bayestribo.io.arrays`
for how the signals are picked.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.arrays import NamedArray, signals_from_arrays

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
