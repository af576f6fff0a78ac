"""Time stamps in messages: to a fraction of the record, on any clock.

Six significant digits print a DAQ's time column in Unix seconds (1.4e9 s) as
``1.40672e+09 s`` at every instant of a record: the release, the window's ends and a
drift's start cannot be told apart or given back as ``--window``. :func:`stamp` prints
a time to a ten-thousandth of the span it is read against, and where the clock does not
start near zero, how far into the record it is.
"""

from __future__ import annotations

import math

__all__ = ["stamp"]


def stamp(value: float | None, span: float, origin: float | None = None) -> str:
    """``value`` [s] as text, to a ten-thousandth of ``span`` [s] (six digits at least),
    with ``(x s into the record)`` where ``origin`` (the record's first time) is
    farther from zero than ``span``.

    Examples
    --------
    >>> stamp(50.48621, 0.66, 50.436)
    '50.48621 s (0.05021 s into the record)'
    >>> stamp(1406722069.8071, 49.1, 1406722067.411)
    '1406722069.807 s (2.3961 s into the record)'
    >>> stamp(0.25, 2.0)
    '0.25 s'
    >>> stamp(float("nan"), 2.0)
    'nan s'
    """
    if value is None:
        return "— s"
    if not math.isfinite(value):
        return f"{value} s"
    span = abs(span)
    resolution = 1e-4 * span if span > 0 and math.isfinite(span) else 1e-6
    # at most the 17 digits a double holds
    decades = math.log10(max(abs(value), resolution)) - math.log10(resolution)
    digits = min(17, max(6, math.ceil(decades) + 1))
    # the shortest text that reads back as the value where a double's digits run out
    text = f"{value!r} s" if digits >= 16 else f"{value:.{digits}g} s"
    if origin is not None and abs(origin) > span:
        text += f" ({value - origin:.6g} s into the record)"
    return text
