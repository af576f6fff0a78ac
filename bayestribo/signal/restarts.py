"""A clock that restarts within a record: continued where the signal is, split where not.

A logger whose time counter is reset while it goes on sampling (a stamp counted from
each file chunk's start, a microcontroller's counter reset, a scope's segments written
one after another) writes a time column that falls back at the restart and then rises
again on the same step. Nothing about the motion happened there, so the record is one
record: the stamps after the restart continue the ones before it by one sample step.

Whether the samples are contiguous across the restart is read from the signal, not
assumed. On a smooth signal sampled at step h the second difference
``x[k] - 2 x[k-1] + x[k-2]`` is about ``x'' h²``; a sample lost at the restart adds about
``x' h`` to it, which at ω h < 0.1 is more than ten times larger away from the turning
points. The restart is **continued** when, in every recorded channel, the second
difference across it is within :data:`JUMP_FACTOR` times the largest of its
neighbours' (:data:`NEIGHBOURS` on each side) plus the channel's noise. Otherwise the
samples after it are another stretch of time, of unknown distance from the first: the
record is **split** there and only the part before the restart (the release and the
decay from it) is analysed; the message names the part left out, so it can be saved
and fitted as a record of its own.

A lost sample near a turning point (where x' ≈ 0) passes as contiguous: the clock
after it is then late by a sample step, which shifts that one half cycle's duration by
h; the warning says that the continuation assumes one sample step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo._clock import _noise_sd  # robust sd of white noise on a smooth signal

__all__ = ["JUMP_FACTOR", "NEIGHBOURS", "Restart", "continue_clock", "restarts"]

#: Second differences compared on each side of a restart.
NEIGHBOURS = 10
#: A second difference across a restart beyond this many times its neighbours' largest
#: (plus the noise) is a jump of the signal: the samples are not contiguous.
JUMP_FACTOR = 4.0
#: Samples needed on each side of a restart to judge it.
_SIDE = NEIGHBOURS + 3


@dataclass(frozen=True)
class Restart:
    """A fall of the time stamps within a record.

    Attributes
    ----------
    at : int
        The first sample of the new clock (counting from 0 in the record as given).
    before, after : float
        The stamps of samples ``at - 1`` and ``at`` as recorded [s].
    contiguous : bool
        True when the signal goes on smoothly across it (the clock is continued).
    jump : float
        The largest over the channels of the second difference across the restart in
        units of its neighbours' largest plus the noise (<= :data:`JUMP_FACTOR` when
        contiguous).
    """

    at: int
    before: float
    after: float
    contiguous: bool
    jump: float

    def describe(self) -> str:
        """One phrase: where the clock restarted and what was done."""
        where = (
            f"the clock restarts at sample {self.at} (t = {self.after:.6g} s after "
            f"{self.before:.6g} s)"
        )
        if self.contiguous:
            return (
                where + "; the signal goes on smoothly there, so the stamps from it on "
                "continue the ones before by one sample step"
            )
        return (
            where + f"; the signal jumps there ({self.jump:.3g} times its neighbouring "
            "second differences), so the samples from it on are another stretch of time"
        )


def _jump(values: NDArray, k: int) -> float:
    """The second differences across a restart at ``k`` (the two that hold samples of
    both clocks) over their neighbours' largest."""
    d2_at = max(
        abs(values[k] - 2.0 * values[k - 1] + values[k - 2]),
        abs(values[k + 1] - 2.0 * values[k] + values[k - 1]),
    )
    before = np.diff(values[k - 1 - NEIGHBOURS - 1 : k], 2)  # within the old clock
    after = np.diff(values[k : k + NEIGHBOURS + 2], 2)  # within the new one
    scale = float(np.max(np.abs(np.concatenate([before, after]))))
    floor = 4.0 * _noise_sd(values) + float(np.min(np.abs(np.diff(np.unique(values))), initial=0.0))
    reference = scale + floor
    if reference <= 0.0:
        return 0.0 if d2_at == 0.0 else math.inf
    return d2_at / reference


def restarts(
    t: ArrayLike, displacement: ArrayLike | None = None, velocity: ArrayLike | None = None
) -> tuple[Restart, ...]:
    """The restarts of a time column: where the stamps fall back, judged on the signal.

    Parameters
    ----------
    t : array_like
        Finite time stamps [s], increasing but for the restarts.
    displacement, velocity : array_like or None
        The recorded channels, one value per stamp.

    Returns
    -------
    tuple of Restart
        Empty when the stamps never fall; also empty when a fall is not a restart
        (by two steps or less, as a swapped or repeated stamp gives; within
        :data:`NEIGHBOURS` + 3 samples of the record's ends or of another fall; or
        amid irregular steps), where it cannot be judged: the time checks then name it.
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 * _SIDE or not np.all(np.isfinite(t)):
        return ()
    falls = np.flatnonzero(np.diff(t) <= 0.0) + 1
    if falls.size == 0:
        return ()
    edges = np.concatenate([[0], falls, [t.size]])
    if np.any(np.diff(edges) < _SIDE):
        return ()
    # A restart falls back by more than two steps and both clocks tick regularly
    # around it; a swapped or repeated stamp (a fall of one step or none) is not one.
    dt = np.diff(t)
    step = float(np.median(dt[dt > 0.0]))
    for k in falls.tolist():
        if t[k - 1] - t[k] <= 2.0 * step:
            return ()
        around = np.concatenate([dt[k - _SIDE : k - 1], dt[k : k + _SIDE - 1]])
        if np.any(np.abs(around - step) > 0.5 * step):
            return ()
    channels = [
        np.asarray(c, dtype=float)
        for c in (displacement, velocity)
        if c is not None and np.shape(c) == t.shape
    ]
    out = []
    for k in falls.tolist():
        jump = max((_jump(c, k) for c in channels), default=math.inf)
        contiguous = bool(jump <= JUMP_FACTOR)
        out.append(Restart(int(k), float(t[k - 1]), float(t[k]), contiguous, float(jump)))
    return tuple(out)


def continue_clock(
    t: ArrayLike, displacement: ArrayLike | None, velocity: ArrayLike | None
) -> tuple[NDArray, NDArray | None, NDArray | None, tuple[Restart, ...], int | None]:
    """A record whose clock restarts, on one clock.

    Each contiguous restart is continued (the stamps after it shifted to follow the
    stamp before it by the median step); at the first restart across which the signal
    jumps, the record is cut: the samples from it on are left out.

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    displacement, velocity : array_like or None
        The recorded channels.

    Returns
    -------
    t, displacement, velocity : ndarray or None
        Unchanged when the clock never restarts; else on one clock (and cut).
    restarts : tuple of Restart
        The restarts continued, and the one cut at (last, not contiguous), if any.
    cut : int or None
        The first sample left out (None when nothing was).
    """
    found = restarts(t, displacement, velocity)
    t = np.asarray(t, dtype=float)
    if not found:
        return t, displacement, velocity, (), None
    out = t.copy()
    step = float(np.median(np.diff(t)[np.diff(t) > 0.0]))
    kept: list[Restart] = []
    cut = None
    for r in found:
        kept.append(r)
        if not r.contiguous:
            cut = r.at
            break
        out[r.at :] += out[r.at - 1] + step - out[r.at]
    if cut is None:
        return out, displacement, velocity, tuple(kept), None

    def head(values: ArrayLike | None) -> NDArray | None:
        return None if values is None else np.asarray(values, dtype=float)[:cut]

    return out[:cut], head(displacement), head(velocity), tuple(kept), cut
