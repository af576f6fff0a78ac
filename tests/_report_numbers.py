"""The numbers of a rendered report against the JSON they come from.

A report shows a value with its interval as one cell, ``0.02360 [0.02340, 0.02380]``,
in the digits the interval supports (:func:`bayestribo.summary.interval_text`, the digit
rule). :func:`interval_cells` reads every such cell of a report's tables;
:func:`json_intervals` writes every (centre, low, high) triple a JSON output of ``fit``
or ``campaign`` holds by the same rule. A cell that is none of those is a number the
report made up, rounded its own way or took from somewhere else.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Iterator, Mapping
from html.parser import HTMLParser
from statistics import NormalDist
from typing import Any

from bayestribo.summary import interval_text

__all__ = [
    "BOUND",
    "INTERVAL",
    "interval_cells",
    "json_intervals",
    "section",
    "table_cells",
    "unmatched",
]

_NUMBER = r"-?(?:\d+(?:\.\d*)?|\.\d+)(?:e[+-]?\d+)?"
#: A cell that is a value with its interval, in one of the digit rule's forms.
INTERVAL = re.compile(
    rf"^(?:{_NUMBER} \[{_NUMBER}, {_NUMBER}\]|0 \(at the bound\) \[0, {_NUMBER}\]|< 1e-9)$"
)


#: A cell that shows a quantity the data do not constrain as a bound: its number is the
#: upper end of its interval in two digits.
BOUND = re.compile(rf"^not constrained by the data: \S+ < ({_NUMBER}) ")


class _Tables(HTMLParser):
    """Every table cell's text with the heading of its column (the table's first row);
    a cell spanning rows (a grouped index) holds its column in the rows below it."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: list[tuple[str, str, str]] = []
        self._cell: list[str] | None = None
        self._columns: list[str] = []
        self._row: dict[int, str] = {}
        self._spans: dict[int, int] = {}  # column -> rows it is still held in
        self._span = 1
        self._first = False

    def _free(self) -> int:
        """The next column of the row not held by a cell spanning rows above."""
        i = 0
        while i in self._row or self._spans.get(i, 0) > 0:
            i += 1
        return i

    def handle_starttag(self, tag: str, attrs: Any) -> None:
        if tag == "table":
            self._columns, self._first, self._spans = [], True, {}
        elif tag == "tr":
            self._row = {}
        elif tag in ("td", "th"):
            self._cell = []
            self._span = int(dict(attrs).get("rowspan") or 1)

    def handle_endtag(self, tag: str) -> None:
        if tag == "tr":
            if self._first:
                self._columns = [self._row[i] for i in sorted(self._row)]
                self._first = False
            self._spans = {i: n - 1 for i, n in self._spans.items() if n > 1}
        elif tag in ("td", "th") and self._cell is not None:
            text = " ".join("".join(self._cell).split())
            i = self._free()
            self._row[i] = text
            if self._span > 1:
                self._spans[i] = self._span
            column = self._columns[i] if i < len(self._columns) else ""
            self.cells.append((text, column, " | ".join(self._columns)))
            self._cell = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)


def section(page: str, title: str) -> str:
    """The HTML of the section whose ``<h2>`` heading holds ``title``, to the next one."""
    heads = [m.start() for m in re.finditer(r"<h2\b", page)]
    start = next(i for i, h in enumerate(heads) if title in page[h : h + 400])
    return page[heads[start] : heads[start + 1] if start + 1 < len(heads) else len(page)]


def table_cells(page: str) -> list[tuple[str, str, str]]:
    """Every table cell of ``page``: its text, the heading of its column and the table's
    first row (its headings)."""
    parser = _Tables()
    parser.feed(page)
    return parser.cells


def interval_cells(page: str) -> list[tuple[str, str, str]]:
    """Every table cell of ``page`` that is a value with its interval: the cell, the
    heading of its column and the table's first row (its headings)."""
    return [c for c in table_cells(page) if INTERVAL.match(c[0]) or BOUND.match(c[0])]


