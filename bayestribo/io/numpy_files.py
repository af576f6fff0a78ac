"""NumPy files: ``.npz`` archives of named arrays, ``.npy`` single arrays.

An ``.npz`` archive (``np.savez(path, t=t, x=x)``) holds arrays by name, read as a
MATLAB file's variables are (:mod:`bayestribo.io.arrays`): names that carry a unit
(``time_s``, ``displacement_mm``, ``velocity_m_per_s``) are found, others are named
with ``channels={"time_s": "t", "displacement_m": "x"}``. An ``.npy`` file holds one
array without names: its columns (a 2-D array of samples in rows, or one vector) are
named in order with ``columns=[...]``, as a text file's are.

Files are read with ``np.load(..., allow_pickle=False)``: an array of Python objects
(pickled) is refused by name and never unpickled; an archive's other arrays are read
as usual. Each array's shape and type are read from its header first, so that one that
claims more samples than :data:`~bayestribo.io.arrays.MAX_SAMPLES`, or more memory
than the read budget (:mod:`bayestribo.io.budget`: a compressed archive can claim
gigabytes), is refused before it is read; only the arrays picked are read.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.arrays import MAX_SAMPLES, NamedArray, signals_from_arrays
from bayestribo.io.budget import FLOAT_BYTES, ReadBudget, read_budget
from bayestribo.io.columns import IGNORE, parse_column
from bayestribo.io.run import ACCELERATIONS, ANGULAR, DISPLACEMENT, TIME, VELOCITY

__all__ = ["ArrayHeader", "describe_numpy", "read_numpy"]

_NPY = b"\x93NUMPY"
_ZIP = (b"PK\x03\x04", b"PK\x05\x06")
_PICKLE = b"\x80"  # a pickle of protocol 2 or later
#: Column roles that carry the motion (any one makes a run, with the time or a rate).
_MOTION = (DISPLACEMENT, VELOCITY, *ANGULAR, *ACCELERATIONS)


@dataclass(frozen=True)
class ArrayHeader:
    """An array's shape and type, from its ``.npy`` header, its data not read.

    Attributes
    ----------
    shape : tuple of int
        The array's shape.
    dtype : numpy.dtype
        Its type (``object`` for pickled Python objects).
    """

    shape: tuple[int, ...]
    dtype: np.dtype

    @property
    def size(self) -> int:
        """Number of elements."""
        return int(np.prod(self.shape, dtype=np.float64)) if self.shape else 1

    def describe(self) -> str:
        """``1000x3 float64`` for messages."""
        return f"{'x'.join(map(str, self.shape)) or 'scalar'} {self.dtype}"


def _header(fh: BinaryIO, what: str, where: str) -> ArrayHeader:
    """The header of the ``.npy`` data at the position of ``fh``."""
    try:
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise ValueError(f"format version {version} (expected 1.0 or 2.0)")
    except ValueError as exc:
        raise RunFormatError(f"{what}: not a readable NumPy array header ({exc})", where) from None
    return ArrayHeader(tuple(int(n) for n in shape), np.dtype(dtype))


def _refuse_objects(header: ArrayHeader, what: str, where: str) -> None:
    """Refuse an array of Python objects (or a structured one) before it is read."""
    if header.dtype.hasobject:
        raise RunFormatError(
            f"{what} ({header.describe()}) holds Python objects, which would be unpickled "
            "and are never loaded (allow_pickle=False); save the samples as numeric "
            "arrays, e.g. np.savez(path, time_s=t, displacement_m=x)",
            where,
        )
    if header.dtype.names is not None:
        raise RunFormatError(
            f"{what} ({header.describe()}) is a structured array (fields "
            f"{list(header.dtype.names)}); save each field as an array of an .npz archive, "
            "np.savez(path, **{name: a[name] for name in a.dtype.names})",
            where,
        )


def _check_size(header: ArrayHeader, budget: ReadBudget, what: str) -> None:
    """Refuse an array past :data:`MAX_SAMPLES` per channel or past the read budget."""
    columns = header.shape[1] if len(header.shape) == 2 else 1
    if header.size > MAX_SAMPLES * max(columns, 1):
        raise RunFormatError(
            f"{what} claims {header.size} values (shape {header.shape}); expected at most "
            f"{MAX_SAMPLES} samples per channel (a damaged header, or a record to cut "
            "into runs)",
            budget.where,
        )
    budget.claim(
        what,
        header.size * max(FLOAT_BYTES, header.dtype.itemsize),
        f"shape {header.shape}, {header.dtype}",
    )


def _placeholder(header: ArrayHeader) -> NDArray:
    """An array of the header's shape and type that holds no data, for picking by name."""
    dtype = header.dtype if not header.dtype.hasobject else np.dtype(np.float64)
    shape = header.shape
    return np.lib.stride_tricks.as_strided(np.zeros(1, dtype), shape, (0,) * len(shape))


