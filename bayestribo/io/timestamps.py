"""Time stamps: a column of dates and times of day, as seconds from its first sample.

Data loggers, microcontroller sketches, phone sensor apps and some acquisition
software write each sample's absolute time instead of seconds: ISO 8601
(``2026-11-30T09:15:02.120``, ``2026-11-30 09:15:02.120Z``, ``...+01:00``), a time of
day alone (``09:15:02.120``, or ``09:15:02:120`` as Physics Toolbox writes it), or a
date in the day-first or month-first order (``30/11/2026 09:15:02,120``).
:func:`parse_stamps` turns such cells into integer microseconds from the first one.

A column of a million cells that share one layout (zero-padded fields, the usual case)
is read column-wise with NumPy from its bytes; a cell of another layout (an hour
without its leading zero, a blank before the zone) is read by a regular expression,
and a cell that is no date and time is refused, naming its row.
"""

from __future__ import annotations

import datetime as _dt
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["STAMP_CELL", "StampError", "Stamps", "looks_like_stamp", "parse_stamps"]

#: A date before the time of day: year first (ISO, ``2026-11-30``, ``2026/11/30``), or
#: day and month before the year (``30/11/2026``, ``11/30/2026``, ``30.11.2026``).
_DATE = (
    r"(?:(?P<y>\d{4})(?P<ys>[-/])(?P<mo>\d{1,2})(?P=ys)(?P<d>\d{1,2})"
    r"|(?P<a>\d{1,2})(?P<as>[-/.])(?P<b>\d{1,2})(?P=as)(?P<ya>\d{4}))"
)
#: A time of day with its fraction of a second (a decimal point or comma), or with
#: milliseconds after a third colon (exactly three digits: ``09:15:02:120``).
_TIME = r"(?P<H>\d{1,2}):(?P<M>\d{2}):(?P<S>\d{2})(?:[.,](?P<f>\d{1,9})|:(?P<ms>\d{3}))?"
#: A time zone: ``Z`` or an offset from UTC, ``+01:00``, ``+0100``, ``-05``.
_ZONE = r"(?P<z>Z|[+-]\d{2}(?::?\d{2})?)"
#: A cell of a time-stamp column.
STAMP_CELL = re.compile(rf"(?:{_DATE}(?:T|\s+))?{_TIME}\s*{_ZONE}?")

_US_PER_S = 1_000_000
_US_PER_DAY = 86_400 * _US_PER_S
#: Date forms: none (a time of day), year first, day or month first (``/`` or ``-``),
#: day first (``.``: dotted dates are written day first).
_NONE, _YMD, _AB, _DOTTED = 0, 1, 2, 3
#: No zone (a sentinel among offsets in minutes).
_NAIVE = np.iinfo(np.int32).min
#: An offset that is no time zone (24 h or more from UTC, or 60 minutes or more).
_NO_ZONE = 24 * 60


class StampError(ValueError):
    """A time-stamp cell that is refused; ``row`` is its index among the cells."""

    def __init__(self, message: str, row: int) -> None:
        super().__init__(message)
        self.row = row


@dataclass(frozen=True)
class Stamps:
    """A column of time stamps read.

    Attributes
    ----------
    offsets_us : ndarray of int64
        Each cell's time after the first cell's [µs] (one clock: UTC where the cells
        carry zones; a day added after each pass through midnight of times of day).
    start : str
        The first cell's date and time (or time of day) as ISO 8601 text, with its zone
        when it has one.
    midnight : list of int
        The rows whose time of day passed midnight since the row before (a day added).
    """

    offsets_us: NDArray[np.int64]
    start: str
    midnight: list[int]


def looks_like_stamp(cell: str) -> bool:
    """True for a cell that is a date and time, or a time of day (``hh:mm:ss``)."""
    return STAMP_CELL.fullmatch(cell.strip().strip('"')) is not None


@dataclass
class _Fields:
    """The fields of the cells, one array each (``form`` the same for every cell)."""

    n1: NDArray[np.int64]  # year (year first) or the first number of the date
    n2: NDArray[np.int64]
    n3: NDArray[np.int64]
    tod_us: NDArray[np.int64]  # time of day [µs]
    zone_min: NDArray[np.int64]  # offset from UTC [min], or _NAIVE


def _form(match: re.Match[str]) -> int:
    if match.group("y") is not None:
        return _YMD
    if match.group("a") is not None:
        return _DOTTED if match.group("as") == "." else _AB
    return _NONE


