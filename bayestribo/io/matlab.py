"""MATLAB ``.mat`` files: version 4 to 7 through :func:`scipy.io.loadmat`, version 7.3
(HDF5) through h5py.

Variables are found by name, also inside structures (``data.t``, ``data.x``); see
:mod:`bayestribo.io.arrays` for how the signals are picked and their units.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.arrays import MAX_SAMPLES, NamedArray, signals_from_arrays
from bayestribo.io.budget import FLOAT_BYTES, ReadBudget, read_budget
from bayestribo.io.hdf5 import hdf5_signals
from bayestribo.io.mat_headers import DamagedHeader, declared_bytes, v5_variables

__all__ = ["read_mat"]


def _flatten(prefix: str, value: Any, out: list[NamedArray], depth: int = 0) -> None:
    if isinstance(value, Mapping):
        if depth > 8:
            return
        for key, item in value.items():
            _flatten(f"{prefix}.{key}" if prefix else str(key), item, out, depth + 1)
    elif isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        out.append(NamedArray(prefix, value))
    elif isinstance(value, int | float) and not isinstance(value, bool):
        out.append(NamedArray(prefix, np.asarray(value)))


def _check_sizes(path: Path, where: str, names: list[str] | None) -> None:
    """Refuse a variable to be loaded (``names``, or all) whose header claims more than
    :data:`MAX_SAMPLES` values, from the headers alone (:func:`scipy.io.whosmat`)
    before any data is read. A file whose headers cannot be read is left to
    ``loadmat``, which names what is wrong."""
    import scipy.io

    try:
        variables = scipy.io.whosmat(path)
    except Exception:  # not a v4-v7 file (v7.3 is HDF5), or damaged: loadmat says which
        return
    for name, shape, kind in variables:
        if names is not None and name not in names:
            continue  # not loaded
        count = int(np.prod(shape, dtype=np.float64)) if len(shape) else 1
        if count > MAX_SAMPLES:
            raise RunFormatError(
                f"variable {name!r} ({kind}) claims {count} values (shape {tuple(shape)}); "
                f"expected at most {MAX_SAMPLES} samples per channel (a damaged header, or "
                "a record to cut into runs)",
                where,
            )


def _budgeted_variables(
    path: Path, channels: Mapping[str, str] | None, where: str
) -> list[str] | None:
    """The variables to load, checked against the read budget from their headers.

    With ``channels`` naming top-level variables (or fields of them, ``data.x``), only
    those are loaded; otherwise every variable is. What they declare is added up before
    any is decompressed (:mod:`bayestribo.io.mat_headers`) and refused past the budget
    (:func:`bayestribo.io.budget.read_budget`).

    Returns
    -------
    list of str or None
        The names for ``loadmat(variable_names=...)``; None for all of them.
    """
    try:
        size = path.stat().st_size
        fh = open(path, "rb")
    except OSError as exc:
        raise RunFormatError(f"not a readable MATLAB .mat file ({exc})", where) from None
    budget = read_budget(size, where)
    with fh:
        try:
            variables = list(v5_variables(fh))
        except DamagedHeader as exc:
            raise RunFormatError(f"not a readable MATLAB .mat file ({exc})", where) from None
        if not variables:  # version 4 (uncompressed: the file bounds it) or 7.3 (HDF5)
            _check_v4_budget(path, budget)
            return None
        names = [v.name for v in variables]
        wanted: set[str] | None = None
        if isinstance(channels, Mapping):
            tops = {str(source).split(".", 1)[0] for source in channels.values()}
            if tops <= set(names):
                wanted = tops
        for variable in variables:
            if wanted is not None and variable.name not in wanted:
                continue
            ceiling = budget.limit - budget.used
            try:
                declared, complete = declared_bytes(fh, variable, ceiling)
            except DamagedHeader as exc:
                raise RunFormatError(
                    f"variable {variable.name!r}: not a readable MATLAB array ({exc})", where
                ) from None
            budget.claim(
                f"variable {variable.name!r}",
                declared,
                f"{variable.nbytes} bytes in the file",
                at_least=not complete,
            )
    return None if wanted is None else sorted(wanted)


def _check_v4_budget(path: Path, budget: ReadBudget) -> None:
    import scipy.io

    try:
        variables = scipy.io.whosmat(path)
    except Exception:  # v7.3 (HDF5, read with its own budget), or damaged: loadmat says
        return
    for name, shape, kind in variables:
        count = int(np.prod(shape, dtype=np.float64)) if len(shape) else 1
        budget.claim(f"variable {name!r}", count * FLOAT_BYTES, f"{kind}, shape {tuple(shape)}")


def read_mat(
    path: str | Path,
    *,
    channels: Mapping[str, str] | None = None,
    scale: Mapping[str, float] | None = None,
) -> dict[str, NDArray]:
    """Read the signals of a run from a MATLAB file.

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file.
    channels : mapping, optional
        Column name -> variable name (``"data.x"`` inside a structure), e.g.
        ``{"time_s": "t", "displacement_um": "x"}``. Without it, variables named
        ``time_s``, ``displacement_m``, ``velocity_m_per_s`` or with a unit
        (``displacement_um``) are used.
    scale : mapping, optional
        Extra factor per canonical column.

    Returns
    -------
    dict
        Arrays by canonical column name, in s, m and m/s.

    Raises
    ------
    RunFormatError
        For a file that is not a MATLAB file, signals that cannot be picked, or
        variables that declare more memory than the read budget
        (:func:`bayestribo.io.budget.read_budget`; only the variables ``channels``
        names are loaded and counted).
    """
    import scipy.io  # on first use: the acquisition logger reads no MATLAB files

    path = Path(path)
    where = str(path)
    names = _budgeted_variables(path, channels, where)
    _check_sizes(path, where, names)
    try:
        content = scipy.io.loadmat(path, simplify_cells=True, variable_names=names)
    except NotImplementedError:
        # Version 7.3 files are HDF5 files; MATLAB stores vectors as 1 x n or n x 1.
        return hdf5_signals(
            path, group=None, channels=channels, scale=scale, where=where, kind="variable"
        )
    except (ValueError, TypeError, OSError, IndexError, KeyError) as exc:
        # scipy raises MatReadError (a ValueError) for most bad files, IndexError for
        # some short ones.
        raise RunFormatError(f"not a readable MATLAB .mat file ({exc})", where) from None
    arrays: list[NamedArray] = []
    for key, value in content.items():
        if not key.startswith("__"):
            _flatten(key, value, arrays)
    return signals_from_arrays(arrays, channels=channels, scale=scale, where=where)
