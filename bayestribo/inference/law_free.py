"""The turning points the law-free ΔE(A) is read off, and what it says when it cannot be.

The law-free answer (:func:`~bayestribo.inference.dissipation.turning_point_dissipation`)
takes the energy lost from one turning point to the next. A coarse displacement (steps
its noise does not dither, :mod:`bayestribo.signal.coarse`) has its turning points on its
levels, up to half a step off; its staircase says where they are
(:func:`~bayestribo.signal.staircase.coarse_turning_points`), and those are the turning
points used, on a linear spring. Where the staircase gives none (a swing that crosses
no level the noise leaves clear), the levels' turning points are used and a
:class:`~bayestribo.errors.CoarseSignalWarning` says the answer is not calibrated.

A free decay loses energy: a band wholly below zero at some swing (an energy gain) is no
measurement of the dissipation, and an :class:`~bayestribo.errors.EnergyGainWarning`
says so with the swings.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._warnings import warn
from bayestribo.errors import CoarseSignalWarning, EnergyGainWarning
from bayestribo.signal.coarse import coarse_steps
from bayestribo.signal.staircase import coarse_turning_points

__all__ = ["STAIRCASE", "law_free_turning_points", "warn_energy_gain"]

#: What the law-free answer's definition adds when its turning points are the staircase's.
STAIRCASE = "turning points of the coarse displacement from the time it spends above its levels"


def law_free_turning_points(prepared: Any, *, warn_levels: bool = True) -> tuple[NDArray, bool]:
    """Turning points of a prepared run for its law-free ΔE(A), dimensionless (units of ℓ).

    Parameters
    ----------
    prepared : PreparedRun
        The run and its energy decay.
    warn_levels : bool
        Warn (:class:`~bayestribo.errors.CoarseSignalWarning`) when a coarse
        displacement's turning points are its levels.

    Returns
    -------
    values : ndarray
        The decay's turning points, or those of its staircase where its displacement is
        coarse (those at either end whose swing crosses no level left out).
    staircase : bool
        True when they are the staircase's.
    """
    decay = prepared.decay
    scale = decay.scaling.length_scale
    values = np.asarray(decay.peaks.value, dtype=float)
    run = prepared.run
    if decay.restoring is not None or run.displacement is None:
        return values / scale, False
    stair = coarse_turning_points(decay, run.time, run.displacement)
    if stair is not None and np.isfinite(stair).sum() >= 2:
        return stair[np.isfinite(stair)] / scale, True
    noise = decay.noise
    step = coarse_steps((noise.displacement_step, None), (noise.displacement, None))[0]
    if (
        warn_levels
        and step is not None
        and decay.derived_channel != "displacement"
        and decay.peaks.kind == "displacement"
    ):
        warn(
            f"coarse digitiser: the turning points of {prepared.name or 'the run'} stand on "
            f"the displacement's levels (steps of {step:.3g} its noise does not dither), up to "
            "half a step off, and its staircase does not place them (a swing crosses no "
            "level clear of the noise): the law-free ΔE(A) read off them is not calibrated "
            "(on simulated records of 3 to 5 steps across the swing whose staircase placed "
            "none, its 95 % intervals held the truth at 57 to 87 % of the swings, where the "
            "staircase's held it at 99 %; benchmarks/coarse_dissipation.py)",
            CoarseSignalWarning,
        )
    return values / scale, False


def warn_energy_gain(name: str | None, measured: Mapping[str, Any] | None) -> list[float]:
    """Warn when the law-free ΔE(A) is below zero, beyond its interval, at some swing.

    Parameters
    ----------
    name : str or None
        The run's name in the message.
    measured : mapping or None
        The law-free ΔE(A) (:func:`~bayestribo.inference.dissipation.
        turning_point_dissipation`).

    Returns
    -------
    list of float
        The swings [``amplitude_unit``] whose interval lies wholly below zero (empty: no
        warning).
    """
    if not measured or not measured.get("amplitude"):
        return []
    amp = np.asarray(measured["amplitude"], dtype=float)
    upper = np.asarray(measured["interval"][1], dtype=float)
    below = amp[np.isfinite(upper) & (upper < 0)]
    if below.size:
        unit = measured.get("amplitude_unit", "")
        warn(
            f"law-free ΔE(A) of {name or 'the run'}: the energy lost per cycle is below zero "
            f"beyond its interval at {below.size} swing(s) ({below.min():.3g} to "
            f"{below.max():.3g} {unit}), an energy gain no free decay has: the turning "
            "points there are not the motion's (a coarse or clipped channel, an "
            "equilibrium that moves, a driven record), and the law-free answer is no "
            "measurement of the dissipation at those swings",
            EnergyGainWarning,
        )
    return below.tolist()