def _open(path: Path, where: str) -> tuple[bytes, int]:
    """The first bytes of the file and its size, a file that is no NumPy file refused."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError as exc:
        raise RunFormatError(f"not a readable NumPy file ({exc})", where) from None
    if size == 0:
        raise RunFormatError(
            "the file is empty (0 bytes); expected a NumPy .npz archive or .npy array", where
        )
    if head.startswith(_NPY) or head.startswith(_ZIP):
        return head, size
    if head.startswith(_PICKLE):
        raise RunFormatError(
            "the file is a Python pickle, which is never loaded; save the samples with "
            "np.savez(path, time_s=t, displacement_m=x)",
            where,
        )
    raise RunFormatError(
        f"not a NumPy file: it starts with {head!r}, expected an .npz archive (a zip "
        "file, 'PK') or an .npy array ('\\x93NUMPY')",
        where,
    )


def _archive_headers(archive: Any, where: str) -> dict[str, ArrayHeader]:
    """The header of each array of an open ``.npz`` archive, by name (none read)."""
    headers: dict[str, ArrayHeader] = {}
    for member in archive.zip.namelist():
        if member.endswith(".npy"):  # np.savez names each array NAME.npy
            with archive.zip.open(member) as fh:
                headers[member[:-4]] = _header(fh, f"array {member[:-4]!r}", where)
    return headers


def _npz_signals(
    path: Path,
    size: int,
    channels: Mapping[str, Any] | None,
    scale: Mapping[str, float] | None,
    where: str,
) -> dict[str, NDArray]:
    """The signals of an ``.npz`` archive, only the picked arrays read."""
    budget = read_budget(size, where)
    try:
        archive = np.load(path, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise RunFormatError(f"not a readable NumPy .npz archive ({exc})", where) from None
    with archive:
        headers = _archive_headers(archive, where)
        if not headers:
            raise RunFormatError(
                "the .npz archive holds no arrays; expected the samples as named arrays, "
                "e.g. np.savez(path, time_s=t, displacement_m=x)",
                where,
            )

        def load(item: NamedArray) -> NDArray:
            header = headers[item.name]
            what = f"array {item.name!r}"
            _refuse_objects(header, what, where)
            _check_size(header, budget, what)
            return archive[item.name]

        arrays = [NamedArray(name, _placeholder(h)) for name, h in headers.items()]
        return signals_from_arrays(
            arrays, channels=channels, scale=scale, where=where, kind="array", load=load
        )


def _suggested_columns(count: int) -> list[str]:
    """Column names to show for an array of ``count`` columns."""
    names = [TIME, DISPLACEMENT, VELOCITY][: max(count, 1)] if count > 1 else [DISPLACEMENT]
    return names + [IGNORE] * (count - len(names))


def _column_roles(columns: Sequence[str], count: int, header: ArrayHeader, where: str) -> None:
    """Refuse ``columns`` that do not name the array's columns, naming the argument."""
    example = _suggested_columns(count)
    if len(columns) != count:
        raise RunFormatError(
            f"columns: {len(columns)} name(s) given for an array of {count} column(s) "
            f"({header.describe()}); expected one per column, e.g. columns={example}",
            where,
        )
    roles = []
    for index, name in enumerate(columns):
        if name == IGNORE:
            continue
        try:
            parsed = parse_column(str(name))
        except ValueError as exc:
            raise RunFormatError(f"columns[{index}]: {exc}", where) from None
        if parsed is None:
            raise RunFormatError(
                f"columns[{index}]: unknown column {name!r}; expected a quantity with its "
                "unit (time_s, displacement_mm, velocity_m_per_s, ...) or 'ignore'",
                where,
            )
        if parsed[0] in roles:
            raise RunFormatError(f"columns: {parsed[0]} is named twice", where)
        roles.append(parsed[0])
    if not set(roles) & set(_MOTION):
        raise RunFormatError(
            f"columns: no displacement, velocity, angle or acceleration among {list(columns)}; "
            f"expected one, e.g. columns={example}",
            where,
        )


