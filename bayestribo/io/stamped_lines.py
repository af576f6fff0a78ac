"""A text file's column of time stamps, read as seconds from its first sample.

A header naming a column ``Timestamp``, ``Time stamp``, ``Date Time``, ``DateTime``,
``Date/Time`` or ``Time``, or two columns ``Date`` and ``Time``, over cells that are
dates and times or times of day (:mod:`bayestribo.io.timestamps`), is such a column.
:func:`stamped_lines` finds it in a text's first lines and writes the file's lines
anew with that column as ``time_us``, microseconds from the first sample (integers,
which read alike with a decimal point or comma): the text reader then reads them as any
other file, with every check of its rows. The absolute time of the first sample is kept
(:attr:`Stamped.start`) for the run's metadata (``start_time``). Beside a time column of
the file's own (``Time (s)``), the stamps are not read as the time (``ignore``); the
first one is kept all the same.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.columns import IGNORE, parse_column
from bayestribo.io.instruments import PREAMBLE_LINES
from bayestribo.io.run import TIME
from bayestribo.io.timestamps import STAMP_CELL, StampError, parse_stamps

__all__ = ["STAMP_COLUMN", "STAMP_NAMES", "START_TIME", "Stamped", "stamped_lines"]

#: Header names of a column of time stamps (lower case, single blanks, quotes and a
#: bracketed note such as ``(UTC)`` left out).
STAMP_NAMES = frozenset(
    {
        "timestamp",
        "time stamp",
        "time_stamp",
        "datetime",
        "date time",
        "date_time",
        "date-time",
        "date/time",
        "date & time",
        "date and time",
        "time",
    }
)
#: The name the column is written under: integers of microseconds from the first stamp.
STAMP_COLUMN = "time_us"
#: The key of the first sample's date and time (ISO 8601 text), beside the columns
#: :func:`bayestribo.io.text.read_text` returns and in a run's metadata.
START_TIME = "start_time"

_DATE_TOKEN = re.compile(r"\d{4}[-/]\d{1,2}[-/]\d{1,2}|\d{1,2}[-/.]\d{1,2}[-/.]\d{4}")
_BRACKET = re.compile(r"\s*[\(\[][^\)\]]*[\)\]]\s*$")


@dataclass(frozen=True)
class Stamped:
    """A text's lines with its time stamps as microseconds from the first.

    Attributes
    ----------
    lines : list of (int, str)
        The lines (numbered as the file numbers them), the stamps' header name(s) and
        cells replaced by :data:`STAMP_COLUMN` and integers.
    start : str
        The first sample's date and time, ISO 8601.
    label : str
        The header's name of the column (``Date`` + ``Time``: both).
    delimiter : str or None
        The file's column separator (None: blanks).
    cell, cells : int
        The index of the stamps' first field in a row of the file, and the number of
        its fields (two: a date and a time of day).
    midnight : bool
        Whether a time of day passed midnight (said with a warning).
    """

    lines: list[tuple[int, str]]
    start: str
    label: str
    delimiter: str | None = None
    cell: int = 0
    cells: int = 1
    midnight: bool = False


def _name(field: str) -> str:
    text = field.strip().strip('"').strip("'").strip()
    return " ".join(_BRACKET.sub("", text).lower().split())


def _split(line: str, delimiter: str | None) -> list[str]:
    return line.split(delimiter) if delimiter is not None else line.split()


@dataclass(frozen=True)
class _Column:
    """Where the stamps are: the header line's index and the fields it takes (``at``,
    ``names``), and in the rows (``cell``, ``cells``: two for a date and a time)."""

    delimiter: str | None
    header: int
    at: int
    names: int
    cell: int
    cells: int


def _in_header(names: list[str]) -> tuple[int, int] | None:
    """(index, count) of the stamp column's name(s) among a header's fields."""
    low = [_name(n) for n in names]
    for i, name in enumerate(low):
        following = low[i + 1] if i + 1 < len(low) else ""
        if (name, following) in (("date", "time"), ("time", "stamp")):
            return i, 2
        if name in STAMP_NAMES:
            return i, 1
    return None


def _in_row(fields: list[str], at: int, blanks: bool) -> tuple[int, int] | None:
    """(index, count) of the stamp cell(s) of a row: a date and time (or a time of day)
    at ``at``, or a date at ``at`` and a time of day after it (two columns, or one cell
    that blanks split); with blanks, the first field that is a date or a time."""
    places = range(len(fields)) if blanks else [at]
    for j in places:
        cell = fields[j].strip().strip('"') if j < len(fields) else ""
        if j + 1 < len(fields) and _DATE_TOKEN.fullmatch(cell):
            both = f"{cell} {fields[j + 1].strip().strip(chr(34))}"
            if STAMP_CELL.fullmatch(both):
                return j, 2
        if STAMP_CELL.fullmatch(cell):
            return j, 1
        if blanks and (_DATE_TOKEN.fullmatch(cell) or ":" in cell):
            return None
    return None


def _find(lines: Sequence[tuple[int, str]], delimiter: str | None) -> _Column | None:
    """The stamp column of a text's first lines, or None."""
    head = lines[: PREAMBLE_LINES + 1]
    if not any(":" in line for _, line in head):
        return None  # no time of day: a file of numbers (no cost to it)
    choices = (delimiter,) if delimiter is not None else (",", ";", "\t", None)
    for d in choices:
        for h in range(len(head) - 1):
            names = _split(head[h][1], d)
            found = _in_header(names)
            if found is None:
                continue
            at, count = found
            row = _split(head[h + 1][1], d)
            if d is not None and len(row) != len(names):
                continue
            cell = _in_row(row, at, d is None)
            if cell is None:
                continue
            if d is not None and cell[1] != count:
                continue  # Date and Time over a single cell, or the reverse
            return _Column(d, h, at, count, *cell)
    return None