def _fraction_us(digits: str | None, ms: str | None) -> int:
    """Microseconds of a fraction of a second (rounded to the nearest, half up)."""
    if ms is not None:
        return int(ms) * 1000
    if not digits:
        return 0
    padded = (digits + "0000000")[:7]
    return int(padded[:6]) + (int(padded[6]) >= 5)


def _zone_min(zone: str | None) -> int:
    if zone is None:
        return int(_NAIVE)
    if zone == "Z":
        return 0
    digits = zone[1:].replace(":", "")
    part = int(digits[2:4]) if len(digits) > 2 else 0
    if part >= 60:
        return _NO_ZONE  # refused by parse_stamps
    minutes = int(digits[:2]) * 60 + part
    return -minutes if zone[0] == "-" else minutes


def _one(match: re.Match[str]) -> tuple[int, int, int, int, int]:
    """(n1, n2, n3, time of day [µs], zone [min]) of one matched cell."""
    g = match.group
    if g("y") is not None:
        n = (int(g("y")), int(g("mo")), int(g("d")))
    elif g("a") is not None:
        n = (int(g("a")), int(g("b")), int(g("ya")))
    else:
        n = (0, 0, 0)
    tod = (int(g("H")) * 3600 + int(g("M")) * 60 + int(g("S"))) * _US_PER_S
    seconds_ok = int(g("H")) < 24 and int(g("M")) < 60 and int(g("S")) < 60
    tod = tod + _fraction_us(g("f"), g("ms")) if seconds_ok else -1
    return (*n, tod, _zone_min(g("z")))


def _digits(block: NDArray[np.uint8], start: int, end: int) -> NDArray[np.int64]:
    """The number written by the digits in columns ``start:end`` of a byte block."""
    out = np.zeros(block.shape[0], dtype=np.int64)
    for j in range(start, end):
        out = out * 10 + (block[:, j].astype(np.int64) - 48)
    return out


def _columnwise(
    cells: Sequence[str], template: re.Match[str]
) -> tuple[_Fields, NDArray[np.bool_]] | None:
    """The fields of the cells that share ``template``'s layout up to its seconds (same
    separators, digits in the same places), read column-wise from their bytes, and
    which cells they are; None for cells that are not all ASCII."""
    try:
        raw = np.array(cells, dtype=np.bytes_)
    except UnicodeEncodeError:
        return None
    n, width = raw.size, raw.dtype.itemsize
    block = np.zeros((n, width + 8), dtype=np.uint8)  # room for the zone's look-ahead
    if width:
        block[:, :width] = raw.view(np.uint8).reshape(n, width)
    del raw
    end = template.end("S")
    head = block[:, :end]
    digit = (head >= 48) & (head <= 57)
    first = np.frombuffer(template.string[:end].encode("ascii"), dtype=np.uint8)
    want = (first >= 48) & (first <= 57)
    ok = np.all(np.where(want, digit, head == first), axis=1)
    del head, digit
    # the tail: a fraction (".ddd", ",ddd", ":ddd" as milliseconds), then a zone
    tail = block[:, end:]
    mark = tail[:, 0]
    after = tail[:, 1:]
    run = np.logical_and.accumulate((after >= 48) & (after <= 57), axis=1)
    count = run.sum(axis=1)
    decimal = (mark == ord(".")) | (mark == ord(","))
    millis = mark == ord(":")
    ok &= ~(decimal | millis) | (count > 0)
    ok &= ~millis | (count == 3)
    values = np.where(run[:, :7], after[:, :7].astype(np.int64) - 48, 0)
    frac = values[:, :6] @ (10 ** np.arange(5, -1, -1, dtype=np.int64)) + (values[:, 6] >= 5)
    has = decimal | millis
    pos = np.where(has, 1 + count, 0)
    rest = np.take_along_axis(tail, pos[:, None] + np.arange(7), axis=1)
    r = rest.astype(np.int64)
    isdig = (rest >= 48) & (rest <= 57)
    sign = (rest[:, 0] == ord("+")) | (rest[:, 0] == ord("-"))
    naive = rest[:, 0] == 0
    utc = (rest[:, 0] == ord("Z")) & (rest[:, 1] == 0)
    hh = sign & isdig[:, 1] & isdig[:, 2]
    colon = hh & (rest[:, 3] == ord(":")) & isdig[:, 4] & isdig[:, 5] & (rest[:, 6] == 0)
    packed = hh & isdig[:, 3] & isdig[:, 4] & (rest[:, 5] == 0)
    hours = hh & (rest[:, 3] == 0)
    ok &= naive | utc | colon | packed | hours
    tens = np.where(colon, rest[:, 4], rest[:, 3])  # the tens of the zone's minutes
    ok &= ~(colon | packed) | (tens < ord("6"))
    zone_h = (r[:, 1] - 48) * 10 + (r[:, 2] - 48)
    zone_m = np.where(colon, (r[:, 4] - 48) * 10 + r[:, 5] - 48, 0)
    zone_m = np.where(packed, (r[:, 3] - 48) * 10 + r[:, 4] - 48, zone_m)
    zone = np.where(rest[:, 0] == ord("-"), -1, 1) * (zone_h * 60 + zone_m)
    zone = np.where(naive, _NAIVE, np.where(utc, 0, zone))
    numbers = []
    for name in ("y", "mo", "d") if template.group("y") else ("a", "b", "ya"):
        if template.group(name) is None:
            numbers.append(np.zeros(n, dtype=np.int64))
        else:
            numbers.append(_digits(block, *template.span(name)))
    hour, minute, second = (_digits(block, *template.span(k)) for k in ("H", "M", "S"))
    ok &= (hour < 24) & (minute < 60) & (second < 60)
    tod = (hour * 3600 + minute * 60 + second) * _US_PER_S + np.where(has, frac, 0)
    return _Fields(*numbers, tod, zone), ok


