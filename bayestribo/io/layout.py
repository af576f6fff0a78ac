"""How a file is read, described before anything is computed from it.

:func:`describe_file` says which reader a file goes to and what it found there:
the recognised instrument export and its columns with their units, or the header
row of a plain text file, and the sidecar read beside it. ``bayestribo inspect``
prints it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bayestribo.errors import RunFormatError
from bayestribo.io.files import format_of
from bayestribo.io.instruments import PREAMBLE_LINES, detect_export
from bayestribo.io.run import COLUMNS
from bayestribo.io.sidecar import sidecar_path

__all__ = ["describe_file"]

_NAMES = {
    "text": "delimited text",
    "uff": "UFF 58",
    "tdms": "LabVIEW TDMS",
    "mat": "MATLAB .mat",
    "hdf5": "HDF5",
}


def _first_lines(path: Path, count: int) -> list[str]:
    lines = []
    try:
        with path.open("r", encoding="utf-8-sig") as handle:
            for _, line in zip(range(count), handle, strict=False):
                lines.append(line.rstrip("\r\n"))
    except UnicodeDecodeError as exc:
        raise RunFormatError(f"the file is not UTF-8 text ({exc.reason})", str(path)) from None
    return lines


def describe_file(
    path: str | Path, *, file_format: str | None = None, skip_rows: int = 0
) -> dict[str, Any]:
    """Which reader a run file goes to, and the layout it has there.

    Parameters
    ----------
    path : str or Path
        The run file.
    file_format, skip_rows
        As for :func:`bayestribo.read_run`.

    Returns
    -------
    dict
        ``format`` (a key of :data:`bayestribo.io.FORMATS`), ``reader`` (in words),
        ``columns`` (a list of ``{"label", "unit"}`` as the file gives them, for a
        recognised export or a header row; empty otherwise) and ``sidecar`` (the
        path of the JSON sidecar read with the file, or None).

    Raises
    ------
    RunFormatError
        For a file that does not exist or whose format is unknown.
    """
    path = Path(path)
    if not path.is_file():
        raise RunFormatError("no such run file; expected an existing file", str(path))
    kind = format_of(path, file_format)
    out: dict[str, Any] = {"format": kind, "reader": _NAMES[kind], "columns": []}
    if kind == "text":
        lines = _first_lines(path, PREAMBLE_LINES + skip_rows)
        export = detect_export(lines, str(path)) if skip_rows == 0 else None
        if export is not None:
            out["reader"] = f"{export.vendor} export"
            out["columns"] = [
                {"label": label, "unit": unit}
                for i, (label, unit) in enumerate(zip(export.labels, export.units, strict=True))
                if i not in export.ignore
            ]
            if export.implicit_time:
                out["columns"].insert(0, {"label": "time (X0, Delta_X)", "unit": "s"})
        else:
            body = [line for line in lines[skip_rows:] if line.strip() and not line.startswith("#")]
            if body:
                fields = [f.strip().strip('"') for f in body[0].replace(";", ",").split(",")]
                header = any(not _is_number(f) for f in fields if f)
                if header and fields[0] == COLUMNS[0] and set(fields) <= set(COLUMNS):
                    out["reader"] = "canonical CSV"
                    out["columns"] = [{"label": f, "unit": ""} for f in fields]
                elif header:
                    out["reader"] = "delimited text with a header row"
                    out["columns"] = [{"label": f, "unit": ""} for f in fields]
                else:
                    out["reader"] = "delimited text without a header row"
            if skip_rows:
                out["reader"] += f", {skip_rows} line(s) skipped"
    side = sidecar_path(path)
    out["sidecar"] = str(side) if side.is_file() and side != path else None
    return out


def _is_number(text: str) -> bool:
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return True
