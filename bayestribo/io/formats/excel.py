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
import shlex
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.budget import ReadBudget, read_budget
from bayestribo.io.options import ReadOptions
from bayestribo.io.registry import FileFormat
from bayestribo.io.text import parse_lines

__all__ = ["FORMAT", "read_xlsx"]

#: Memory a cell takes on its way to the text parser, as text and then as a number
#: [bytes]: a worksheet of two columns of numbers reads in about 200 bytes a cell
#: (peak resident memory over the number of cells), rounded up.
CELL_BYTES = 256
#: Read budget per byte of a workbook [-] (:func:`~bayestribo.io.budget.read_budget`):
#: its cells take about 35 times the file's size through the parser (13 bytes a row of
#: two numbers in the file); 48 leaves room for wider rows.
PER_FILE_BYTE = 48

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


def _lines(rows: Iterable[tuple[Any, ...]], budget: ReadBudget | None = None) -> list[str]:
    """Rows as tab-separated lines, each as wide as the widest row: a column left empty
    in its last rows (a derived channel) reads as empty cells, as in a CSV export.

    With ``budget``, the cells are counted as they come (:data:`CELL_BYTES` each) and
    refused past it: a workbook compressed from repeated cells declares nothing of its
    size until its rows are read.
    """
    lines: list[str] = []
    fields: list[int] = []
    width = cells = 0
    for i, row in enumerate(rows):
        cells += len(row)
        if budget is not None and cells * CELL_BYTES > budget.limit:
            budget.claim(
                "the worksheet", cells * CELL_BYTES, f"{cells} cells to row {i + 1}", at_least=True
            )
        n = len(row)
        while n and row[n - 1] is None:
            n -= 1
        width = max(width, n)
        lines.append("\t".join(_cell(c) for c in row[:n]))
        fields.append(n)
    return [line + "\t" * (width - n) if n else "" for line, n in zip(lines, fields, strict=True)]


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
        # a date and time is a sample's time stamp (read as seconds from the first)
        numbers = sum(
            isinstance(c, int | float | datetime.datetime | datetime.time)
            and not isinstance(c, bool)
            for c in row
        )
        if numbers >= 2:
            return True
        alone += numbers == 1 and sum(c is not None for c in row) == 1
        if alone >= _COLUMN_ROWS:
            return True
    return False


def _check_parts(path: Path, where: str) -> None:
    """Refuse a workbook whose parts declare more uncompressed bytes than its read budget
    (:func:`~bayestribo.io.budget.read_budget`), from the zip directory alone: openpyxl
    holds the shared strings in memory and parses every worksheet it is asked for.
    A file that is not a zip is left to :func:`_open`, which names what is wrong."""
    try:
        with zipfile.ZipFile(path) as archive:
            parts = archive.infolist()
    except (zipfile.BadZipFile, OSError, EOFError, ValueError):
        return
    declared = sum(part.file_size for part in parts)
    budget = read_budget(path.stat().st_size, where)
    largest = max(parts, key=lambda part: part.file_size, default=None)
    detail = f"largest part {largest.filename!r}" if largest is not None else ""
    budget.claim(f"the workbook's {len(parts)} parts", declared, detail)


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
        "that holds the run: "
        + " or ".join(f"`--sheet {shlex.quote(str(name))}`" for name in data),
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
    _check_parts(path, where)
    book = _open(path)
    try:
        ws = _sheet(book, sheet, where)
        title = ws.title
        budget = read_budget(path.stat().st_size, where, per_file_byte=PER_FILE_BYTE)
        lines = _lines(ws.iter_rows(values_only=True), budget)
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
    _check_parts(path, str(path))
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
