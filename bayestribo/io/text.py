"""Delimited text files: the canonical CSV and any other column layout.

The canonical file has a header row naming its columns with the canonical names
``time_s``, ``displacement_m`` and ``velocity_m_per_s``; a header may instead give
other units in the names (``time_ms``, ``displacement_um``, ``velocity [mm/s]``, see
:mod:`bayestribo.io.columns`), which are converted. The delimiter and the
decimal mark (a comma in a semicolon, tab or blank separated file) are found from the
rows of numbers, a byte-order mark is dropped, and a software's preamble (``Key:
value`` lines) above the header row is skipped. A header separated by blanks may hold
names with blanks (``Time (s)    Position (mm)``): it is split into as many names as
the rows hold numbers, and refused when that split is ambiguous. A file without a time
column reads with its sample rate (:func:`bayestribo.read_run`), which its preamble may
state (``Sample rate: 1 kHz``, :func:`stated_rate`). Any other text file of
numbers in columns (comma, semicolon, tab or white-space separated, with or without
a header, ``#`` comment lines allowed) reads with ``columns=[...]``: one canonical
name or ``"ignore"`` per column, in file order, and optionally a scale factor per
column converting the file's unit to the canonical one (for instance
``scale={"displacement_m": 1e-3}`` for a column in millimetres).
"""

from __future__ import annotations

import io
import re
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._files import write_text
from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io import bulk_text
from bayestribo.io.columns import (
    IGNORE,
    acceleration_label,
    check_scale,
    column_name,
    combine_units_row,
    motion_label,
    other_quantity,
    parse_column,
    pixel_column,
    si_names,
    split_run_tag,
)
from bayestribo.io.comment_header import comment_header
from bayestribo.io.encoder_counts import encoder_advice, encoder_columns, header_and_rows
from bayestribo.io.footer import without_footer
from bayestribo.io.gyroscope import gyroscope_columns
from bayestribo.io.instruments import PREAMBLE_LINES, detect_export, read_export
from bayestribo.io.repeated_header import without_repeated_header
from bayestribo.io.run import (
    ACCELERATION_AXES,
    ACCELERATIONS,
    ANGULAR,
    COLUMNS,
    DISPLACEMENT,
    TIME,
    VELOCITY,
)
from bayestribo.io.stamped_lines import STAMP_COLUMN, START_TIME, stamped_lines
from bayestribo.io.timestamps import StampError, parse_stamps

#: Every column name a text file's columns are read as.
_READ = (*COLUMNS, *ANGULAR, *ACCELERATIONS)

__all__ = [
    "IGNORE",
    "PREAMBLE_RATE",
    "StatedRate",
    "TextLayout",
    "check_scale",
    "decode",
    "parse_lines",
    "read_text",
    "stated_rate",
    "text_layout",
    "write_csv",
]

_DELIMITERS = (",", ";", "\t")


#: The canonical names of a rotation in degrees (:func:`_read`'s advice for a header
#: without units).
_IN_DEGREES = {"angle_rad": "angle_deg", "angular_velocity_rad_per_s": "angular_velocity_deg_per_s"}


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return [field.strip() for field in line.split(delimiter)]