def _fields(cells: Sequence[str]) -> tuple[_Fields, int]:
    """The fields of every cell and their date form; :class:`StampError` for a cell
    that is no date and time or of another form than the first."""
    first = cells[0].strip().strip('"').strip()
    # cells written bare (the first one is) are read as they are: one with a blank or a
    # quote about it is then read one by one, below
    stripped = list(cells) if first == cells[0] else [c.strip().strip('"').strip() for c in cells]
    template = STAMP_CELL.fullmatch(stripped[0])
    if template is None:
        raise StampError(f"{cells[0][:40]!r} is not a date and time", 0)
    form = _form(template)
    found = _columnwise(stripped, template)
    if found is None:
        fields = _Fields(*(np.zeros(len(cells), dtype=np.int64) for _ in range(5)))
        ok = np.zeros(len(cells), dtype=bool)
    else:
        fields, ok = found
    for i in np.flatnonzero(~ok):  # another layout: read one by one, or refused
        match = STAMP_CELL.fullmatch(stripped[i].strip().strip('"').strip())
        if match is None:
            raise StampError(
                f"{cells[i][:40]!r} is not a date and time like the column's first cell "
                f"{stripped[0]!r}",
                int(i),
            )
        if _form(match) != form:
            raise StampError(
                f"{cells[i][:40]!r} is not written like the column's first cell "
                f"{stripped[0]!r} (another form of date)",
                int(i),
            )
        values = _one(match)
        if values[3] < 0:
            raise StampError(f"{cells[i][:40]!r} is no time of day", int(i))
        for array, value in zip(
            (fields.n1, fields.n2, fields.n3, fields.tod_us, fields.zone_min), values, strict=True
        ):
            array[i] = value
    return fields, form


def _date_order(fields: _Fields, form: int, cells: Sequence[str]) -> tuple[NDArray, NDArray]:
    """(month, day) of dates written day or month first: the order a number above 12
    tells, refused when none tells (naming both readings) or both do."""
    a, b = fields.n1, fields.n2
    zero = np.flatnonzero((a < 1) | (b < 1))
    if zero.size:
        i = int(zero[0])
        raise StampError(f"{cells[i].strip()[:40]!r} is no date of the calendar", i)
    if form == _DOTTED:
        return b, a
    big_a, big_b = np.flatnonzero(a > 12), np.flatnonzero(b > 12)
    if big_a.size and big_b.size:
        i, j = int(big_a[0]), int(big_b[0])
        raise StampError(
            f"{cells[i].strip()[:40]!r} is written day first but {cells[j].strip()[:40]!r} "
            "month first; write the dates in one order (YYYY-MM-DD)",
            max(i, j),
        )
    if big_a.size:
        return b, a
    if big_b.size or np.array_equal(a, b):
        return a, b
    i = int(np.flatnonzero(a != b)[0])
    first = str(cells[i]).strip()
    day_first = _reading(int(fields.n3[i]), int(b[i]), int(a[i]))
    month_first = _reading(int(fields.n3[i]), int(a[i]), int(b[i]))
    raise StampError(
        f"{first[:40]!r}: the date reads day first ({day_first}) or month first "
        f"({month_first}), and no day above 12 in the column tells which; write the dates "
        "year first (YYYY-MM-DD)",
        i,
    )