def _npy_signals(
    path: Path,
    size: int,
    columns: Sequence[str] | None,
    scale: Mapping[str, float] | None,
    where: str,
) -> dict[str, NDArray]:
    """The signals of an ``.npy`` array, its columns named by ``columns``."""
    with open(path, "rb") as fh:
        header = _header(fh, "the array", where)
    _refuse_objects(header, "the array", where)
    if len(header.shape) not in (1, 2) or header.dtype.kind not in "iuf":
        raise RunFormatError(
            f"the array ({header.describe()}): expected real numbers, one vector or a 2-D "
            "array of samples in rows and signals in columns",
            where,
        )
    count = header.shape[1] if len(header.shape) == 2 else 1
    if columns is None:
        raise RunFormatError(
            f"an .npy file holds one array without names ({header.describe()}): name its "
            f"{count} column(s) in order, e.g. columns={_suggested_columns(count)} (a unit "
            "in the name, displacement_mm; 'ignore' leaves a column out), or save named "
            "arrays in an .npz archive, np.savez(path, time_s=t, displacement_m=x)",
            where,
        )
    _column_roles(columns, count, header, where)
    _check_size(header, read_budget(size, where), "the array")
    cache: dict[str, NDArray] = {}

    def load(item: NamedArray) -> NDArray:
        if "array" not in cache:
            cache["array"] = np.load(path, allow_pickle=False)
        values = cache["array"]
        return values[:, int(item.name)] if values.ndim == 2 else values

    column = _placeholder(ArrayHeader(header.shape[:1], header.dtype))
    arrays = [NamedArray(str(k), column) for k in range(count)]
    chosen = {str(name): str(k) for k, name in enumerate(columns) if name != IGNORE}
    return signals_from_arrays(
        arrays, channels=chosen, scale=scale, where=where, kind="column", load=load
    )


def read_numpy(
    path: str | Path,
    *,
    channels: Mapping[str, Any] | None = None,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
) -> dict[str, NDArray]:
    """Read the signals of a run from a NumPy ``.npz`` archive or ``.npy`` array.

    Which of the two the file is comes from its first bytes (a zip archive or an
    ``.npy`` header), not from its suffix.

    Parameters
    ----------
    path : str or Path
        The file.
    channels : mapping, optional
        ``.npz``: column name -> array name, e.g. ``{"time_s": "t", "displacement_mm":
        "x"}``. Without it, arrays named ``time_s``, ``displacement_m``,
        ``velocity_m_per_s`` or with a unit (``displacement_um``) are used.
    columns : sequence of str, optional
        ``.npy``: one name per column of the array in order (a canonical name, a
        quantity with its unit such as ``displacement_mm``, or ``"ignore"``); one name
        for a vector. Required: the array names nothing.
    scale : mapping, optional
        Extra factor per canonical column.

    Returns
    -------
    dict
        Arrays by canonical column name, in s, m and m/s.

    Raises
    ------
    RunFormatError
        For an empty file, a file that is neither, a pickle or an array of Python
        objects picked (never unpickled), ``columns`` given for an ``.npz`` or
        ``channels`` for an ``.npy``, an ``.npy`` without ``columns``, signals that
        cannot be picked, or arrays past the sample limit or read budget.
    """
    path = Path(path)
    where = str(path)
    head, size = _open(path, where)
    if head.startswith(_NPY):
        if channels is not None:
            raise RunFormatError(
                "channels: an .npy file holds one array without names; name its columns "
                "in order with columns=[...] instead",
                where,
            )
        return _npy_signals(path, size, columns, scale, where)
    if columns is not None:
        raise RunFormatError(
            "columns: an .npz archive names its arrays; pick them with channels={...} "
            "(column name -> array name) instead",
            where,
        )
    return _npz_signals(path, size, channels, scale, where)


def describe_numpy(path: str | Path) -> dict[str, Any]:
    """How a NumPy file is read, from its headers: ``{"reader", "columns"}`` for ``inspect``.

    Parameters
    ----------
    path : str or Path
        The ``.npz`` or ``.npy`` file.

    Returns
    -------
    dict
        ``reader``: the kind of file (and an ``.npy`` array's shape and type);
        ``columns``: an ``.npz`` archive's arrays as ``{"label": name, "unit": None}``.
    """
    path = Path(path)
    where = str(path)
    head, _ = _open(path, where)
    if head.startswith(_NPY):
        with open(path, "rb") as fh:
            header = _header(fh, "the array", where)
        return {"reader": f"NumPy .npy array ({header.describe()})", "columns": []}
    with np.load(path, allow_pickle=False) as archive:
        headers = _archive_headers(archive, where)
    listing = ", ".join(f"{name} ({h.describe()})" for name, h in headers.items())
    return {
        "reader": f"NumPy .npz archive of {len(headers)} array(s): {listing}",
        "columns": [{"label": name, "unit": None} for name in headers],
    }