def _a_time(names: Sequence[str]) -> bool:
    """True when one of a header's other names (or two neighbours, split by blanks) is
    a time column in seconds or another unit (``time_s``, ``Time (s)``)."""
    pairs = [f"{a} {b}" for a, b in pairwise(names)]
    for name in (*names, *pairs):
        try:
            parsed = parse_column(name.strip().strip('"'))
        except ValueError:
            continue
        if parsed is not None and parsed[0] == TIME:
            return True
    return False


def _header_line(line: str, column: _Column) -> tuple[str, str]:
    """The header line with the stamp column's name(s) replaced, and the name(s): by
    :data:`STAMP_COLUMN`, or by ``ignore`` beside a time column of the file's own."""
    d = column.delimiter
    fields = line.split(d)
    stamps = slice(column.at, column.at + column.names)
    name = IGNORE if _a_time(fields[: stamps.start] + fields[stamps.stop :]) else STAMP_COLUMN
    if d is not None:
        label = " ".join(f.strip().strip('"') for f in fields[stamps])
        fields[stamps] = [name]
        return d.join(fields), label
    spans = [m.span() for m in re.finditer(r"\S+", line)]
    start, end = spans[stamps.start][0], spans[stamps.stop - 1][1]
    return line[:start] + name + line[end:], line[start:end]


def stamped_lines(
    lines: Sequence[tuple[int, str]], delimiter: str | None, where: str
) -> Stamped | None:
    """A text's lines with its column of time stamps as microseconds from the first.

    Parameters
    ----------
    lines : sequence of (int, str)
        The text's numbered lines (blank and comment lines left out).
    delimiter : str or None
        The column separator when it is given; None to find it.
    where : str
        The file, for messages.

    Returns
    -------
    Stamped or None
        None when the text has no such column (its lines are read as they are).

    Raises
    ------
    RunFormatError
        Naming the line, the column and the cell: a cell that is no date and time (or
        of another form than the first), a row with another number of fields, dates
        that read day first and month first, a zone on some cells only.
    """
    column = _find(lines, delimiter)
    if column is None:
        return None
    header, label = _header_line(lines[column.header][1], column)
    rows = lines[column.header + 1 :]
    d = column.delimiter
    j, k = column.cell, column.cells
    cut = j + k  # the fields split off each row: those before the stamps, and the stamps
    if len(rows) > 1 and len(_split(rows[-1][1], d)) < len(_split(rows[0][1], d)):
        number, line = rows[-1]
        warn(
            f"{where}: the last line (line {number}) is incomplete: {line[:80]!r}; it is "
            "left out of the run",
            ReadingWarning,
        )
        rows = rows[:-1]
    # the rest of each row stays as written: the text reader reads and checks it
    split = [line.split(d, cut) for _, line in rows]
    if min(map(len, split)) < cut:
        i = next(i for i, f in enumerate(split) if len(f) < cut)
        number, line = rows[i]
        raise RunFormatError(
            f"line {number}, column {label!r}: no time stamp in {line[:80]!r}", where
        )
    cells = [f[j] for f in split] if k == 1 else [f"{f[j]} {f[j + 1]}" for f in split]
    present = [i for i, c in enumerate(cells) if c.strip().strip('"')]
    if not present:
        raise RunFormatError(f"column {label!r} has no time stamp in any row", where)
    try:
        stamps = parse_stamps(cells if len(present) == len(cells) else [cells[i] for i in present])
    except StampError as exc:
        number = rows[present[exc.row]][0]
        raise RunFormatError(f"line {number}, column {label!r}: {exc}", where) from None
    for m in stamps.midnight:
        number = rows[present[m]][0]
        before = cells[present[m - 1]].strip()
        warn(
            f"{where}: column {label!r}: the time of day passes midnight at line {number} "
            f"({before!r} to {cells[present[m]].strip()!r}): a day is added from there on",
            ReadingWarning,
        )
    del cells
    values = [""] * len(rows)
    for i, offset in zip(present, map(str, stamps.offsets_us.tolist()), strict=True):
        values[i] = offset
    joiner = d if d is not None else " "
    out = list(lines[: column.header])
    out.append((lines[column.header][0], header))
    out.extend(
        (number, joiner.join([*f[:j], value, *f[cut:]]))
        for (number, _), f, value in zip(rows, split, values, strict=True)
    )
    return Stamped(out, stamps.start, label, d, j, k, bool(stamps.midnight))
