"""A footer of labelled values below a text table: a program's summary of the record.

Data-acquisition and spreadsheet exports often close a table with a blank line and a
few lines of statistics, each a label and its values (``Mean,0.0123,0.0001`` then
``Std,0.3,2.1``). Those lines are no samples: they are left out with a
:class:`~bayestribo.errors.ReadingWarning` naming them and their labels. Only a block
that a blank line sets off from the table, at the end of the file, of at most
:data:`MOST_FOOTER_LINES` lines, each of whose first field is a label (not a number),
is taken so: a line that is not a number inside the table is an error naming it, as
before.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning

__all__ = ["MOST_FOOTER_LINES", "without_footer"]

#: Most lines a footer may hold (a summary's statistics, not a second table).
MOST_FOOTER_LINES = 20

#: A field that reads as a number in either decimal mark (a label does not).
_NUMBER = re.compile(r"^[+-]?(\d[\d.,]*|[.,]\d+)([eE][+-]?\d+)?$")


def _first_field(line: str, delimiter: str | None) -> str:
    text = line.strip()
    first = text.split(delimiter, 1)[0] if delimiter is not None else (text.split() or [""])[0]
    return first.strip().strip('"').strip("'").strip()


def without_footer(
    rows: Sequence[tuple[int, str]],
    all_lines: Sequence[str],
    delimiter: str | None,
    where: str,
) -> list[tuple[int, str]]:
    """The rows without a footer of labelled values that ends the file.

    Parameters
    ----------
    rows : sequence of (int, str)
        Line numbers (1-based, in ``all_lines``) and lines of the table's rows, blank
        and comment lines left out.
    all_lines : sequence of str
        Every line of the file.
    delimiter : str or None
        The column separator (None: blanks).
    where : str
        The file, for the warning.

    Returns
    -------
    list of (int, str)
        ``rows`` without the footer (the same rows when there is none).
    """
    rows = list(rows)
    if len(rows) < 2:
        return rows
    # the last break in the line numbers that a blank line makes, within the footer's
    # reach of the end
    for k in range(len(rows) - 1, max(0, len(rows) - 1 - MOST_FOOTER_LINES), -1):
        before, after = rows[k - 1][0], rows[k][0]
        if after - before < 2:
            continue
        gap = all_lines[before : after - 1]  # lines before+1 .. after-1 (1-based)
        if not any(not line.strip() for line in gap):
            continue
        footer = rows[k:]
        labels = [_first_field(line, delimiter) for _, line in footer]
        if not all(label and not _NUMBER.match(label) for label in labels):
            return rows
        if k < 2:
            return rows
        shown = ", ".join(repr(label[:20]) for label in labels[:4]) + (
            " ..." if len(labels) > 4 else ""
        )
        warn(
            f"{where}: line(s) {footer[0][0]} to {footer[-1][0]}, below a blank line that "
            f"ends the table, are a footer of labelled values ({shown}): a program's summary "
            "of the record, not samples; left out",
            ReadingWarning,
        )
        return rows[:k]
    return rows