#: A classical estimate's 95 % interval, in standard errors either side (written apart
#: from the package's, so that a wrong factor there is caught).
Z95 = NormalDist().inv_cdf(0.975)


def _triples(node: Any) -> Iterator[tuple[float, float, float]]:
    """Every (centre, low, high) a JSON document holds: a summary (``median`` or ``mean``
    with ``interval``), a row (``X_median``, ``X_low``, ``X_high``, or ``X``, ``X low``,
    ``X high``, or ``X`` with ``X_interval``), a band (lists of ``mean`` and
    ``interval``), a classical estimate (``X`` with its standard error ``X_se``: ±1.96
    of it)."""
    if isinstance(node, Mapping):
        interval = node.get("interval")
        if isinstance(interval, list | tuple) and len(interval) == 2:
            low, high = interval
            if all(isinstance(v, int | float) for v in (low, high)):
                for key in ("median", "mean"):
                    if isinstance(node.get(key), int | float):
                        yield float(node[key]), float(low), float(high)
            elif all(isinstance(v, list) for v in (low, high)) and isinstance(
                node.get("mean"), list
            ):
                for m, lo, hi in zip(node["mean"], low, high, strict=False):
                    if None not in (m, lo, hi):
                        yield float(m), float(lo), float(hi)
        for key, value in node.items():
            # a row: "X_median", "X_low", "X_high"; "X median" or "X", "X low", "X high"
            for sep in ("_", " "):
                stem = str(key).removesuffix(f"{sep}median")
                low, high = node.get(f"{stem}{sep}low"), node.get(f"{stem}{sep}high")
                if all(isinstance(v, int | float) for v in (value, low, high)):
                    yield float(value), float(low), float(high)
            if isinstance(value, int | float) and not isinstance(value, bool):
                # a windowed fit's "zeta" with "zeta_interval"; an estimate's "zeta_se"
                ends = node.get(f"{key}_interval")
                if isinstance(ends, list | tuple) and len(ends) == 2:
                    if all(isinstance(v, int | float) for v in ends):
                        yield float(value), float(ends[0]), float(ends[1])
                se = node.get(f"{key}_se")
                if isinstance(se, int | float) and se > 0:
                    yield float(value), value - Z95 * se, value + Z95 * se
            yield from _triples(value)
    elif isinstance(node, list):
        for item in node:
            yield from _triples(item)


def json_intervals(*documents: Any, scales: Iterable[float] = (1.0,)) -> set[str]:
    """Every triple of ``documents`` as the digit rule writes it: as it is, and held at
    zero below (an energy per cycle), each multiplied by every factor of ``scales`` (a
    report's x_c/A₀)."""
    out = set()
    for doc in documents:
        for centre, low, high in _triples(doc):
            if not all(math.isfinite(v) for v in (centre, low, high)):
                continue
            for s in scales:
                c, lo, hi = centre * s, low * s, high * s
                out.add(interval_text(c, lo, hi))
                out.add(interval_text(max(c, 0.0), max(lo, 0.0), hi))
                out.add(f"< {hi:.2g}")  # a bound's number
    return out


def unmatched(
    page: str,
    *documents: Any,
    scales: Iterable[float] = (1.0,),
    skip_columns: Iterable[str] = (),
    skip_tables: Iterable[str] = (),
) -> list[str]:
    """The value-with-interval cells of ``page`` that no triple of ``documents`` gives,
    each with its column's heading (empty: every such number is the JSON's, in its
    digits). Left out: cells in the columns ``skip_columns`` (a recording not fitted),
    and the tables whose headings hold one of ``skip_tables``."""
    known = json_intervals(*documents, scales=scales)
    skip = set(skip_columns)

    def shown(text: str) -> str:
        bound = BOUND.match(text)
        return f"< {bound.group(1)}" if bound else text

    return [
        f"{text!r} (column {column!r})"
        for text, column, head in interval_cells(page)
        if shown(text) not in known
        and column not in skip
        and not any(t in head for t in skip_tables)
    ]
