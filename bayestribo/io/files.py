"""One entry to read a run from any supported file, and one to write it.

``read_run(path, metadata={...})`` picks the reader from the file suffix (or
``file_format=``), reads the JSON sidecar beside the file when there is one, lets
the given metadata fill or override it, builds a :class:`~bayestribo.io.run.Run` and
checks it with :func:`~bayestribo.io.validation.validate_run`. ``write_run`` writes
the canonical CSV and its sidecar, which read back identically. ``as_run`` is the one
place where "a run or a file" becomes a :class:`~bayestribo.io.run.Run`.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io.hdf5 import read_hdf5
from bayestribo.io.matlab import read_mat
from bayestribo.io.run import DISPLACEMENT, TIME, VELOCITY, Run
from bayestribo.io.sidecar import read_sidecar, sidecar_path, write_sidecar
from bayestribo.io.tdms import read_tdms
from bayestribo.io.text import read_text, write_csv
from bayestribo.io.uff import read_uff
from bayestribo.io.validation import validate_run

__all__ = ["FORMATS", "READ_OPTIONS", "as_run", "format_of", "read_run", "write_run"]

#: File formats and their suffixes.
FORMATS: Mapping[str, tuple[str, ...]] = {
    "text": (".csv", ".txt", ".dat", ".tsv", ".asc", ".prn", ".lvm"),
    "uff": (".uff", ".unv", ".uf", ".58"),
    "tdms": (".tdms",),
    "mat": (".mat",),
    "hdf5": (".h5", ".hdf5", ".hdf", ".he5"),
}

_OPTIONS = {
    "columns": ("text",),
    "delimiter": ("text",),
    "decimal": ("text",),
    "skip_rows": ("text",),
    "encoding": ("text",),
    "group": ("tdms", "hdf5"),
    "channels": ("uff", "tdms", "mat", "hdf5"),
}


def format_of(path: str | Path, file_format: str | None = None) -> str:
    """The format a file is read as: ``file_format`` if given, else from its suffix.

    Raises
    ------
    RunFormatError
        For an unknown format or suffix, listing the known ones.
    """
    path = Path(path)
    if file_format is not None:
        if file_format not in FORMATS:
            raise RunFormatError(
                f"file_format: expected one of {sorted(FORMATS)}, got {file_format!r}", str(path)
            )
        return file_format
    suffix = path.suffix.lower()
    for name, suffixes in FORMATS.items():
        if suffix in suffixes:
            return name
    raise RunFormatError(
        f"unknown file type {suffix!r}; expected one of "
        f"{sorted(s for v in FORMATS.values() for s in v)}, or give file_format=",
        str(path),
    )


def read_run(
    path: str | Path,
    *,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
    delimiter: str | None = None,
    decimal: str = ".",
    skip_rows: int = 0,
    encoding: str | None = None,
    group: str | None = None,
    channels: Mapping[str, Any] | None = None,
    file_format: str | None = None,
    sidecar: bool | str | Path = True,
    validate: bool = True,
    metadata: Mapping[str, Any] | None = None,
    **unexpected: Any,
) -> Run:
    """Read one run from a file.

    Parameters
    ----------
    path : str or Path
        Canonical CSV, other delimited text (``.csv .txt .dat .tsv .asc .prn``), the
        text exports of oscilloscopes and DAQ software recognised by their preamble
        (Tektronix, Keysight/Agilent, Rigol, PicoScope CSV and LabVIEW ``.lvm``, see
        :mod:`bayestribo.io.instruments`), UFF 58/58b (``.uff .unv .uf .58``), TDMS
        (``.tdms``), MATLAB (``.mat``, v4 to v7.3) or HDF5 (``.h5 .hdf5``, the
        ``hdf5`` extra).
    columns : list of str, optional
        Text files: one canonical name (``time_s``, ``displacement_m``,
        ``velocity_m_per_s``) or ``"ignore"`` per column, in file order. Needed when
        the file has no canonical header row.
    scale : mapping, optional
        Factor per canonical name converting the file's unit to s, m or m/s, e.g.
        ``{"displacement_m": 1e-3}`` for millimetres.
    delimiter, decimal, skip_rows
        Text files: column separator (default: guessed), decimal mark, lines to skip.
    encoding : str, optional
        Text files: the text encoding (``"cp1252"``, ``"latin-1"``, ...). Default UTF-8,
        and a file that is not UTF-8 is read as Windows-1252 (µ as the byte 0xB5, the
        8-bit encoding of most lab software) with a
        :class:`~bayestribo.errors.ReadingWarning` saying so.
    group : str, optional
        TDMS, HDF5: the group holding the channels.
    channels : mapping, optional
        TDMS: channel name per canonical name (required). UFF: record index per
        canonical name (when the records' types are ambiguous). MATLAB, HDF5:
        variable or dataset name per column name (a key may carry a unit,
        ``"displacement_um"``), when the names are not canonical.
    file_format : {"text", "uff", "tdms", "mat", "hdf5"}, optional
        Overrides the choice by suffix.
    sidecar : bool or path
        Read the JSON sidecar with the file's stem if it exists (``True``), do not
        (``False``), or read this sidecar file (which must exist).
    validate : bool
        Run the data checks of :func:`~bayestribo.io.validation.validate_run`.
    metadata : mapping, optional
        Metadata that fill or override the sidecar's, e.g.
        ``{"load_N": 0.31, "length_unit": "arbitrary"}``.

    Returns
    -------
    Run
        With ``source`` set to the path.

    Raises
    ------
    RunFormatError
        For a file or sidecar that cannot be read as its format, naming the file, line
        or field and what was expected.
    BayestriboError
        For a keyword argument that is not an option (a misspelt ``delimeter=``, or a
        metadata key given as a keyword instead of in ``metadata=``).
    RecordingError
        For data that fail the checks (NaN, irregular time, clipping, units...).
        A missing file or sidecar is a ``RunFormatError`` too, so that one ``except``
        of the package's errors covers every bad input.

    Examples
    --------
    A two-column text file of time [s] and position in an unknown unit:

    >>> run = read_run("HarmOsc1.txt", columns=["time_s", "displacement_m"],
    ...                metadata={"length_unit": "arbitrary"})  # doctest: +SKIP
    """
    if unexpected:
        raise _unexpected_options(unexpected)
    path = Path(path)
    where = str(path)
    if not path.is_file():
        raise RunFormatError("no such run file; expected an existing file", where)
    kind = format_of(path, file_format)
    given = {
        "columns": columns,
        "delimiter": delimiter,
        "decimal": None if decimal == "." else decimal,
        "skip_rows": skip_rows or None,
        "encoding": encoding,
        "group": group,
        "channels": channels,
    }
    for option, value in given.items():
        if value is not None and kind not in _OPTIONS[option]:
            raise RunFormatError(
                f"option {option!r} applies to {' and '.join(_OPTIONS[option])} files, not to "
                f"a {kind} file",
                where,
            )
    if kind == "text":
        signals = read_text(
            path,
            columns=columns,
            scale=scale,
            delimiter=delimiter,
            decimal=decimal,
            skip_rows=skip_rows,
            encoding=encoding,
        )
    elif kind == "uff":
        signals = read_uff(path, channels=channels, scale=scale)
    elif kind == "mat":
        signals = read_mat(path, channels=channels, scale=scale)
    elif kind == "hdf5":
        signals = read_hdf5(path, channels=channels, group=group, scale=scale)
    else:
        signals = read_tdms(path, channels=channels, group=group, scale=scale)

    meta: dict[str, Any] = {}
    if sidecar is True:
        side = sidecar_path(path)
        if side.is_file() and side != path:
            meta.update(read_sidecar(side))
    elif sidecar is not False:
        side = Path(sidecar)
        if not side.is_file():
            raise RunFormatError("no such sidecar file; expected an existing file", str(side))
        meta.update(read_sidecar(side))
    meta.update(metadata or {})
    run = Run(
        signals[TIME],
        signals.get(DISPLACEMENT),
        signals.get(VELOCITY),
        meta,
        source=where,
    )
    if validate:
        validate_run(run)
    return run


#: Keyword options of :func:`read_run` (and of :func:`as_run` given a path).
READ_OPTIONS = (
    "columns",
    "scale",
    "delimiter",
    "decimal",
    "skip_rows",
    "encoding",
    "group",
    "channels",
    "file_format",
    "sidecar",
    "validate",
    "metadata",
)


def _unexpected_options(unexpected: Mapping[str, Any]) -> BayestriboError:
    """The error for keyword arguments that are not reading options."""
    from bayestribo.io.run import METADATA_KEYS

    parts = []
    for name in sorted(unexpected):
        close = difflib.get_close_matches(name, READ_OPTIONS, n=1)
        if close:
            parts.append(f"{name!r} (did you mean {close[0]!r}?)")
        elif name in METADATA_KEYS:
            parts.append(f"{name!r} (a metadata key: pass metadata={{{name!r}: ...}})")
        else:
            parts.append(f"{name!r}")
    return BayestriboError(
        f"unknown reading option(s) {', '.join(parts)}; the options are {', '.join(READ_OPTIONS)}"
    )


def as_run(run: Run | str | os.PathLike[str], **read_options: Any) -> Run:
    """The one conversion of "a run or a file" into a :class:`~bayestribo.io.run.Run`.

    Parameters
    ----------
    run : Run, str or path-like
        A run, returned as it is, or a file read with :func:`read_run`.
    **read_options
        Options of :func:`read_run` (:data:`READ_OPTIONS`), for a file only.

    Returns
    -------
    Run

    Raises
    ------
    BayestriboError
        If ``run`` is neither a Run nor a path, if reading options are given with a
        Run (they would be ignored), or if an option is unknown.
    """
    if isinstance(run, Run):
        if read_options:
            raise BayestriboError(
                f"reading options {sorted(read_options)} apply to a file, but run is "
                "already a Run; read the file with these options, or drop them"
            )
        return run
    if isinstance(run, str | os.PathLike):
        return read_run(run, **read_options)
    raise BayestriboError(
        f"run: expected a bayestribo Run or the path of a run file, got {type(run).__name__}"
    )


def write_run(run: Run, path: str | Path) -> Path:
    """Write a run in the canonical format: ``path`` (CSV) and its JSON sidecar.

    Parameters
    ----------
    run : Run
        The run to write (its ``source`` is not written).
    path : str or Path
        The ``.csv`` file; the sidecar is the same path with suffix ``.json``.

    Returns
    -------
    Path
        The CSV path. ``read_run(path)`` gives a run equal to ``run``.

    Raises
    ------
    RunFormatError
        If the path does not end in ``.csv``.
    """
    path = Path(path)
    if path.suffix.lower() != ".csv":
        raise RunFormatError(
            f"the canonical run file is a .csv file; got suffix {path.suffix!r}", str(path)
        )
    write_csv(run.signals, path)
    write_sidecar(run.metadata, sidecar_path(path))
    return path
