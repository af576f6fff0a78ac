"""Excel workbooks (``.xlsx``, ``.xlsm``): one worksheet of samples in columns.

A worksheet is read as a delimited text is (:func:`bayestribo.io.text.parse_lines`):
a header row naming the columns with their units (``Time (s)``, ``Displacement [µm]``)
or ``columns=[...]``, rows of numbers below, rows to skip at the top with
``skip_rows``. Numbers are taken as stored (float64, no decimal rounding); a cell
holding a formula gives the value Excel saved with it. A workbook with several
worksheets of numbers needs ``sheet=`` (a name, or the position from 0): it is never
guessed. Reading is streamed (openpyxl's read-only mode), so memory stays near the size
of the samples.

Old binary ``.xls`` workbooks are not read: the error says to save as ``.xlsx`` or CSV.
"""

from __future__ import annotations

import datetime
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.text import parse_lines

__all__ = ["FORMAT", "read_xlsx"]

#: Rows looked at to tell a worksheet of samples from a sheet of notes or a chart.
_PROBE_ROWS = 50


def _cell(value: Any) -> str:
    """A cell as text that the text parser reads back to the same float64."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value)  # not a number: refused by the parser, naming the cell
    if isinstance(value, int | float):
        return repr(float(value))
    if isinstance(value, datetime.datetime | datetime.date | datetime.time):
        return value.isoformat()
    return " ".join(str(value).split())  # no tab or line break inside a field


def _lines(rows: Iterable[tuple[Any, ...]]) -> list[str]:
    """Rows as tab-separated lines, each as wide as the widest row: a column left empty
    in its last rows (a derived channel) reads as empty cells, as in a CSV export."""
    cells = []
    width = 0
    for row in rows:
        kept = list(row)
        while kept and kept[-1] is None:
            kept.pop()
        width = max(width, len(kept))
        cells.append([_cell(c) for c in kept])
    return ["\t".join(row + [""] * (width - len(row))) if row else "" for row in cells]


#: Rows of numbers alone that make a worksheet of one column a sheet of samples (a
#: column of displacements read with its sample rate), not a sheet of notes.
_COLUMN_ROWS = 10


def _has_numbers(sheet: Any) -> bool:
    """A worksheet of samples: a row of two numbers or more among its first rows, or
    :data:`_COLUMN_ROWS` rows that hold a number and nothing else."""
    alone = 0
    for i, row in enumerate(sheet.iter_rows(values_only=True)):
        if i >= _PROBE_ROWS:
            break
        numbers = sum(isinstance(c, int | float) and not isinstance(c, bool) for c in row)
        if numbers >= 2:
            return True
        alone += numbers == 1 and sum(c is not None for c in row) == 1
        if alone >= _COLUMN_ROWS:
            return True
    return False


def _open(path: Path) -> Any:
    openpyxl = require("openpyxl", "reading Excel files")
    where = str(path)
    try:
        return openpyxl.load_workbook(path, read_only=True, data_only=True)
    except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError) as exc:
        raise RunFormatError(
            f"not a readable Excel .xlsx workbook ({type(exc).__name__}: {exc}); save it "
            "again from Excel, or export the sheet as CSV",
            where,
        ) from None
    except Exception as exc:  # openpyxl's InvalidFileException and XML parser errors
        raise RunFormatError(
            f"not a readable Excel .xlsx workbook ({type(exc).__name__}: {exc})", where
        ) from None


def _sheet(book: Any, sheet: str | int | None, where: str) -> Any:
    names = list(book.sheetnames)
    if isinstance(sheet, bool) or (sheet is not None and not isinstance(sheet, str | int)):
        raise RunFormatError(
            f"sheet: expected a worksheet name or position, got {sheet!r}; the sheets are {names}",
            where,
        )
    if isinstance(sheet, int):
        if not 0 <= sheet < len(names):
            raise RunFormatError(
                f"sheet: position {sheet} is not in 0..{len(names) - 1}; the sheets are {names}",
                where,
            )
        return book[names[sheet]]
    if isinstance(sheet, str):
        if sheet not in names:
            raise RunFormatError(f"sheet: no worksheet {sheet!r}; the sheets are {names}", where)
        return book[sheet]
    data = [name for name in names if _has_numbers(book[name])]
    if len(data) == 1:
        return book[data[0]]
    if not data:
        raise RunFormatError(
            f"no worksheet holds columns of numbers (sheets {names}); the samples should be "
            "in columns below a header row",
            where,
        )
    raise RunFormatError(
        f"several worksheets hold numbers ({data}); give sheet= (--sheet) with the one "
        "that holds the run",
        where,
    )


def read_xlsx(
    path: str | Path,
    *,
    sheet: str | int | None = None,
    columns: Any = None,
    scale: Any = None,
    skip_rows: int = 0,
) -> dict[str, NDArray]:
    """Read the samples of one worksheet of an Excel workbook.

    Parameters
    ----------
    path : str or Path
        The ``.xlsx`` or ``.xlsm`` file.
    sheet : str or int, optional
        The worksheet, by name or position from 0; needed when several hold numbers.
    columns, scale, skip_rows
        As for delimited text (:func:`bayestribo.io.text.read_text`); rows count as
        lines.

    Returns
    -------
    dict
        Arrays by canonical column name (time first).

    Raises
    ------
    RunFormatError
        For a file that is not a workbook, a sheet that is not there or not given
        among several, or cells that are not numbers (naming the row and column).
    MissingDependencyError
        Without openpyxl (``pip install 'bayestribo[formats]'``).
    """
    path = Path(path)
    where = str(path)
    book = _open(path)
    try:
        ws = _sheet(book, sheet, where)
        title = ws.title
        lines = _lines(ws.iter_rows(values_only=True))
    finally:
        book.close()
    return parse_lines(
        lines,
        f"{where}, sheet {title!r} (a line is a row)",
        columns=columns,
        scale=scale,
        delimiter="\t",
        skip_rows=skip_rows,
    )


def _read(path: Path, options: ReadOptions) -> dict[str, NDArray]:
    return read_xlsx(
        path,
        sheet=options.sheet,
        columns=options.columns,
        scale=options.scale,
        skip_rows=options.skip_rows,
    )


def _describe(path: Path, options: ReadOptions) -> dict[str, Any]:
    book = _open(path)
    try:
        ws = _sheet(book, options.sheet, str(path))
        head = []
        for i, row in enumerate(ws.iter_rows(values_only=True)):
            if i >= options.skip_rows + _PROBE_ROWS:
                break
            if i >= options.skip_rows and any(c is not None for c in row):
                head = [_cell(c) for c in row]
                break
        title = ws.title
    finally:
        book.close()
    out: dict[str, Any] = {"reader": f"Excel worksheet {title!r}", "columns": []}
    numbers = sum(_is_number(c) for c in head)
    if head and numbers < len([c for c in head if c]):
        out["reader"] += " with a header row"
        out["columns"] = [{"label": c, "unit": ""} for c in head if c]
    else:
        out["reader"] += " without a header row"
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


FORMAT = FileFormat.builtin("xlsx", _read, describe=_describe)
