"""A rotary encoder's raw counts read as an angle, with the counts per revolution the
file states.

An encoder's logger writes the position as whole counts (``counts``, ``ticks``,
``Position (counts)``) and states its resolution once above the rows (``# counts_per_rev:
8192``, ``CPR = 4096``, ``Resolution: 2000 pulses/rev``). Such a column is an angle of
2π/N rad per count. :func:`encoder_reading` finds the column and the statement; without
a statement :func:`encoder_advice` names the options that read the column once N is
known.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "COUNT_NAMES",
    "EncoderReading",
    "counts_per_rev",
    "encoder_advice",
    "encoder_columns",
    "encoder_reading",
    "header_and_rows",
]

#: Column names (lower case, a unit in brackets taken off) of an encoder's raw counts.
COUNT_NAMES: frozenset[str] = frozenset(
    {
        "counts",
        "count",
        "encoder",
        "encoder counts",
        "encoder count",
        "encoder_counts",
        "ticks",
        "pulses",
        "position",
        "angle",
        "position_counts",
        "angle_counts",
    }
)

#: The unit in brackets (or after ``_``) that makes a position or an angle a count.
_COUNT_UNITS = ("counts", "count", "cts", "ticks", "pulses", "inc", "increments")

#: A statement of the counts per revolution: ``counts_per_rev: 8192``, ``CPR = 4096``,
#: ``Resolution: 2000 pulses/rev``, ``counts per revolution 1024``, ``PPR: 500 (x4)``.
_STATEMENT = re.compile(
    r"(?:(?:counts?|pulses|ticks|increments|lines)[\s_/-]*(?:per|/)[\s_]*"
    r"(?:rev(?:olution)?s?|turns?)|\bcpr\b)"
    r"\s*(?:\([^)]*\))?\s*[:=,\t ]\s*(?P<n>\d+(?:\.\d*)?)"
    r"|(?P<m>\d+(?:\.\d*)?)\s*(?:counts?|pulses|ticks|cpr)\s*(?:/|per)\s*rev",
    re.IGNORECASE,
)


@dataclass(frozen=True)
class EncoderReading:
    """How a column of counts is read as an angle.

    Attributes
    ----------
    column : int
        The column's position in the file (from 0).
    name : str
        The column's name as written.
    counts_per_rev : float
        Counts in one revolution N.
    line : int
        The line stating N (from 1).
    text : str
        That line, stripped.
    """

    column: int
    name: str
    counts_per_rev: float
    line: int
    text: str

    @property
    def radians_per_count(self) -> float:
        """The angle of one count, 2π/N [rad]."""
        return 2.0 * math.pi / self.counts_per_rev

    def note(self) -> str:
        """One sentence saying how the column is read."""
        return (
            f"column {self.name!r} read as an encoder's angle, 2π/{self.counts_per_rev:g} = "
            f"{self.radians_per_count:.6g} rad per count (line {self.line}: {self.text!r}); "
            "give columns=[...] to read it otherwise"
        )


def _count_column(name: str) -> bool:
    """True for a column name of raw counts (``counts``, ``Position (counts)``)."""
    text = name.strip().strip("\"'").lower()
    bracket = re.match(r"^(?P<word>.*?)\s*[\(\[](?P<unit>[^\)\]]*)[\)\]]\s*$", text)
    if bracket:
        word, unit = bracket.group("word").strip(), bracket.group("unit").strip()
        return unit in _COUNT_UNITS and (word in COUNT_NAMES or word == "")
    if text in ("position", "angle", "encoder"):
        return False  # a position or an angle without a unit is not a count
    if text in COUNT_NAMES:
        return True
    word, _, unit = text.rpartition("_")
    return bool(word) and unit in _COUNT_UNITS and word in COUNT_NAMES


def counts_per_rev(lines: Sequence[tuple[int, str]]) -> tuple[float, int, str] | None:
    """The counts per revolution a file's lines state, its line and text, or None.

    Parameters
    ----------
    lines : sequence of (int, str)
        The lines above the rows of numbers, numbered from 1 (``#`` comment lines
        included).

    Returns
    -------
    (N, line, text) or None
        None when no line states it, or when two lines state different numbers.
    """
    found: tuple[float, int, str] | None = None
    for number, line in lines:
        text = line.strip().lstrip("#").strip()
        match = _STATEMENT.search(text)
        if match is None:
            continue
        n = float(match.group("n") or match.group("m"))
        if not n >= 1:
            continue
        if found is not None and found[0] != n:
            return None
        found = found or (n, number, text)
    return found


def encoder_reading(
    names: Sequence[str], lines: Sequence[tuple[int, str]]
) -> EncoderReading | None:
    """The column of counts among a header's names, read with the stated resolution.

    Parameters
    ----------
    names : sequence of str
        The header's column names, as written.
    lines : sequence of (int, str)
        The lines above the rows of numbers, numbered from 1.

    Returns
    -------
    EncoderReading or None
        None without exactly one column of counts, or without a statement of N.
    """
    columns = [i for i, name in enumerate(names) if _count_column(name)]
    if len(columns) != 1:
        return None
    stated = counts_per_rev(lines)
    if stated is None:
        return None
    n, line, text = stated
    return EncoderReading(columns[0], names[columns[0]], n, line, text)


def encoder_advice(names: Sequence[str], canonical: Sequence[str | None]) -> str:
    """The options that read a column of counts as an angle, "" for no such column.

    Parameters
    ----------
    names : sequence of str
        The header's column names, as written.
    canonical : sequence of str or None
        Each column's canonical name where it has one (``time_s``), else None.

    Returns
    -------
    str
        A sentence naming ``--columns ... angle_rad ...`` and ``--scale angle_rad=2π/N``.
    """
    columns = [i for i, name in enumerate(names) if _count_column(name)]
    if len(columns) != 1:
        return ""
    roles = [
        "angle_rad" if i == columns[0] else (canonical[i] or "ignore") for i in range(len(names))
    ]
    return (
        f"{names[columns[0]]!r} holds an encoder's counts: state its counts per revolution N "
        "in a line above the header ('# counts_per_rev: N'), or read it as an angle with "
        f"'--columns {' '.join(roles)} --scale angle_rad=X', X = 2π/N rad per count "
        "(for instance 0.000766990393942821 for N = 8192)"
    )


def _header_names(line: str, delimiter: str | None) -> list[str]:
    """A header line's names: split by ``delimiter``, else by the first of ``,``, ``;``
    and a tab it holds, else by blanks."""
    if delimiter is None:
        delimiter = next((d for d in (",", ";", "\t") if d in line), None)
    fields = line.split(delimiter) if delimiter is not None else line.split()
    return [f.strip().strip("\"'").strip() for f in fields]


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def encoder_columns(
    lines: Sequence[str], delimiter: str | None
) -> tuple[list[str], float, EncoderReading] | None:
    """The ``columns=`` and the scale that read a file's column of counts as an angle.

    Parameters
    ----------
    lines : sequence of str
        The file's first lines, without line ends.
    delimiter : str or None
        The delimiter given, or None (guessed from the header line).

    Returns
    -------
    (columns, factor, reading) or None
        The columns in file order (``angle_rad`` for the counts, each other column's
        name as written where it names a quantity, else ``ignore``), the factor to
        radians, 2π/N, and the reading (:class:`EncoderReading`); None when the first
        line that is not a comment, above the first row of numbers, holds no single
        column of counts or no line above the rows states N.
    """
    from bayestribo.io.columns import parse_column

    above: list[tuple[int, str]] = []
    header: str | None = None
    for number, line in enumerate(lines, start=1):
        text = line.strip().lstrip("\ufeff")
        if not text:
            continue
        if text.startswith("#"):
            above.append((number, text))
            continue
        fields = _header_names(text, delimiter)
        if fields and all(_number(f) for f in fields if f):
            break
        above.append((number, text))
        header = text
    if header is None:
        return None
    names = _header_names(header, delimiter)
    reading = encoder_reading(names, above)
    if reading is None:
        return None

    def role(i: int, name: str) -> str:
        if i == reading.column:
            return "angle_rad"
        try:
            return name if parse_column(name) is not None else "ignore"
        except ValueError:
            return "ignore"

    return [role(i, n) for i, n in enumerate(names)], reading.radians_per_count, reading


def header_and_rows(
    lines: Sequence[str], delimiter: str | None, decimal: str | None = None
) -> tuple[list[str], np.ndarray] | None:
    """A plain table's header names and its rows of numbers, or None.

    The header is the last line that is not a comment above the first row of numbers;
    rows that do not hold as many numbers are NaN.

    Parameters
    ----------
    lines : sequence of str
        The file's lines, without line ends.
    delimiter : str or None
        The delimiter given, or None (guessed from the header line).
    decimal : str or None
        The decimal mark (``,`` read as a point).
    """
    header: str | None = None
    start = None
    for number, line in enumerate(lines):
        text = line.strip().lstrip("\ufeff")
        if not text or text.startswith("#"):
            continue
        fields = _header_names(text, delimiter)
        if fields and all(_number(_point(f, decimal)) for f in fields if f):
            start = number
            break
        header = text
    if header is None or start is None:
        return None
    names = _header_names(header, delimiter)
    rows = np.full((len(lines) - start, len(names)), np.nan)
    count = 0
    for line in lines[start:]:
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = _header_names(text, delimiter)
        if len(fields) != len(names):
            continue
        try:
            rows[count] = [float(_point(f, decimal)) for f in fields]
        except ValueError:
            continue
        count += 1
    return names, rows[:count]


def _point(text: str, decimal: str | None) -> str:
    return text.replace(",", ".") if decimal == "," else text
