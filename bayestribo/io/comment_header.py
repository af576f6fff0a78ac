"""Column names in the last comment line above the rows (``# t_s  x_um  v_mm_per_s``).

Many programs that write whitespace-separated ``.dat`` files put every line above the
numbers behind ``#``, the column names included: gnuplot's convention, and NumPy's
``savetxt(header=...)``. Such a file has no header row once its comments are left out,
and was refused ("no header row"). :func:`comment_header` reads the last comment line
directly above the first row of numbers as the header when it holds one name per
column, each a quantity with its unit.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

__all__ = ["comment_header"]

#: Separators tried, in order, for a comment line (a blank run last).
_SEPARATORS = (",", ";", "\t")


def _fields(text: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        delimiter = next((d for d in _SEPARATORS if d in text), None)
    parts = text.split(delimiter) if delimiter is not None else text.split()
    return [p.strip().strip("\"'").strip() for p in parts]


def _numbers(text: str, delimiter: str | None) -> int | None:
    """How many numbers a row holds, or None for a line that is not a row of numbers."""
    fields = _fields(text, delimiter)
    try:
        [float(f) for f in fields]
    except ValueError:
        return None
    return len(fields)


def comment_header(lines: Sequence[str], delimiter: str | None) -> tuple[list[str], int] | None:
    """The column names a comment line gives a file without a header row.

    Parameters
    ----------
    lines : sequence of str
        The file's first lines, without line ends.
    delimiter : str or None
        The delimiter given, or None (guessed).

    Returns
    -------
    (names, line) or None
        The names, one per column of the first row of numbers, and the line (from 1)
        that gives them; None when the first line that is not a comment or blank is not
        a row of numbers (a header row is read as usual), or when the comment line right
        above it does not hold one name per column, each a quantity with its unit
        (``t_s``, ``x_um``, ``velocity [mm/s]``) or ``ignore``.
    """
    from bayestribo.io.columns import parse_column

    last: tuple[int, str] | None = None
    for number, line in enumerate(lines, start=1):
        text = line.strip().lstrip("\ufeff").strip()
        if not text:
            continue
        if text.startswith("#"):
            last = (number, re.sub(r"^#+", "", text).strip())
            continue
        width = _numbers(text, delimiter)
        if width is None or last is None or not last[1]:
            return None
        names = _fields(last[1], delimiter)
        if len(names) != width:
            return None
        for name in names:
            if name == "ignore":
                continue
            try:
                if parse_column(name) is None:
                    return None
            except ValueError:
                return None
        return names, last[0]
    return None
