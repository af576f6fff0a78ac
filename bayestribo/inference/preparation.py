"""The prepare stage: a run becomes the Π increments the likelihood observes.

:func:`prepare` reads and checks a run, calibrates its channels and gives a
:class:`~bayestribo.inference.types.PreparedRun` (energy decay, noise model,
increments). The same run prepared otherwise: in another frame of time
(:func:`reframe`, at the frequency :func:`law_frequency` finds for a nonlinear law), on
another grid (:func:`regrid`) or in part (:func:`prepare_part`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import zlib
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.calibration import calibrate_channels
from bayestribo.inference.types import PreparedRun
from bayestribo.io.files import as_run
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.signal.decay import EnergyDecay, energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import NoiseModel, noise_model

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior

__all__ = ["law_frequency", "matched_law_times", "prepare", "prepare_part", "reframe", "regrid"]


def _run_name(run: Run) -> str:
    return str(run.source or dict(run.metadata).get("run_id", "") or "")


def _undo_declared_filter(run: Run) -> tuple[Run, bool]:
    """The run before its declared first-order filter, when it records both channels
    (:func:`bayestribo.signal.sensor.undo_first_order`), and whether it was undone."""
    spec = dict(run.metadata).get("filter")
    if spec is None or run.displacement is None or run.velocity is None:
        return run, False
    from bayestribo.signal.period import dominant_period
    from bayestribo.signal.sensor import check_filter, undo_first_order

    if check_filter(spec)["order"] != 1:
        return run, False
    try:
        period = dominant_period(run.time, run.displacement)
    except BayestriboError:
        return run, False  # no oscillation: energy_decay says so
    x, v = undo_first_order(run.time, run.displacement, run.velocity, spec, period)
    return dataclasses.replace(run, displacement=x, velocity=v), True


def _data_seed(decay: EnergyDecay) -> int:
    """A seed that is a function of the analysed signals alone (CRC-32 of their bytes)."""
    crc = zlib.crc32(np.ascontiguousarray(decay.y).tobytes())
    return zlib.crc32(np.ascontiguousarray(decay.yp).tobytes(), crc)


def prepare(
    run: Run | str | os.PathLike[str],
    *,
    skip_oscillations: int = 1,
    grid_points: int | None = None,
    noise: NoiseModel | None = None,
    seed: int | np.random.Generator | None = None,
    read_options: ReadOptions | Mapping[str, Any] | None = None,
    correct_channels: bool = True,
    notch: float | Literal["auto"] | None = None,
) -> PreparedRun:
    """Step 1: a run becomes observed Π increments with their noise variances.

    Parameters
    ----------
    run : Run or path
        The recording, or a file read by :func:`bayestribo.io.as_run`.
    skip_oscillations : int
        Oscillations skipped after the release.
    grid_points : int, optional
        Number of Π increments; default one per half cycle.
    noise : NoiseModel, optional
        Use this noise model instead of the recording's.
    seed : int or Generator, optional
        Seed of the Monte Carlo propagation of the noise into the increments of a
        derived channel. Default: a seed computed from the recording itself, so that
        the observation, and every answer drawn from it, is a function of the data and
        not of the fit's seed (the increments' variances carry the Monte Carlo's
        relative error of about 8 %; where the law misfits a record, a fit seeded
        anew with each draw moved by more than one posterior sd).
    read_options : ReadOptions or mapping, optional
        How to read ``run`` when it is a path (:class:`~bayestribo.io.options.ReadOptions`,
        or a mapping of the options of :func:`bayestribo.read_run`).
    correct_channels : bool
        Correct the velocity to the displacement when their gain ratio or delay is
        off (:func:`bayestribo.inference.calibration.calibrate_channels`; a
        :class:`~bayestribo.errors.ChannelCalibrationWarning` either way).
    notch : float, "auto" or None
        Subtract the mains line measured at rest at this frequency [Hz], or the one
        found in the rest spectrum (``"auto"``), from both channels before the
        analysis (:func:`bayestribo.signal.decay.energy_decay`); the result records
        the line removed.

    Returns
    -------
    PreparedRun
    """
    recording, undone = _undo_declared_filter(as_run(run, read_options))
    recording, channels = calibrate_channels(recording, correct=correct_channels)
    decay = energy_decay(
        recording.time,
        recording.displacement,
        recording.velocity,
        rig=recording.rig(),
        skip_oscillations=skip_oscillations,
        notch=notch,
    )
    noise_used = noise or noise_model(decay, dict(recording.metadata))
    if seed is None:
        mc_seed = _data_seed(decay)
    else:
        mc_seed = int(np.random.default_rng(seed).integers(2**31))
    data = pi_data(decay, noise_used, grid_points=grid_points, seed=mc_seed)
    return PreparedRun(
        recording,
        _run_name(recording),
        decay,
        noise_used,
        data,
        grid_points,
        skip_oscillations,
        channels,
        noise is not None,
        undone,
    )


def reframe(prepared: PreparedRun, frequency_Hz: float) -> PreparedRun:
    """The same run prepared again with time scaled by another natural frequency.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    frequency_Hz : float
        The natural frequency [Hz] that scales time (τ = 2πf t), e.g.
        :func:`law_frequency`.

    Returns
    -------
    PreparedRun
        The same window, notch and settings; the noise model measured anew (its
        dimensionless levels follow the frequency) unless it was given.
    """
    run = prepared.run
    old = prepared.decay
    decay = energy_decay(
        run.time,
        run.displacement,
        run.velocity,
        rig=run.rig(),
        skip_oscillations=prepared.skip_oscillations,
        notch=old.notch_Hz[0] if old.notch_Hz else None,
        frequency_Hz=frequency_Hz,
    )
    noise_used = prepared.noise if prepared.noise_given else noise_model(decay, dict(run.metadata))
    data = pi_data(decay, noise_used, grid_points=prepared.grid_points, seed=_data_seed(decay))
    return dataclasses.replace(prepared, decay=decay, noise=noise_used, data=data)


def regrid(prepared: PreparedRun, grid_points: int) -> PreparedRun:
    """The same run observed on another grid of Π increments.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    grid_points : int
        Number of Π increments (:func:`bayestribo.signal.increments.pi_data`).

    Returns
    -------
    PreparedRun
        The same decay and noise model, with the increments on the new grid.
    """
    if isinstance(grid_points, bool) or not isinstance(grid_points, (int, np.integer)):
        raise BayestriboError(f"grid_points: expected an integer, got {grid_points!r}")
    if grid_points < 2:
        raise BayestriboError(f"grid_points: expected at least 2, got {grid_points}")
    decay = prepared.decay
    data = pi_data(decay, prepared.noise, grid_points=int(grid_points), seed=_data_seed(decay))
    return dataclasses.replace(prepared, data=data, grid_points=int(grid_points))


def prepare_part(prepared: PreparedRun, start: int, stop: int) -> PreparedRun:
    """Samples ``start`` to ``stop`` (excluded) of a prepared run, prepared alike.

    The part of the recording (already checked, and its channels calibrated, by
    :func:`prepare`) gets the same notch, oscillations skipped, grid and noise model
    (given: measured on the whole, where the rest is); its channels are not checked
    again, since a part that decays into the noise correlates less than the whole.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    start, stop : int
        First and past-the-last sample of the part.

    Returns
    -------
    PreparedRun
    """
    run = prepared.run
    if not 0 <= start < stop <= run.time.size:
        raise BayestriboError(
            f"start, stop: expected 0 <= start < stop <= {run.time.size}, got {start}, {stop}"
        )
    keep = slice(start, stop)
    part = dataclasses.replace(
        run,
        time=run.time[keep],
        displacement=None if run.displacement is None else run.displacement[keep],
        velocity=None if run.velocity is None else run.velocity[keep],
    )
    old = prepared.decay
    decay = energy_decay(
        part.time,
        part.displacement,
        part.velocity,
        rig=part.rig(),
        skip_oscillations=prepared.skip_oscillations,
        notch=old.notch_Hz[0] if old.notch_Hz else None,
    )
    data = pi_data(decay, prepared.noise, grid_points=prepared.grid_points, seed=_data_seed(decay))
    return dataclasses.replace(prepared, run=part, decay=decay, data=data, noise_given=True)


def matched_law_times(
    posterior: Posterior, theta: NDArray, decay: EnergyDecay
) -> tuple[NDArray, NDArray, NDArray] | None:
    """The record's turning times τ (in its frame), the law's at θ matched to them, and
    which of the record's have a match (a turning point of the law within a quarter
    period; the one the record starts just after has none when the law starts in
    motion); None when fewer than 90 % (and 4) have one, or two share one."""
    times = decay.turning_times
    if times is None or np.size(times) < 4:
        return None
    data = posterior.likelihood.data
    params = posterior.physical(np.asarray(theta, dtype=float)[None])["params"]
    values = {k: float(v[0]) for k, v in params.items() if k != "y0"}
    tau_law, _ = posterior.law.turning_points(
        values,
        float(params["y0"][0]),
        float(data.yp0),
        tau_max=float(data.tau_end) + 2.0 * math.pi,
        reference=posterior.likelihood.reference_amplitude,
    )
    if tau_law.size < 3:
        return None
    tau_meas = decay.scaling.omega * (np.asarray(times, dtype=float) - decay.start_time)
    at = np.clip(np.searchsorted(tau_law, tau_meas), 1, tau_law.size - 1)
    nearer = np.where(
        np.abs(tau_law[at - 1] - tau_meas) <= np.abs(tau_law[at] - tau_meas), at - 1, at
    )
    close = np.abs(tau_law[nearer] - tau_meas) <= 0.25 * math.pi
    nearer = nearer[close]
    if close.sum() < max(4, 0.9 * close.size) or np.unique(nearer).size != nearer.size:
        return None
    return tau_meas[close], tau_law[nearer], close


def law_frequency(posterior: Posterior, theta: NDArray, decay: EnergyDecay) -> float | None:
    """The natural frequency [Hz] at which the law's turning times at θ keep step with
    the record's.

    The record's frequency (:func:`bayestribo.signal.decay.energy_decay`) is its damped
    frequency corrected by the decrement's ζ, f_d√(1+β²): exact for viscous damping
    and Coulomb friction, but a nonlinear drag's equivalent damping changes along the
    decay, and the correction is then off by about the spread of β² (quadratic drag of
    ζ_e = 0.02 at the release: 1e-4, two posterior standard deviations of ΔE(A) at ten
    times the vibrometer's resolution). The law's own turning times include what its
    drag does to the period: the slope of the record's turning times against them
    (weighted by |Y_n|, the inverse of their noise) gives the frequency.

    Returns
    -------
    float or None
        None when the turning points cannot be matched.
    """
    pair = matched_law_times(posterior, theta, decay)
    if pair is None:
        return None
    tau_meas, matched, close = pair
    w = np.abs(np.asarray(decay.peaks.value, dtype=float))[close]
    if w.size != matched.size or not np.all(np.isfinite(w)) or not np.any(w > 0):
        w = np.ones(matched.size)
    slope = float(np.polyfit(matched, tau_meas, 1, w=np.sqrt(w))[0])
    if not (math.isfinite(slope) and slope > 0):
        return None
    return decay.scaling.omega / slope / (2.0 * math.pi)
