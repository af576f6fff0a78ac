"""Time stamps: a regular clock, a jittery one, or a gap.

An analysis of a free decay needs samples on a regular clock. Time stamps that
scatter about a regular grid (a scope's or a logger's time column, stamped with a
few microseconds of jitter) are such a clock: each stamp is off by a small, bounded
amount and the grid goes on. A missing sample, a restart of the clock or a resampled
segment is not: the stamps leave the grid by a whole step or more. The two are told
apart by the residuals of the stamps from the best regular grid ``t0 + i h`` (least
squares): jitter keeps every residual within a quarter of a step, a gap puts the
residuals on either side of it a whole step apart (about half a step each).

The samples of a jittered record are taken as the regular grid's
(:func:`bayestribo.signal.decay.check_time` returns it). Where the clock is regular
and the stamps jittered (a time column written by software, or rounded), the grid is
exact; where the samples themselves were taken off the grid, the energy
``E = (y² + y'²)/2`` of a sample read at ``τ + e`` differs from the energy at ``τ`` by
only ``E' e``: E' is the dissipated power, not the oscillation's (the displacement's
error ``y' e`` and the velocity's ``-y e`` cancel in E to first order). On the grid,
±2 µs of jitter on a simulated 10 kHz record of the paper's rig leaves the fit that of
the record without jitter (``tests/test_signal_digitiser.py``). The jitter is recorded
(:attr:`bayestribo.signal.decay.NoiseLevels.timing_jitter_s`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["JITTER_LIMIT", "Clock", "clock"]

#: Largest residual from the regular grid, in steps, that is jitter rather than a gap.
JITTER_LIMIT = 0.25


@dataclass(frozen=True)
class Clock:
    """How regular the time stamps are.

    Attributes
    ----------
    step : float
        The grid's step h [s] (least squares).
    jitter : float
        Standard deviation of the stamps about the grid [s] (0 for a regular clock).
    worst : float
        Largest |residual| in steps.
    first_off : int
        The first sample whose residual is beyond :data:`JITTER_LIMIT` steps (-1 when
        none is: the clock is regular or jittered).
    intercept : float
        The grid's first time t0 [s].
    """

    step: float
    jitter: float
    worst: float
    first_off: int

    intercept: float = 0.0

    def grid(self, n: int) -> np.ndarray:
        """The regular grid ``t0 + i h`` of ``n`` samples [s]."""
        return self.intercept + np.arange(n, dtype=float) * self.step

    @property
    def regular(self) -> bool:
        """True when every stamp is within :data:`JITTER_LIMIT` steps of the grid."""
        return self.first_off < 0


def clock(t: ArrayLike) -> Clock:
    """The regular grid that fits the time stamps, and how far they are from it.

    Parameters
    ----------
    t : array_like
        Strictly increasing time stamps [s] (at least 2).

    Returns
    -------
    Clock

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000) * 1e-4
    >>> clock(t + np.random.default_rng(0).uniform(-2e-6, 2e-6, 1000)).regular
    True
    >>> clock(np.delete(t, 500)).regular  # a missing sample
    False
    """
    t = np.asarray(t, dtype=float)
    i = np.arange(t.size, dtype=float)
    # least squares: a gap's step then shows as residuals of about half a step on
    # either side of it, beyond the jitter limit
    slope, intercept = np.polyfit(i, t, 1)
    h = float(slope)
    residual = t - (intercept + i * h)
    worst = float(np.max(np.abs(residual)) / h)
    off = np.flatnonzero(np.abs(residual) > JITTER_LIMIT * h)
    return Clock(
        step=h,
        jitter=float(np.std(residual)),
        worst=worst,
        first_off=int(off[0]) if off.size else -1,
        intercept=float(intercept),
    )