def _reading(year: int, month: int, day: int) -> str:
    """A reading of a date, for a message: ISO text, or that it is none."""
    try:
        return _dt.date(year, month, day).isoformat()
    except ValueError:
        return "no date"


def _days(fields: _Fields, form: int, cells: Sequence[str]) -> NDArray[np.int64]:
    """Days since 1970-01-01 of each cell's date (0 for times of day alone)."""
    if form == _NONE:
        return np.zeros(fields.n1.size, dtype=np.int64)
    if form == _YMD:
        year, month, day = fields.n1, fields.n2, fields.n3
    else:
        month, day = _date_order(fields, form, cells)
        year = fields.n3
    bad = (month < 1) | (month > 12) | (day < 1) | (year < 1)
    months = (year - 1970) * 12 + np.clip(month, 1, 12) - 1
    first = months.astype("datetime64[M]").astype("datetime64[D]").astype(np.int64)
    after = (months + 1).astype("datetime64[M]").astype("datetime64[D]").astype(np.int64)
    bad |= day > after - first
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise StampError(f"{cells[i].strip()[:40]!r} is no date of the calendar", i)
    return first + day - 1


def _start_text(fields: _Fields, form: int, days: int) -> str:
    """The first cell's date and time as ISO 8601 text."""
    seconds, micro = divmod(int(fields.tod_us[0]), _US_PER_S)
    clock = _dt.time(seconds // 3600, seconds // 60 % 60, seconds % 60, micro)
    zone = int(fields.zone_min[0])
    if zone != _NAIVE:
        clock = clock.replace(tzinfo=_dt.timezone(_dt.timedelta(minutes=zone)))
    if form == _NONE:
        return clock.isoformat(timespec="microseconds")
    day = _dt.date(1970, 1, 1) + _dt.timedelta(days=days)
    return _dt.datetime.combine(day, clock).isoformat(timespec="microseconds")


def parse_stamps(cells: Sequence[str]) -> Stamps:
    """Time stamps as microseconds from the first.

    Parameters
    ----------
    cells : sequence of str
        The column's cells (none empty), each a date and time or a time of day
        (:data:`STAMP_CELL`); all with a zone (converted to UTC) or none.

    Returns
    -------
    Stamps
        The offsets [µs] from the first cell, its ISO 8601 text, and the rows after
        which a time of day passed midnight (a day is then added: times of day alone
        only; a backward step of more than 12 h is taken as one).

    Raises
    ------
    StampError
        Naming the cell and its row (``row``): no date and time, another form of date
        than the first cell's, a date that is not in the calendar, dates day first and
        month first, dates that read both ways, a zone on some cells but not others.
    """
    if not cells:
        raise ValueError("cells: expected at least one time stamp")
    fields, form = _fields(cells)
    naive = fields.zone_min == _NAIVE
    if naive.any() and not naive.all():
        i = int(np.flatnonzero(naive != naive[0])[0])
        has = "has no time zone" if naive[i] else "has a time zone"
        raise StampError(
            f"{cells[i].strip()[:40]!r} {has} but {cells[0].strip()[:40]!r} "
            f"{'does' if naive[i] else 'does not'}: the cells are on two clocks",
            i,
        )
    zoned = fields.zone_min[~naive]
    if zoned.size and np.abs(zoned).max() >= 24 * 60:
        i = int(np.flatnonzero(~naive)[np.argmax(np.abs(zoned))])
        raise StampError(
            f"{cells[i].strip()[:40]!r}: its offset is no time zone (hh:mm, less than 24 h "
            "from UTC)",
            i,
        )
    days = _days(fields, form, cells)
    clock = days * _US_PER_DAY + fields.tod_us
    if not naive[0]:
        clock = clock - fields.zone_min * 60 * _US_PER_S
    midnight: list[int] = []
    if form == _NONE and clock.size > 1:
        wrapped = np.diff(clock) < -_US_PER_DAY // 2
        if wrapped.any():
            midnight = [int(i) + 1 for i in np.flatnonzero(wrapped)]
            clock = clock.copy()
            clock[1:] += np.cumsum(wrapped) * _US_PER_DAY
    offsets = clock - clock[0]
    return Stamps(offsets, _start_text(fields, form, int(days[0])), midnight)
