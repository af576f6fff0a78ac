"""A stop's turning point split in two by the noise on its plateau.

Where an oscillator sticks, its last turning point is the level it stays at. On a
displacement integrated from a velocity alone (a gyroscope's, a geophone's), the noise
at rest makes that plateau wander, and the turning points found up to a little past the
stop may hold it twice: two extrema on the same level a small fraction of a half period
apart. Their interval breaks the half period of the decay and the record was refused
("no two consecutive turning points are half a period apart after them"). The first of
the pair is the stop's turning point; the second is the plateau's noise.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["SPLIT_GAP", "split_stop"]

#: The largest interval, as a fraction of the decay's half period, between the two
#: extrema of a split stop.
SPLIT_GAP = 0.25

#: Intervals before the pair that must be regular (two oscillations).
_BEFORE = 4


def split_stop(times: ArrayLike, values: ArrayLike, level: float) -> bool:
    """True when the last two turning points are one stop's, split by the noise.

    Parameters
    ----------
    times : array_like
        Turning-point times [s], increasing.
    values : array_like
        Their values about the equilibrium [signal unit].
    level : float
        How far apart the pair's values may lie: the noise's reach on the turning
        points [signal unit].

    Returns
    -------
    bool
        True when the record holds at least :data:`_BEFORE` + 2 turning points, the
        last interval is under :data:`SPLIT_GAP` of the median of the
        :data:`_BEFORE` intervals before it, each of which is within 30 % of that
        median, and the last two values are within ``level`` of each other.
    """
    tt = np.asarray(times, dtype=float)
    w = np.asarray(values, dtype=float)
    if tt.size < _BEFORE + 2 or not level > 0:
        return False
    gaps = np.diff(tt)
    before = gaps[-1 - _BEFORE : -1]
    half = float(np.median(before))
    if not half > 0 or np.any(np.abs(before - half) > 0.3 * half):
        return False
    return bool(gaps[-1] < SPLIT_GAP * half and abs(w[-1] - w[-2]) <= level)
