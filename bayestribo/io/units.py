"""Units of length and time as recording software spells them, and their SI factors.

One table for every reader: a text header (``Position (in)``, ``time_msec``), a UFF
record's axis label, a TDMS channel's ``unit_string`` and an instrument's export all
read a unit through :func:`length_unit` or :data:`TIMES`, so a spelling one reader
knows, every reader knows.
"""

from __future__ import annotations

__all__ = ["INCH_M", "LENGTHS", "PER_SECOND", "TIMES", "length_unit"]

#: The inch [m] (international yard and pound agreement, 1959).
INCH_M = 0.0254

#: Lengths a displacement is written in and their factor to metres: SI prefixes, the
#: micron, and the inch and the mil (a thousandth of an inch) of US vibration
#: instruments. Keys are as written; :func:`length_unit` also tries them in lower case.
LENGTHS: dict[str, float] = {
    "m": 1.0,
    "cm": 1e-2,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "micron": 1e-6,
    "microns": 1e-6,
    "nm": 1e-9,
    "in": INCH_M,
    "inch": INCH_M,
    "inches": INCH_M,
    "mil": 1e-3 * INCH_M,
    "mils": 1e-3 * INCH_M,
}

#: Spellings of "per second" after a length (``mm/s``, ``mm_per_s``, ``mm/sec``).
PER_SECOND: tuple[str, ...] = ("_per_s", "/s", "/sec", "_per_sec")

#: Velocity units written as one word, and their factor to m/s (``ips``: inches per
#: second, the unit of US vibration meters).
_VELOCITY_WORDS: dict[str, float] = {"ips": INCH_M}

#: Times a time column or axis is written in and their factor to seconds (lower case).
TIMES: dict[str, float] = {
    **dict.fromkeys(("s", "sec", "secs", "second", "seconds"), 1.0),
    **dict.fromkeys(("ms", "msec", "millisecond", "milliseconds"), 1e-3),
    **dict.fromkeys(("us", "µs", "usec", "µsec", "microsecond", "microseconds"), 1e-6),
    "ns": 1e-9,
    **dict.fromkeys(("min", "minute", "minutes"), 60.0),
}


def length_unit(label: str) -> tuple[float, bool] | None:
    """The factor to SI of a length or a velocity unit, and whether it is per second.

    Parameters
    ----------
    label : str
        A unit as written: ``"mm"``, ``"µm"``, ``"in/s"``, ``"mm_per_sec"``, ``"ips"``.
        The Greek letter mu and the micro sign are the same unit; spaces are ignored.

    Returns
    -------
    (factor, per_second) or None
        ``factor`` to metres (a length) or to m/s (``per_second`` True); None for a
        label that is no known length or velocity unit.
    """
    text = label.strip().replace("\u03bc", "\u00b5").replace(" ", "")
    if text.lower() in _VELOCITY_WORDS:
        return _VELOCITY_WORDS[text.lower()], True
    per_second = False
    for per in PER_SECOND:
        if text.lower().endswith(per):
            text, per_second = text[: -len(per)], True
            break
    factor = LENGTHS.get(text, LENGTHS.get(text.lower()))
    return None if factor is None else (factor, per_second)