def _as_float(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _parse_block(
    rows: list[tuple[int, str]],
    delimiter: str | None,
    width: int,
    keep: list[int],
    decimal: str = ".",
) -> NDArray | None:
    """The kept columns of rows of ``width`` numbers each, parsed by numpy's C reader
    (:func:`numpy.loadtxt`, which reads every number as Python's ``float`` does), or
    None for anything else (a field that is not a number, a row of another width),
    which :func:`_parse_rows` then reads or names. A decimal comma is read as a point
    (the delimiter is then not a comma)."""
    text = "\n".join(line for _, line in rows)
    if decimal == ",":
        if "." in text:
            return None  # a point beside decimal commas: _parse_rows names the cell
        text = text.replace(",", ".")
    try:
        block = np.loadtxt(
            io.StringIO(text), delimiter=delimiter, comments=None, ndmin=2, dtype=np.float64
        )
    except ValueError:
        return None
    if block.shape != (len(rows), width):
        return None
    return np.ascontiguousarray(block[:, keep])


def _parse_rows(
    rows: list[tuple[int, str]],
    delimiter: str | None,
    decimal: str,
    names: list[str],
    keep: list[tuple[int, str]],
    where: str,
    grouped: bool = False,
) -> NDArray:
    """The kept columns, row by row with Python's ``float``; the first row of another
    width or field that is not a number is an error naming its line and column.
    Numbers grouped in thousands by points beside a decimal comma (``1.234,5``) are
    read only when the decimal comma was given (``grouped``); a guess names them."""
    data = np.empty((len(rows), len(keep)), dtype=np.float64)
    width = len(names)
    last = len(rows) - 1
    for r, (number, line) in enumerate(rows):
        fields = _split(line, delimiter)
        if r == last and r > 0 and _cut_short(fields, width, keep, decimal):
            # a last line cut short (the file was copied while it was being written)
            warn(
                f"{where}: the last line (line {number}) is incomplete: "
                f"{line[:80]!r}; it is left out of the run",
                ReadingWarning,
            )
            return data[:last]
        if len(fields) != width:
            raise RunFormatError(
                f"line {number}: expected {width} field(s) ({', '.join(names)}), got "
                f"{len(fields)}: {line[:80]!r}",
                where,
            )
        for c, (i, name) in enumerate(keep):
            field = fields[i]
            if decimal == ",":
                field = _with_point(field) if grouped or "." not in field else "x"
            if field == "":
                data[r, c] = np.nan  # an empty cell: kept as missing, see _trim_missing
                continue
            value = _as_float(field)
            if value is None:
                hint = (
                    " (a point grouping thousands beside decimal commas: --decimal , reads it so)"
                    if decimal == "," and not grouped and _GROUPED.fullmatch(fields[i])
                    else ""
                )
                raise RunFormatError(
                    f"line {number}, column {name!r}: {fields[i][:40]!r} is not a number{hint}",
                    where,
                )
            data[r, c] = value
    return data


def decode(data: bytes, encoding: str | None, where: str, *, say: bool = True) -> str:
    """The file's text: in ``encoding`` when given, else UTF-8, else Windows-1252 (the
    8-bit encoding lab software writes; a byte it leaves undefined falls back to
    Latin-1), said with a :class:`~bayestribo.errors.ReadingWarning` unless ``say`` is
    false.

    Raises
    ------
    RunFormatError
        For an unknown encoding, or text that is not in the given one.
    """
    if encoding is not None:
        if not isinstance(encoding, str):
            raise RunFormatError(
                f"encoding: expected the name of a text encoding, got {encoding!r}", where
            )
        try:
            return data.decode(encoding)
        except LookupError:
            raise RunFormatError(f"encoding: unknown text encoding {encoding!r}", where) from None
        except UnicodeDecodeError as exc:
            raise RunFormatError(
                f"the file is not {encoding} text ({exc.reason} at byte {exc.start})", where
            ) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        first = exc.start
    try:
        text, used = data.decode("cp1252"), "Windows-1252"
    except UnicodeDecodeError:
        text, used = data.decode("latin-1"), "Latin-1"
    if not say:
        return text
    warn(
        f"{where}: not UTF-8 (byte {data[first]:#04x} at {first}): read as {used}, where it "
        f"is {text[first]!r}; give encoding= (--encoding) if the header reads wrong",
        ReadingWarning,
    )
    return text


#: A number with a decimal comma whose integer part is grouped in thousands by points
#: (``1.234,5``, a European spreadsheet's number format).
_GROUPED = re.compile(r"[+-]?\d{1,3}(?:\.\d{3})+,\d*(?:[eE][+-]?\d+)?")


def _with_point(field: str) -> str:
    """A field of a file with decimal commas, written with a decimal point.

    The points of a thousands grouping (``1.234,5`` → ``1234.5``) are taken off; a
    point anywhere else beside decimal commas is not read (``"x"``, which no reader
    takes for a number), so the cell is named.
    """
    if "." in field:
        if _GROUPED.fullmatch(field) is None:
            return "x"
        field = field.replace(".", "")
    return field.replace(",", ".")


#: What a number cut short can look like: a prefix of a decimal number.
_NUMBER_PREFIX = re.compile(r"[+-]?\d*[.,]?\d*(?:[eE][+-]?\d*)?")


def _cut_short(fields: list[str], width: int, keep: list[tuple[int, str]], decimal: str) -> bool:
    """True when a row is a complete row cut short: no more fields than the header,
    every field before the last one a number where one is kept, and the last a prefix
    of a number (a bad field, ``abc``, is no truncation but an error)."""
    if not fields or len(fields) > width:
        return False
    kept = {i for i, _ in keep}
    for i, field in enumerate(fields[:-1]):
        value = field.replace(",", ".") if decimal == "," else field
        if i in kept and _as_float(value) is None:
            return False
    if len(fields) == width and (
        fields[-1] == ""  # an empty cell, not a cut: see _trim_missing
        or len(fields) - 1 not in kept
        or _as_float(fields[-1].replace(",", ".")) is not None
    ):
        return False
    return _NUMBER_PREFIX.fullmatch(fields[-1]) is not None


def _trim_missing(
    data: NDArray, rows: list[tuple[int, str]], keep: list[tuple[int, str]], where: str
) -> NDArray:
    """The rows without empty cells: a channel may lack values at the start or the end
    of the file (an instrument's derivative is not defined there), and those rows are
    left out, with a :class:`~bayestribo.errors.ReadingWarning` that names them; an
    empty cell between values is an error naming its line and column."""
    missing = np.isnan(data)
    if not missing.any():
        return data
    names = [name for _, name in keep]
    if TIME in names:
        # A time cell may be empty only in a row with no value at all (the end of a
        # shorter run beside a longer one in the same file).
        lone = missing[:, names.index(TIME)] & ~missing.all(axis=1)
        if lone.any():
            line = rows[int(np.flatnonzero(lone)[0])][0]
            raise RunFormatError(f"line {line}, column {TIME!r}: '' is not a number", where)
    for c, (_, name) in enumerate(keep):
        present = np.flatnonzero(~missing[:, c])
        if present.size == 0:
            raise RunFormatError(f"column {name!r} has no value in any row", where)
        gap = np.flatnonzero(missing[present[0] : present[-1] + 1, c])
        if gap.size:
            line = rows[present[0] + int(gap[0])][0]
            raise RunFormatError(
                f"line {line}, column {name!r}: an empty cell between values; a channel may "
                "lack values only at the start or the end of the file",
                where,
            )
    good = ~missing.any(axis=1)
    lines = [rows[i][0] for i in np.flatnonzero(~good)]
    span = f"line {lines[0]}" if len(lines) == 1 else f"lines {lines[0]}-{lines[-1]}"
    empty = [name for c, (_, name) in enumerate(keep) if missing[:, c].any()]
    warn(
        f"{where}: {len(lines)} row(s) at the start or end of the file ({span}) have no "
        f"value for {', '.join(empty)}; they are left out of the run (give "
        "columns=[...] with 'ignore' for a channel not to use)",
        ReadingWarning,
    )
    return np.ascontiguousarray(data[good])


def _canonical(name: str, where: str, what: str) -> tuple[str, float]:
    """Canonical name and unit factor of one column name (canonical, with a unit, or
    ``ignore``)."""
    if name in (*_READ, IGNORE):
        return name, 1.0
    try:
        parsed = parse_column(name)
    except ValueError as exc:
        raise RunFormatError(f"{what}: {exc}", where) from None
    if parsed is None:
        raise RunFormatError(
            f"{what}: unknown column {name!r}; expected per column one of "
            f"{[*COLUMNS, IGNORE]} or a quantity with its unit (time_ms, displacement_um, "
            "velocity_mm_per_s, angle_deg, angular_velocity_rad_per_s, acceleration_g, ...); "
            "columns=[...] "
            "names the columns in file order",
            where,
        )
    return parsed


def _check_columns(
    columns: Sequence[str], where: str, what: str = "columns"
) -> tuple[list[str], dict[str, float]]:
    """Canonical names of the columns in file order and the unit factor of each."""
    if isinstance(columns, str) or not isinstance(columns, Sequence):
        raise RunFormatError(
            "columns: expected a list with one name per column of the file, for instance "
            f"['time_s', 'displacement_m']; got {columns!r}",
            where,
        )
    parsed = [_canonical(str(name), where, what) for name in columns]
    names = [n for n, _ in parsed]
    factors = {n: f for n, f in parsed if n != IGNORE and f != 1.0}
    used = [n for n in names if n != IGNORE]
    for name in set(used):
        if used.count(name) > 1:
            raise RunFormatError(f"{what}: {name!r} is given {used.count(name)} times", where)
    if not {DISPLACEMENT, VELOCITY, *ANGULAR, *ACCELERATIONS} & set(used):
        raise RunFormatError(
            f"{what}: a {DISPLACEMENT!r} or {VELOCITY!r} column is needed (or an angle, "
            "angle_deg, angular_velocity_rad_per_s, ..., or an acceleration, "
            f"acceleration_m_per_s2, accel_g, ...); got {list(columns)}",
            where,
        )
    return names, factors


#: The key under which :func:`read_text` and :func:`parse_lines` return, beside the
#: columns, the sample rate the file's preamble states (a :class:`StatedRate`), when it
#: states one; :func:`bayestribo.read_run` takes it out before building the run.
PREAMBLE_RATE = "preamble_sample_rate"


@dataclass(frozen=True)
class StatedRate:
    """The sample rate a preamble line states (``Sample rate: 1 kHz``).

    Attributes
    ----------
    rate_Hz : float
        The rate [Hz] (an interval's reciprocal).
    line : int
        The line that states it, from 1.
    text : str
        That line as the file writes it (stripped).
    skip : int
        The ``skip_rows`` that leaves every line stating a rate out of the reading.
    """

    rate_Hz: float
    line: int
    text: str
    skip: int

    def __str__(self) -> str:
        return f"the preamble's {self.text!r} (line {self.line})"


#: A preamble line stating a rate or an interval: a key (its unit in brackets may
#: follow), ``:``, ``=``, a tab, ``;`` or ``,``, a number, and a unit (optional).
_RATE_LINE = re.compile(
    r"^\s*(?P<key>[^:=\t;,\(\[\d]+?)\s*(?:[\(\[]\s*(?P<key_unit>[^\)\]]*?)\s*[\)\]])?"
    r"\s*(?:[:=\t;,]\s*)+(?P<value>[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"(?:(?:\s*[\t;,]\s*|\s*)(?P<unit>[^\s\d;,][^\s;,]*))?[\s;,]*$"
)
#: Keys of a sample rate, in lower case with single blanks.
_RATE_KEYS = frozenset(
    {
        "sample rate",
        "sampling rate",
        "sample frequency",
        "sampling frequency",
        "fs",
        "samples per second",
        "scan rate",
    }
)
#: Keys of a sample interval.
_INTERVAL_KEYS = frozenset(
    {
        "sample interval",
        "sampling interval",
        "sample period",
        "sampling period",
        "dt",
        "δt",
        "delta t",
    }
)
#: Units of a rate and their factor to Hz ("" for none: a rate is per second). The
#: case of M and m is kept: mHz is no MHz.
_RATE_UNITS = {
    "": 1.0,
    "Hz": 1.0,
    "hz": 1.0,
    "HZ": 1.0,
    "kHz": 1e3,
    "KHz": 1e3,
    "khz": 1e3,
    "KHZ": 1e3,
    "MHz": 1e6,
    "MHZ": 1e6,
    "S/s": 1.0,
    "Sa/s": 1.0,
    "samples/s": 1.0,
    "kS/s": 1e3,
    "kSa/s": 1e3,
    "ksamples/s": 1e3,
    "MS/s": 1e6,
    "MSa/s": 1e6,
    "Msamples/s": 1e6,
}
#: Units of an interval and how many of them make a second (none: s or ms is not
#: guessed); 1 / (10 µs) is then 1e6 / 10, exactly 100 kHz.
_INTERVAL_UNITS = {
    "s": 1.0,
    "sec": 1.0,
    "ms": 1e3,
    "msec": 1e3,
    "us": 1e6,
    "µs": 1e6,
    "\u03bcs": 1e6,
    "usec": 1e6,
}
#: Statements of one rate that differ by more than this (relative) contradict.
_RATES_AGREE = 1e-9


def _rate_of(line: str) -> float | None:
    """The sample rate [Hz] a preamble line states, or None for a line that states
    none: another key, no number, an unknown unit (never guessed)."""
    m = _RATE_LINE.match(line.replace('"', ""))
    if m is None:
        return None
    key = " ".join(m.group("key").lower().split())
    key_unit = (m.group("key_unit") or "").strip()
    unit = m.group("unit") or ""
    if key_unit and unit and key_unit != unit:
        return None
    unit = unit or key_unit
    value = float(m.group("value"))
    if not (np.isfinite(value) and value > 0.0):
        return None
    if key in _RATE_KEYS and unit in _RATE_UNITS:
        rate = value * _RATE_UNITS[unit]
    elif key in _INTERVAL_KEYS and unit in _INTERVAL_UNITS:
        rate = _INTERVAL_UNITS[unit] / value
    else:
        return None
    return rate if np.isfinite(rate) else None


def stated_rate(lines: Sequence[tuple[int, str]], where: str) -> StatedRate | None:
    """The sample rate the preamble lines of a file state, or None.

    A line such as ``Sample rate: 1 kHz``, ``Sampling rate = 500 Hz``, ``Fs: 2000``,
    ``Samples per second: 200``, ``Sample interval: 0.001 s`` or ``dt = 1 ms`` (a ``#``
    before it, quotes and a unit in brackets after the key, ``Sample rate (Hz): 1000``,
    allowed) states one. Rates are in Hz, kHz, MHz, S/s, Sa/s or samples/s (a bare
    number is Hz), intervals in s, ms, µs or us (a bare number is no interval: s and ms
    are not guessed). A line with another unit or a value that is not a number states
    nothing: it stays a preamble line.

    Parameters
    ----------
    lines : sequence of (int, str)
        The lines above the header (or above the first row of numbers), numbered from 1.
    where : str
        The file, for messages.

    Returns
    -------
    StatedRate or None

    Raises
    ------
    RunFormatError
        When two lines state different rates, naming both.
    """
    found: StatedRate | None = None
    for number, line in lines:
        text = line.strip().lstrip("#").strip()
        rate = _rate_of(text)
        if rate is None:
            continue
        if found is None:
            found = StatedRate(rate, number, text, number)
        elif abs(rate - found.rate_Hz) > _RATES_AGREE * found.rate_Hz:
            raise RunFormatError(
                f"{found} states a sample rate of {found.rate_Hz:g} Hz but line {number} "
                f"{text!r} states {rate:g} Hz; correct the one that is wrong, or leave the "
                f"preamble out with skip_rows={number}",
                where,
            )
        else:
            found = StatedRate(found.rate_Hz, found.line, found.text, number)
    return found


#: Delimiters a spreadsheet export may write at the end of every line (``1.0,2.5,``,
#: ``1.0\t2.5\t``).
_TRAILING = (",", ";", "\t")


def _line_end(line: str, mark: str) -> str:
    """``line`` without the blanks at its end, a tab kept when ``mark`` is one."""
    return line.rstrip(" \r\n\f\v") if mark == "\t" else line.rstrip()


def without_trailing_delimiter(lines: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """The lines without the delimiter that ends every one of them that holds it.

    Spreadsheet and LabVIEW exports often end each line, the header's too, with the
    delimiter (``"Time (s)","Position (mm)",`` then ``0.001,0.52,``; a tab in a
    tab-separated export): a field after it
    is empty on every line, so it ends no field, and it is taken off. Nothing is taken
    off when a line that holds the delimiter does not end with it (a header without it
    above rows with it keeps its empty column, which is then said as one without
    values), or when fewer than two lines hold it.

    Parameters
    ----------
    lines : list of (int, str)
        Line numbers and lines, blank and comment lines left out.

    Returns
    -------
    list of (int, str)
        ``lines`` itself when nothing is taken off, else new lines.
    """
    for mark in _TRAILING:
        holding = 0
        for _, line in lines:
            if mark in line:
                if not _line_end(line, mark).endswith(mark):
                    break  # a line holds it and does not end with it
                holding += 1
        else:
            if holding >= 2:
                return [
                    (n, _line_end(line, mark)[:-1] if mark in line else line) for n, line in lines
                ]
    return lines


def _fields_of(line: str, delimiter: str | None) -> list[str]:
    return [f.strip().strip('"').strip("'").strip() for f in _split(line, delimiter)]


#: Where a header of names separated by blanks may split between names that hold
#: blanks themselves (``Time (s)    Position (mm)``): at a run of two or more blanks or
#: a tab, after a unit's closing bracket (or a closing quote), or at either.
_HEADER_GAPS = (
    re.compile(r"[ \t]{2,}|\t"),
    re.compile(r"(?<=[\)\]\"])[ \t]+"),
    re.compile(r"(?<=[\)\]\"])[ \t]+|[ \t]{2,}|\t"),
)


def _header_splits(line: str, delimiter: str | None, width: int | None) -> list[list[str]]:
    """The ways a header line splits into ``width`` names.

    A line split by a delimiter, or one whose blanks split it into ``width`` names, has
    one way (its fields, whatever their number). A line of names separated by blanks
    whose names hold blanks too (``Time (s)    Position (mm)``) is split at runs of two
    or more blanks or a tab, after a closing ``)``/``]``, or at either: every distinct
    split into ``width`` names is returned (none when no split gives ``width``, more
    than one when the line is ambiguous; the caller refuses both).
    """
    plain = _fields_of(line, delimiter)
    if delimiter is not None or width is None or len(plain) == width:
        return [plain]
    text = line.strip()
    splits: list[list[str]] = []
    for gaps in _HEADER_GAPS:
        fields = [f.strip().strip('"').strip("'").strip() for f in gaps.split(text)]
        if len(fields) == width and fields not in splits:
            splits.append(fields)
    return splits


def _names_of(line: str, delimiter: str | None, width: int | None) -> list[str]:
    """The names of a header line: its first split into ``width`` names
    (:func:`_header_splits`), else its plain fields."""
    return (_header_splits(line, delimiter, width) or [_fields_of(line, delimiter)])[0]


def _header_fields(
    number: int, line: str, delimiter: str | None, width: int | None, where: str
) -> list[str]:
    """The names of a header line (:func:`_header_splits`): its plain fields when no
    split gives ``width`` names (the caller then says the widths differ).

    Raises
    ------
    RunFormatError
        For a blank-separated header that splits into ``width`` names in more than one
        way, naming the line and the splits: the units would be guessed.
    """
    splits = _header_splits(line, delimiter, width)
    if len(splits) == 1:
        return splits[0]
    if not splits:
        return _fields_of(line, delimiter)
    ways = " or ".join(repr(s) for s in splits)
    raise RunFormatError(
        f"header (line {number}) {line.strip()[:80]!r}: its names are separated by blanks "
        f"and hold blanks, and it splits into the {width} columns of the rows in more than "
        f"one way ({ways}); name the columns in file order with columns=[...], one name "
        "with its unit per column (for instance 'time_s', 'displacement_mm', 'ignore')",
        where,
    )


def _header(
    lines: Sequence[tuple[int, str]], delimiter: str | None, where: str, width: int | None = None
) -> tuple[list[str], dict[str, float], int]:
    """Column names, unit factors and the number of header lines of a file's header.

    The header is one row of names with units (``Time (s)``), or a row of names and a
    row of units below it (``Time`` / ``s``). Run labels of sensor software (``Run #1``,
    ``Latest:``) are taken off; columns of another quantity (acceleration, force, ...)
    are not read, and said. Several runs side by side are refused with the
    ``columns=`` that reads each. ``width`` is the number of fields of the rows of
    numbers below: a header separated by blanks is split into as many names
    (:func:`_header_fields`).
    """
    number = lines[0][0]
    header = _header_fields(number, lines[0][1], delimiter, width, where)
    count = 1
    if len(lines) > 1:
        second = (_header_splits(lines[1][1], delimiter, width) or [[]])[0]
        if all(_as_float(f) is None for f in second if f):
            combined = combine_units_row(header, second)
            if combined is not None:
                header, count = combined, 2
    what = f"header (line {number})" if count == 1 else f"header (lines {number}-{number + 1})"
    labels, tags = zip(*(split_run_tag(f) for f in header), strict=True)
    runs = list(dict.fromkeys(t for t in tags if t is not None))
    if len(runs) > 1:
        raise RunFormatError(f"{what}: {_side_by_side(labels, tags, runs)}", where)
    kept = []
    other = []
    # an acceleration is read only where the file records no displacement, velocity or
    # angle: the motion recorded is used, the acceleration said and left out
    motion = any(
        label in (DISPLACEMENT, VELOCITY, *ANGULAR) or motion_label(label) for label in labels
    )
    for label in labels:
        if label in (*_READ, IGNORE) or not (
            other_quantity(label) or (motion and acceleration_label(label))
        ):
            kept.append(label)
        else:
            kept.append(IGNORE)
            other.append(label)
    try:
        names, units = _check_columns(kept, where, what)
    except RunFormatError as exc:
        if "unknown column" in exc.message:
            counts = encoder_advice(labels, [_known(label) for label in labels])
            if counts:
                raise RunFormatError(f"{exc.message}; {counts}", where) from None
        if other and "column is needed" in exc.message:
            raise RunFormatError(
                f"{what}: no displacement, velocity or acceleration column; {other} are "
                "other quantities, which are not read; export the position, the velocity "
                "or the acceleration, or name the columns with columns=[...]",
                where,
            ) from None
        si = si_names(labels)
        if si is None and "has no unit" in exc.message:
            tracked = _coordinates_advice(labels)
            if tracked:
                raise RunFormatError(f"{exc.message}; {tracked}", where) from None
        if "in pixels" in exc.message:
            raise RunFormatError(f"{exc.message}; {_pixel_advice(labels)}", where) from None
        if "has no unit" not in exc.message or si is None:
            raise
        if any(name in ANGULAR for name in si):
            # an angle: its degrees as likely as its radians (an encoder's, a video's)
            degrees = [_IN_DEGREES.get(name, name) for name in si]
            units = f"columns={si} if the file is in s and radians, columns={degrees} if in degrees"
        else:
            units = f"columns={si} if the file is in s, m and m/s"
        raise RunFormatError(
            f"{exc.message}; or name every column in file order, for instance {units}",
            where,
        ) from None
    if other:
        warn(
            f"{where}: {what}: column(s) {other} not read (another quantity, or an "
            "acceleration beside the motion recorded); the run is read from "
            f"{[n for n in names if n != IGNORE]}",
            ReadingWarning,
        )
    return names, units, count


def _known(label: str) -> str | None:
    """A header name as ``columns=`` takes it where it names a quantity, else None."""
    try:
        return label if parse_column(label) is not None else None
    except ValueError:
        return None


def _coordinates_advice(labels: Sequence[str]) -> str:
    """How to read a video tracker's ``t, x, y`` columns without units (Tracker's
    export): one coordinate as the displacement, the other left out; "" for other
    labels."""
    words = [label.strip().lower() for label in labels]
    unique = len(set(words)) == len(words)
    if not (unique and {"x", "y"} <= set(words) <= {"t", "x", "y"}):
        return ""

    def names(axis: str) -> list[str]:
        roles = {"t": TIME, axis: DISPLACEMENT}
        return [roles.get(word, IGNORE) for word in words]

    return (
        f"or name every column in file order: columns={names('x')} if the motion is "
        f"along x, columns={names('y')} if along y, the file in s and m"
    )


def _pixel_advice(labels: Sequence[str]) -> str:
    """How to read a video tracker's columns in pixels: as an arbitrary length unit, or
    in metres with the camera's scale (a column of no known quantity, a second
    coordinate ``y (px)``, is left out)."""
    names, pixels = [], []
    for label in labels:
        pixel = pixel_column(label)
        if pixel is not None:
            pixels.append(pixel)
            names.append(pixel)
            continue
        try:
            parsed = parse_column(label)
        except ValueError:  # a quantity without its unit: in SI, as si_names says
            parsed = ((si_names([label]) or [IGNORE])[0], 1.0)
        names.append(IGNORE if parsed is None or other_quantity(label) else parsed[0])
    scale = ", ".join(f"'{name}': 0.001" for name in pixels)
    return (
        f"read it in pixels with columns={names} and length_unit='arbitrary' (friction "
        f"then in pixels), or in metres with columns={names} and scale={{{scale}}} for a "
        "camera that sees 1 mm per pixel (its own metres per pixel in place of 0.001)"
    )


def _side_by_side(labels: Sequence[str], tags: Sequence[str | None], runs: list[str]) -> str:
    """The message for several runs in one file, with the columns= that reads each."""
    choices = []
    for run in runs:
        names = []
        for label, tag in zip(labels, tags, strict=True):
            try:
                parsed = None if tag != run else parse_column(label)
            except ValueError:
                parsed = None
            names.append(IGNORE if parsed is None else column_name(label, *parsed))
        choices.append(f"{run}: columns={names}")
    return (
        f"the file holds {len(runs)} runs side by side ({', '.join(runs)}); read one at a "
        f"time, {'; '.join(choices)}"
    )


#: Rows of numbers looked at to tell the delimiter and the decimal mark.
_PROBE_ROWS = 20
#: Share of those rows that must read as numbers for a choice to be taken.
_GOOD_ROWS = 0.9
#: Candidate (delimiter, decimal mark) pairs, in the order they are tried: the decimal
#: point first, then the decimal comma (never with a comma delimiter).
_MARKS = tuple(
    (d, m) for m in (".", ",") for d in (",", ";", "\t", None) if not (d == "," and m == ",")
)


def _number_or_empty(field: str, decimal: str) -> bool | None:
    """True for a number, None for an empty cell, False for anything else."""
    if field == "":
        return None
    if decimal == ",":
        field = _with_point(field)
    return _as_float(field) is not None


def _numeric_row(fields: list[str], decimal: str, kept: Sequence[int] | None) -> bool:
    """A row of numbers (empty cells allowed, at least one number) in the kept columns."""
    cells = fields if kept is None else [fields[i] for i in kept if i < len(fields)]
    found = [_number_or_empty(f, decimal) for f in cells]
    return False not in found and True in found


def _table_line(fields: list[str], width: int, decimal: str) -> bool:
    """A line above a header that may be a row of samples with a bad cell, not a
    preamble line: as many fields as the table (two or more), a number among them (more
    than half of them in a table of three or more columns: ``Logger export 2.1`` is a
    software's line, ``0.01 overload 0.3`` a row), none of them a ``Key:`` or a
    ``key=value``."""
    numbers = sum(bool(_number_or_empty(f, decimal)) for f in fields)
    return (
        width >= 2
        and len(fields) == width
        and not any(f.endswith(":") or "=" in f for f in fields if f)
        and numbers > 0
        and (width < 3 or 2 * numbers > width)
    )


#: A line that starts with a number (no header row does).
_STARTS_WITH_NUMBER = re.compile(r"^[\s\"']*[-+]?\.?\d")


def _guess_table(
    lines: Sequence[tuple[int, str]],
    columns: Sequence[str] | None,
    delimiter: str | None,
    decimal: str | None,
    where: str = "",
) -> tuple[str | None, str, int | None] | None:
    """The delimiter, the decimal mark and the index of the first row of numbers of a
    text's first lines, or None when no choice reads them as a table.

    Each (delimiter, decimal mark) pair of :data:`_MARKS` (the given ones only) is tried
    in turn; the first that splits the first :data:`_PROBE_ROWS` rows of numbers (all but
    one in ten) into as many numbers (or empty cells) as the header (or ``columns``)
    names is taken. A
    decimal comma is so taken only when no number holds a point. The lines above the
    first row of numbers are the header and a preamble (``Key: value`` lines); the
    index is None when one of them looks like a row of samples with a bad cell, which
    the reader then names. A header over rows separated by blanks is split into as many
    names as the rows hold numbers (:func:`_header_splits`); one that splits so in more
    than one way is refused (:class:`~bayestribo.errors.RunFormatError`, ``where`` names
    the file).
    """
    marks = [
        (d, m)
        for d, m in _MARKS
        if (delimiter is None or d == delimiter) and (decimal in (None, ".") or m == decimal)
    ]
    if delimiter is not None and delimiter not in (",", ";", "\t"):
        marks = [(delimiter, m) for m in ((decimal,) if decimal == "," else (".", ","))]
    kept = None if columns is None else [i for i, n in enumerate(columns) if n != IGNORE]
    probe = lines[:PREAMBLE_LINES]
    for d, m in marks:
        first = None
        for index, (_, line) in enumerate(probe):
            fields = _split(line, d)
            if (columns is None or len(fields) == len(columns)) and _numeric_row(fields, m, kept):
                first = index
                break
        if first is None:
            continue
        if columns is not None:
            width = len(columns)
        elif first > 0 and d is not None:
            width = len(_fields_of(probe[first - 1][1], d))
        else:
            # no header, or one separated by blanks: its names may hold blanks
            # (``Time (s)  Position (mm)``) and are split as the rows are wide, below
            width = len(_split(probe[first][1], d))
        # the rows of numbers below, but for the last line read (it may be cut short)
        rows = probe[first : first + _PROBE_ROWS]
        if len(rows) > 1 and first + len(rows) == len(probe):
            rows = rows[:-1]
        good = sum(
            len(fields) == width and _numeric_row(fields, m, kept)
            for fields in (_split(line, d) for _, line in rows)
        )
        if good < _GOOD_ROWS * len(rows):
            continue  # (a bad cell or two is the reader's to name)
        if columns is None and first > 0 and d is None:
            number, header = probe[first - 1]
            if not _header_splits(header, d, width):
                continue  # no header of this width: another choice, or the reader's error
            _header_fields(number, header, d, width, where)  # refused when ambiguous
        if first >= 2:
            # a preamble above the header: the header must be one, and the preamble no
            # row of the table (the reader then names the line that is wrong)
            header = probe[first - 1][1]
            if _STARTS_WITH_NUMBER.match(header) or any(
                _number_or_empty(f, m) for f in _split(header, d)
            ):
                continue
            start = first - 1
            if first >= 3 and combine_units_row(
                _names_of(probe[first - 2][1], d, width), _names_of(header, d, width)
            ):
                start = first - 2  # a row of names and a row of units
            above = [_split(line, d) for _, line in probe[:start]]
            if any(_table_line(fields, width, m) for fields in above):
                return d, m, None
        return d, m, first
    return None


def _layout(
    lines: Sequence[tuple[int, str]],
    where: str,
    columns: Sequence[str] | None,
    delimiter: str | None,
    decimal: str | None,
) -> tuple[list[str], dict[str, float], int, str | None, str]:
    """Column names, unit factors, header lines (a preamble and a header above the
    first row of numbers), delimiter and decimal mark of a text's first lines
    (numbered, blank and comment lines left out)."""
    units: dict[str, float] = {}
    if columns is not None:
        columns, units = _check_columns(columns, where)
    if not lines:
        raise RunFormatError("the file holds no data rows", where)
    guess = _guess_table(lines, columns, delimiter, decimal, where)
    first: int | None = None
    if guess is not None:
        delimiter, decimal, first = guess
    else:
        decimal = decimal or "."
        if delimiter is None:
            candidates = _DELIMITERS[1:] if decimal == "," else _DELIMITERS
            delimiter = next((d for d in candidates if d in lines[0][1]), None)
    if columns is None and first is not None and first > 0:
        # a header row above the rows of numbers, or a row of names and a row of units
        start = first - 1
        width = len(_split(lines[first][1], delimiter)) if first < len(lines) else None
        if first >= 2:
            names = _names_of(lines[first - 2][1], delimiter, width)
            if combine_units_row(names, _names_of(lines[first - 1][1], delimiter, width)):
                start = first - 2
        names, units, count = _header(lines[start:first], delimiter, where, width)
        return names, units, start + count, delimiter, decimal
    first_fields = _split(lines[0][1], delimiter)
    if decimal == ",":
        first_fields = [f.replace(",", ".") for f in first_fields]
    has_header = any(_as_float(f) is None for f in first_fields)
    if columns is None:
        if not has_header:
            raise RunFormatError(
                "no header row: name the columns in file order with their units, for "
                "instance read_run(path, columns=['time_s', 'displacement_mm']) (t, x and v "
                "alone mean s, m and m/s; length_unit='arbitrary' when the file does not say "
                "its length unit)" + _no_time_hint(len(first_fields)),
                where,
            )
        names, units, header_lines = _header(lines, delimiter, where)
        return names, units, header_lines, delimiter, decimal
    names = list(columns)
    if first is not None and first > 0:
        header = _names_of(lines[first - 1][1], delimiter, len(names))
        if len(header) != len(names):
            raise RunFormatError(
                f"header (line {lines[first - 1][0]}) has {len(header)} column(s) but "
                f"columns= names {len(names)}; expected one name per column"
                + _preamble_hint(lines, delimiter, decimal, len(names)),
                where,
            )
        return names, units, first, delimiter, decimal
    if len(first_fields) == len(names):
        # Only the kept columns decide: a text column that is ignored (a clock
        # time, a label) does not make the first data row a header.
        has_header = any(
            _as_float(f) is None
            for f, name in zip(first_fields, names, strict=True)
            if name != IGNORE
        )
    if has_header and len(first_fields) != len(names):
        raise RunFormatError(
            f"header (line {lines[0][0]}) has {len(first_fields)} column(s) but columns= "
            f"names {len(names)}; expected one name per column"
            + _preamble_hint(lines, delimiter, decimal, len(names)),
            where,
        )
    return names, units, 1 if has_header else 0, delimiter, decimal


#: Lines of a text's start searched for the first row of a table below a preamble.
_PREAMBLE_LINES = 50


def _preamble_hint(
    lines: Sequence[tuple[int, str]], delimiter: str | None, decimal: str | None, width: int
) -> str:
    """Where a table of ``width`` columns starts below lines of another width (a
    preamble: a logger's settings written above one column of samples), as the
    ``skip_rows`` that leaves the lines above it out; empty when no such line is
    found among the first :data:`_PREAMBLE_LINES`.

    The table's first line is the first from which every line given is a row of
    ``width`` numbers (a file whose preamble is ``trigger_start_deg, sample_rate,
    duration_sec`` and ``90, 1000, 5`` above one angle per line starts at line 3)."""
    mark = decimal or "."

    def row(text: str) -> bool:
        fields = _split(text, delimiter)
        return len(fields) == width and all(_number_or_empty(f, mark) for f in fields)

    rows = [row(text) for _, text in lines]
    for i in range(1, min(len(lines), _PREAMBLE_LINES)):
        if all(rows[i:]):
            start = lines[i][0]
            return (
                f"; the rows of {width} number(s) start at line {start}: "
                f"skip_rows={start - 1} (--skip-rows) leaves the lines above out"
            )
    return ""


@dataclass(frozen=True)
class TextLayout:
    """How a delimited text is read (``bayestribo inspect``).

    Attributes
    ----------
    names : list of str
        The canonical name of each column in file order (``"ignore"`` for one not read).
    labels : list of str
        The header's labels (a unit row joined to its names), empty without a header.
    preamble : int
        Lines above the header that are skipped (a software's ``Key: value`` lines).
    delimiter : str or None
        The column separator (None: blanks).
    decimal : str
        The decimal mark.
    rate : StatedRate or None
        The sample rate a line above the rows of numbers states (``Sample rate: 1
        kHz``), or None.
    stamps : str or None
        The header's name of a column of time stamps (read as seconds from the first
        sample, :mod:`bayestribo.io.stamped_lines`), or None.
    """

    names: list[str]
    labels: list[str]
    preamble: int
    delimiter: str | None
    decimal: str
    rate: StatedRate | None = None
    stamps: str | None = None


def text_layout(
    all_lines: Sequence[str],
    where: str,
    *,
    columns: Sequence[str] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    skip_rows: int = 0,
) -> TextLayout:
    """The layout :func:`parse_lines` reads a text's first lines with (no instrument
    export).

    Parameters
    ----------
    all_lines : sequence of str
        The file's first lines (:data:`~bayestribo.io.instruments.PREAMBLE_LINES` or
        more), without line ends.
    where : str
        The file, for messages.
    columns, delimiter, decimal, skip_rows
        As for :func:`read_text`.

    Returns
    -------
    TextLayout

    Raises
    ------
    RunFormatError
        As :func:`read_text` for the header.
    """
    lines = [
        (number, line)
        for number, line in enumerate(all_lines[skip_rows:], start=skip_rows + 1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ReadingWarning)
        stamped = None
        if columns is None:
            try:
                stamped = stamped_lines(lines[:PREAMBLE_LINES], delimiter, where)
            except RunFormatError:
                stamped = None  # the reader names the cell
        if stamped is not None:
            lines = stamped.lines
        names, _, header_lines, delimiter, decimal = _layout(
            lines[:PREAMBLE_LINES], where, columns, delimiter, decimal
        )
    labels: list[str] = []
    preamble = 0
    if header_lines:
        start = header_lines - 1
        header = _names_of(lines[start][1], delimiter, len(names))
        if start > 0:
            above = _names_of(lines[start - 1][1], delimiter, len(names))
            if combine_units_row(above, header):
                start -= 1
                header = combine_units_row(above, header) or header
        labels, preamble = header, start
    end = lines[header_lines][0] - 1 if header_lines < len(lines) else len(all_lines)
    rate = stated_rate(list(enumerate(all_lines[skip_rows:end], start=skip_rows + 1)), where)
    stamps = None if stamped is None else stamped.label
    if stamps is not None:
        labels = [stamps if label == STAMP_COLUMN else label for label in labels]
    return TextLayout(list(names), labels, preamble, delimiter, decimal, rate, stamps)


def _no_time_hint(width: int) -> str:
    """For a headerless file of one or two columns: how to read it without a time column."""
    if width > 2:
        return ""
    return (
        "; a file without a time column is read with its sample rate, e.g. "
        "columns=['displacement_mm'] and sample_rate_Hz=HZ (--sample-rate HZ)"
    )


def _columns(
    data: NDArray | Sequence[NDArray],
    keep: list[tuple[int, str]],
    units: Mapping[str, float],
    scale: Mapping[str, float] | None,
    where: str,
) -> dict[str, NDArray]:
    """The kept columns in canonical units, by canonical name (time first).

    ``data`` is a block of rows (its columns are views: the Run copies them) or a list
    of columns; a column that owns its data is made read-only here and the Run takes
    it without a copy.
    """
    factors = check_scale(scale, [n for _, n in keep], where)
    columns = list(data.T) if isinstance(data, np.ndarray) else list(data)
    out: dict[str, NDArray] = {}
    for c, (_, name) in enumerate(keep):
        column = columns[c]
        if name in units:
            column = column * units[name]
        if name in factors:
            column = column * factors[name]
        if column.flags.owndata:
            column.setflags(write=False)
        out[name] = column
    return {name: out[name] for name in _READ if name in out}


#: Bytes read to lay out a file before streaming its numbers (:func:`_read_streamed`).
_HEAD_BYTES = 1 << 16
#: Line breaks of :meth:`str.splitlines` that CSV parsers do not break lines at.
_OTHER_LINE_BREAKS = ("\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029")


def _read_streamed(
    path: Path,
    where: str,
    columns: Sequence[str] | None,
    scale: Mapping[str, float] | None,
    delimiter: str | None,
    encoding: str | None,
    decimal: str | None = None,
) -> dict[str, Any] | None:
    """A plain file (UTF-8, a header or ``columns``, rows of numbers with a decimal
    point only) read by
    numpy's C reader straight from the file: no line of it is held as a Python string,
    so a 1 MHz record reads in a fraction of the time and memory of the line-by-line
    path. Comment lines (``#``) above the first row of numbers are skipped as the
    line-by-line reader skips them. None for anything else (an instrument export, a
    comment among the rows, a cell that is not a number, an empty cell, a row cut
    short, another encoding): the line-by-line
    reader then reads it, or names the line and column that is wrong, with the same
    numbers (the same parser reads the rows of a block there).
    """
    if encoding not in (None, "utf-8", "utf8"):
        return None
    with path.open("rb") as handle:
        head = handle.read(_HEAD_BYTES)
    complete = len(head) < _HEAD_BYTES
    if not complete:
        head = head[: head.rfind(b"\n") + 1]
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError:
        return None
    head_lines = text.splitlines()
    if detect_export(head_lines[:PREAMBLE_LINES], where) is not None:
        return None
    if any(mark in text for mark in _OTHER_LINE_BREAKS):
        return None  # str.splitlines would count lines the parsers do not
    last_comment = 0  # the last comment line's number (0: none)
    lines = []  # the lines neither blank nor comments, with their numbers
    for n, line in enumerate(head_lines, start=1):
        content = line.lstrip()
        if content.startswith("#"):
            last_comment = n
        elif content:
            lines.append((n, line))
    if len(lines) < 3 or without_trailing_delimiter(lines) is not lines:
        return None  # (a delimiter ending every line: the line-by-line reader drops it)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a header that warns goes the line-by-line way
        try:
            names, units, header_lines, delimiter, decimal = _layout(
                lines[:PREAMBLE_LINES], where, columns, delimiter, decimal
            )
        except (RunFormatError, Warning):
            if columns is not None or complete or decimal == ",":
                return None
            return _read_stamped(path, where, head_lines, lines, scale, delimiter)
    if header_lines >= len(lines) or decimal != ".":
        return None
    skip = lines[header_lines][0] - 1  # physical lines before the first row of numbers
    if last_comment > skip:
        return None  # a comment among the rows: the line-by-line reader leaves it out
    keep = [(i, n) for i, n in enumerate(names) if n != IGNORE]
    data = _read_large(path, delimiter, skip, len(names)) if not complete else None
    if data is None:
        try:
            data = np.loadtxt(
                path,
                delimiter=delimiter,
                comments=None,
                skiprows=skip,
                ndmin=2,
                dtype=np.float64,
                encoding="utf-8",
            )
        except (ValueError, UnicodeDecodeError):
            return None
    if isinstance(data, np.ndarray):  # numpy's reader: a block of rows
        if data.ndim != 2 or data.shape[0] < 1:
            return None
        data = list(data.T)
    if len(data) != len(names) or data[0].size < 1:
        return None
    out: dict[str, Any] = _columns([data[i] for i, _ in keep], keep, units, scale, where)
    _with_file_columns(out, names)
    return _with_stated_rate(out, list(enumerate(head_lines[:skip], start=1)), where)


def _read_stamped(
    path: Path,
    where: str,
    head_lines: list[str],
    lines: list[tuple[int, str]],
    scale: Mapping[str, float] | None,
    delimiter: str | None,
) -> dict[str, Any] | None:
    """A large plain file whose time column holds time stamps
    (:mod:`bayestribo.io.stamped_lines`), read by pandas' C parser with the stamps as
    text, parsed column-wise; None for anything else, or anything the line-by-line
    reader says or names (a cell that is no time stamp, a pass through midnight, an
    empty cell, a comment among the rows), which then reads the file."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            stamped = stamped_lines(lines[:PREAMBLE_LINES], delimiter, where)
            if stamped is None or stamped.midnight:
                return None
            names, units, header_lines, _, decimal = _layout(
                stamped.lines, where, None, stamped.delimiter, None
            )
        except (RunFormatError, Warning):
            return None
    if decimal != "." or header_lines >= len(stamped.lines):
        return None
    skip = stamped.lines[header_lines][0] - 1
    if any(line.lstrip().startswith("#") for line in head_lines[skip:]):
        return None
    j, k = stamped.cell, stamped.cells
    read = bulk_text.read_with_text(
        path, stamped.delimiter, skip, len(names) + k - 1, range(j, j + k)
    )
    if read is None:
        return None
    numbers, text = read
    cells = text[j] if k == 1 else [f"{a} {b}" for a, b in zip(text[j], text[j + 1], strict=True)]
    del text
    try:
        stamps = parse_stamps(cells)
    except StampError:
        return None
    if stamps.midnight:
        return None
    del cells
    columns = [*numbers[:j], stamps.offsets_us.astype(np.float64), *numbers[j + k :]]
    keep = [(i, n) for i, n in enumerate(names) if n != IGNORE]
    out: dict[str, Any] = _columns([columns[i] for i, _ in keep], keep, units, scale, where)
    _with_file_columns(out, names)
    out[START_TIME] = stamps.start
    return _with_stated_rate(out, list(enumerate(head_lines[:skip], start=1)), where)


#: Files at least this large read with pyarrow's CSV reader when it is installed
#: (:func:`_read_large`): importing it takes about 0.04 s, the time numpy's reader takes
#: for 5 MB, and it parses 3 to 5 times faster.
_ARROW_BYTES = 4 << 20
#: Files at least this large read with pandas' C parser otherwise: about 4 times
#: numpy's speed, worth importing pandas for (0.12 s) from about 16 MB, a record of
#: 300,000 rows; once pandas is imported, from :data:`_HEAD_BYTES` on.
_LARGE_BYTES = 16 << 20


def _read_large(path: Path, delimiter: str | None, skip: int, width: int) -> list[NDArray] | None:
    """The rows of numbers of a large plain file, read by a compiled CSV parser
    (:func:`bayestribo.io.bulk_text.read_numbers`: pyarrow's, else pandas'), or None to
    leave the file to :func:`numpy.loadtxt`: a small file, or any row that is not
    ``width`` numbers (numpy's reader, or the line-by-line one, then reads it or names
    the line).
    """
    size = path.stat().st_size
    if delimiter is not None and bulk_text.arrow_available():
        if sys.modules.get("pyarrow") is None and size < _ARROW_BYTES:
            return None
        data = bulk_text.read_numbers(path, delimiter, skip, width, parser="pyarrow")
        if data is not None or sys.modules.get("pyarrow") is not None:
            return data  # read, or refused by pyarrow (and so by pandas)
        # pyarrow is there but does not import (a broken install): pandas' parser
    if "pandas" not in sys.modules and size < _LARGE_BYTES:
        return None
    return bulk_text.read_numbers(path, delimiter, skip, width, parser="pandas")


def read_text(
    path: str | Path,
    *,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    skip_rows: int = 0,
    encoding: str | None = None,
) -> dict[str, Any]:
    """Read a delimited text file of samples.

    Parameters
    ----------
    path : str or Path
        The text file (UTF-8).
    columns : list of str, optional
        One name per column, in file order: a canonical name, a quantity with its unit
        (``time_ms``, ``displacement_um``, ...) or ``"ignore"``. Without it the file
        must hold a header row of such names above its rows of numbers; a preamble
        above the header (``Key: value`` lines of the software that wrote it) is
        skipped. With it, the lines above the first row of numbers are skipped. Without
        a ``time_s`` column the run's time comes from its sample rate
        (:func:`bayestribo.read_run`'s ``sample_rate_Hz``).
    scale : mapping, optional
        Factor per canonical column converting the file's unit into the canonical
        unit (s, m, m/s), e.g. ``{"time_s": 1e-3, "displacement_m": 1e-6}``.
    delimiter : str, optional
        Column separator; by default the first of ``,``, ``;``, tab or white space that
        splits the rows of numbers into as many numbers as the header names.
    decimal : {".", ","}, optional
        Decimal mark: ``","`` reads decimal commas; otherwise a point, or a comma when
        the rows of numbers, split by a delimiter other than a comma, hold decimal
        commas and no point (a sensor-software export: ``0,01;0,4123``).
    skip_rows : int
        Lines to skip at the top before the header or data (an instrument preamble).
    encoding : str, optional
        The text encoding; default UTF-8, and Windows-1252 (said with a
        :class:`~bayestribo.errors.ReadingWarning`) for a file that is not UTF-8.

    Returns
    -------
    dict
        Arrays by canonical column name (time first); and, when a line above the header
        (or above the first row of numbers) states the sample rate (``Sample rate: 1
        kHz``, ``dt = 1 ms``, see :func:`stated_rate`), a :class:`StatedRate` under
        :data:`PREAMBLE_RATE`, which :func:`bayestribo.read_run` takes out: the time of
        a file without a time column then comes from it, and a time column must agree
        with it.

    Raises
    ------
    RunFormatError
        Naming the file, the line and the column, for text that is not UTF-8, an
        unknown header name, a row with the wrong number of fields, a field that is not
        a number, a header separated by blanks that splits into the columns in more
        than one way, or preamble lines that state different sample rates.
    """
    path = Path(path)
    where = str(path)
    _check_options(decimal, delimiter, skip_rows, where)
    if columns is None and skip_rows == 0:
        with path.open("rb") as fh:
            head = fh.read(_HEAD_BYTES)
        # the words the readings below look for, in the lines a header can be in
        probe = head[:_PROBE_BYTES].lower()
        if b"count" in probe or b"tick" in probe:
            columns, scale = _encoder_counts(head, where, scale, delimiter, encoding)
        if columns is None and b"gyr" in probe:
            columns = _gyroscope(path, where, delimiter, encoding, decimal)
        if columns is None and b"#" in probe:
            columns = _comment_header(head, where, delimiter, encoding)
    if skip_rows == 0 and decimal != ",":
        streamed = _read_streamed(path, where, columns, scale, delimiter, encoding, decimal)
        if streamed is not None:
            return streamed
    text = decode(path.read_bytes(), encoding, where)
    return parse_lines(
        text.splitlines(),
        where,
        columns=columns,
        scale=scale,
        delimiter=delimiter,
        decimal=decimal,
        skip_rows=skip_rows,
    )


#: Bytes at the head of a text file in which a header's words are looked for.
_PROBE_BYTES = 8192


def _encoder_counts(
    head: bytes,
    where: str,
    scale: Mapping[str, float] | None,
    delimiter: str | None,
    encoding: str | None,
) -> tuple[list[str] | None, Mapping[str, float] | None]:
    """The ``columns=`` and ``scale=`` that read a column of an encoder's counts as an
    angle, where the lines above the rows state the counts per revolution
    (:mod:`bayestribo.io.encoder_counts`, said); else no columns and ``scale`` as given.
    ``head`` is the file's first bytes."""
    try:
        text = head.decode(encoding or "utf-8-sig")
    except (UnicodeDecodeError, LookupError):
        return None, scale
    found = encoder_columns(text.splitlines()[:PREAMBLE_LINES], delimiter)
    if found is None:
        return None, scale
    names, factor, reading = found
    warn(f"{where}: {reading.note()}", ReadingWarning)
    given = dict(scale or {})
    given["angle_rad"] = factor * float(given.get("angle_rad", 1.0))
    return names, given


def _comment_header(
    head: bytes, where: str, delimiter: str | None, encoding: str | None
) -> list[str] | None:
    """The ``columns=`` a comment line right above the rows gives a file without a
    header row (:mod:`bayestribo.io.comment_header`, said), or None; ``head`` is the
    file's first bytes."""
    try:
        text = head.decode(encoding or "utf-8-sig")
    except (UnicodeDecodeError, LookupError):
        return None
    found = comment_header(text.splitlines()[:PREAMBLE_LINES], delimiter)
    if found is None:
        return None
    names, line = found
    warn(f"{where}: the column names read from comment line {line}: {names}", ReadingWarning)
    return names


def _gyroscope(
    path: Path, where: str, delimiter: str | None, encoding: str | None, decimal: str | None
) -> list[str] | None:
    """The ``columns=`` that read a gyroscope export's swinging axis as the angular
    velocity (:mod:`bayestribo.io.gyroscope`, said), or None."""
    try:
        lines = decode(path.read_bytes(), encoding, where, say=False).splitlines()
    except RunFormatError:
        return None
    found = header_and_rows(lines, delimiter, decimal)
    if found is None:
        return None
    reading = gyroscope_columns(*found)
    if reading is None:
        return None
    warn(f"{where}: {reading.note()}", ReadingWarning)
    return reading.columns


def _check_options(decimal: str | None, delimiter: str | None, skip_rows: int, where: str) -> None:
    if decimal not in (None, ".", ","):
        raise RunFormatError(f"decimal: expected '.' or ',', got {decimal!r}", where)
    if decimal == "," and delimiter == ",":
        raise RunFormatError("delimiter and decimal mark cannot both be ','", where)
    if not isinstance(skip_rows, int) or isinstance(skip_rows, bool) or skip_rows < 0:
        raise RunFormatError(f"skip_rows: expected an integer >= 0, got {skip_rows!r}", where)


def parse_lines(
    all_lines: Sequence[str],
    where: str,
    *,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    skip_rows: int = 0,
) -> dict[str, Any]:
    """Samples from the lines of a delimited text (the body of :func:`read_text`).

    Parameters
    ----------
    all_lines : sequence of str
        The file's lines, without line ends.
    where : str
        The file, for messages.
    columns, scale, delimiter, decimal, skip_rows
        As for :func:`read_text`.

    Returns
    -------
    dict
        As :func:`read_text`: arrays by canonical column name (time first), and the
        preamble's :class:`StatedRate` under :data:`PREAMBLE_RATE` when it states one.

    Raises
    ------
    RunFormatError
        As :func:`read_text`.
    """
    _check_options(decimal, delimiter, skip_rows, where)
    if skip_rows == 0:
        export = detect_export(all_lines[:PREAMBLE_LINES], where)
        if export is not None:
            return read_export(
                all_lines,
                export,
                columns=columns,
                scale=scale,
                delimiter=delimiter,
                decimal=None if decimal in (None, ".") else decimal,
                where=where,
            )
    lines = without_trailing_delimiter(
        [
            (number, line)
            for number, line in enumerate(all_lines[skip_rows:], start=skip_rows + 1)
            if line.strip() and not line.lstrip().startswith("#")
        ]
    )
    # a column of dates and times: microseconds from the first sample (time_us)
    stamped = stamped_lines(lines, delimiter, where) if columns is None else None
    if stamped is not None:
        lines = stamped.lines
    grouped = decimal == ","
    names, units, header_lines, delimiter, decimal = _layout(
        lines, where, columns, delimiter, decimal
    )
    rows = without_repeated_header(lines[header_lines:], lines[:header_lines], where)
    rows = without_footer(rows, all_lines, delimiter, where)
    if not rows:
        raise RunFormatError("the file holds a header but no data rows", where)

    keep = [(i, n) for i, n in enumerate(names) if n != IGNORE]
    width = len(names)
    data = _parse_block(rows, delimiter, width, [i for i, _ in keep], decimal)
    if data is None:
        data = _parse_rows(rows, delimiter, decimal, names, keep, where, grouped)
        data = _trim_missing(data, rows, keep, where)

    out: dict[str, Any] = _columns(data, keep, units, scale, where)
    _with_file_columns(out, names)
    if stamped is not None:
        out[START_TIME] = stamped.start
    above = enumerate(all_lines[skip_rows : rows[0][0] - 1], start=skip_rows + 1)
    return _with_stated_rate(out, list(above), where)


#: The key under which :func:`read_text` returns, beside the columns of a file that
#: holds several acceleration axes, the canonical names of its columns in file order
#: (a list): :func:`bayestribo.read_run` names the ``columns=`` that read one axis.
FILE_COLUMNS = "file_columns"


def _with_file_columns(out: dict[str, Any], names: Sequence[str]) -> None:
    """Add the file's column names (:data:`FILE_COLUMNS`) to ``out`` when it holds
    several acceleration axes."""
    if sum(name in ACCELERATION_AXES.values() for name in names) > 1:
        out[FILE_COLUMNS] = list(names)


def _with_stated_rate(
    out: dict[str, Any], above: Sequence[tuple[int, str]], where: str
) -> dict[str, Any]:
    """``out`` with the sample rate the lines above the rows of numbers state (a
    :class:`StatedRate` under :data:`PREAMBLE_RATE`), when they state one."""
    rate = stated_rate(above, where)
    if rate is not None:
        out[PREAMBLE_RATE] = rate
    return out


def write_csv(signals: Mapping[str, NDArray], path: str | Path) -> Path:
    """Write signals as a canonical CSV (header row, comma separated, shortest exact repr).

    Every value is written with Python's shortest representation that reads back to
    the same float64, so reading the file gives back bit-identical arrays.

    Parameters
    ----------
    signals : mapping
        Arrays by canonical column name, written in the canonical column order.
    path : str or Path
        The ``.csv`` file to write.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    names = [name for name in COLUMNS if signals.get(name) is not None]
    columns = [np.asarray(signals[name], dtype=np.float64).tolist() for name in names]
    body = "\n".join(",".join(map(repr, row)) for row in zip(*columns, strict=True))
    write_text(path, ",".join(names) + "\n" + body + "\n")
    return path
