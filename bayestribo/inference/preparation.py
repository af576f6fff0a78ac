"""The prepare stage: a run becomes the Π increments the likelihood observes.

:func:`prepare` reads and checks a run, calibrates its channels and gives a
:class:`~bayestribo.inference.types.PreparedRun` (energy decay, noise model,
increments). The same run prepared otherwise: in another frame of time
(:func:`reframe`, at the frequency :func:`law_frequency` finds for a nonlinear law), on
another grid (:func:`regrid`) or in part (:func:`prepare_part`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import warnings
import zlib
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.calibration import calibrate_channels
from bayestribo.inference.restoring_choice import AUTO, choose_restoring
from bayestribo.inference.types import PreparedRun
from bayestribo.io.acceleration import motion_edges
from bayestribo.io.files import as_run
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.model.restoring import rescaled
from bayestribo.signal.decay import EnergyDecay, energy_decay, retrograde_integral
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import NoiseModel, noise_model

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior

__all__ = [
    "data_seed",
    "law_frequency",
    "match_turning_times",
    "matched_law_times",
    "prepare",
    "prepare_part",
    "reframe",
    "regrid",
    "run_restoring",
    "small_swing_frequency",
    "with_restoring",
]


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


def data_seed(decay: EnergyDecay) -> int:
    """A seed that is a function of the analysed signals alone (CRC-32 of their bytes)."""
    crc = zlib.crc32(np.ascontiguousarray(decay.y).tobytes())
    return zlib.crc32(np.ascontiguousarray(decay.yp).tobytes(), crc)


def _linear_spring(run: Run) -> bool:
    """True when the run's restoring force (its metadata's ``restoring``) is one the
    laws take as the linear spring (no compiled kernels)."""
    from bayestribo.model.restoring import get_restoring

    return get_restoring(dict(run.metadata).get("restoring")).kernels is None


def run_restoring(run: Run, decay: EnergyDecay) -> Any:
    """The run's nonlinear restoring force (its metadata's ``restoring``), its
    parameters measured from the turning points where it has any, as the energy and the
    laws take it; None for the linear spring.

    Raises
    ------
    BayestriboError
        When a force's parameters cannot be measured from the record.
    """
    from bayestribo.model.restoring import get_restoring

    name = dict(run.metadata).get("restoring")
    force = get_restoring(name)
    if force.kernels is None:
        return None
    if force.angle and decay.scaling.length_scale != 1.0:
        raise BayestriboError(
            f"restoring force {force.name!r}: its potential takes the angle in radians, "
            f"but the run's displacement is scaled by {decay.scaling.length_scale:.6g} (a "
            "rig's load, mass or inertia make y = kx/N): fit the angle without them, or "
            "with another restoring force"
        )
    if force.fitted and force.measure is not None:
        if decay.turning_times is None:
            raise BayestriboError(
                f"restoring force {force.name!r}: its parameters are measured from the "
                "turning times, which this record's analysis does not give"
            )
        try:
            force, _ = force.measure(
                decay.turning_times, decay.peaks.value / decay.scaling.length_scale
            )
        except ValueError as exc:
            raise BayestriboError(f"restoring force {force.name!r}: {exc}") from None
    return force.kernel()


def force_settled(run: Run, decay: EnergyDecay, choice: Any = None) -> bool:
    """Whether the run's nonlinear restoring force is the one its half periods name.

    A velocity derived from the displacement correlates neighbouring increments on a
    nonlinear force (:mod:`bayestribo.signal.derivative_correlation`); the likelihood
    takes that correlation only where the force is not in doubt. Taken as independent,
    the increments leave the intervals some 30 % wider than the estimates' scatter,
    which is what covered a force that is not the record's (a Duffing spring fitted to
    a pendulum recorded as a length: with the correlation, c₂'s and μ_k's z-scores' sd
    1.26-1.27 over 31 runs, ``benchmarks/README.md``).

    Parameters
    ----------
    run : Run
        The recording, its metadata naming the force (``auto`` already replaced by the
        force chosen).
    decay : EnergyDecay
        Its decay, with the turning times.
    choice : RestoringChoice, optional
        ``restoring="auto"``'s choice.

    Returns
    -------
    bool
        With ``choice``: it warned of nothing (a force followed the change, and no
        pendulum was recorded in another unit than radians). For a named force: the
        choice ``auto`` would make on the same turning points is that force, with no
        warning.
    """
    if choice is None:
        if decay.turning_times is None:
            return False
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            choice = choose_restoring(
                decay.turning_times,
                decay.peaks.value / decay.scaling.length_scale,
                length_unit=run.length_unit,
                angle=decay.scaling.length_scale == 1.0,
                length_scale=decay.scaling.length_scale,
            )
        if choice.name != dict(run.metadata).get("restoring"):
            return False
    return choice.warning is None and choice.followed


def _derivative_correlation(prepared: PreparedRun) -> bool:
    """What :func:`prepare` decided of the derivative's correlation (kept in the data's
    ``preparation``), for the preparations made again from it."""
    return bool((prepared.data.preparation or {}).get("derivative_correlation", True))


def small_swing_frequency(decay: EnergyDecay, restoring: Any) -> float:
    """The natural frequency [Hz] of the small swings under a nonlinear restoring force.

    The record's turning times are fitted by least squares as
    ``t_n = t₀ + T₀ Σ_{m<n} T(A_m)/T₀`` (A_m = (|Y_m| + |Y_m+1|)/2, the restoring
    force's half period ratio); the damping's share of the period is the record's own
    (its natural over its damped frequency, :func:`~bayestribo.signal.decay.
    energy_decay`).

    Parameters
    ----------
    decay : EnergyDecay
        The record's decay.
    restoring : RestoringKernel
        Its restoring force (:meth:`~bayestribo.model.restoring.RestoringForce.kernel`).

    Returns
    -------
    float
        ω₀/2π [Hz].
    """
    times = np.asarray(decay.turning_times, dtype=float)
    values = np.abs(np.asarray(decay.peaks.value, dtype=float)) / decay.scaling.length_scale
    swing = 0.5 * (values[1:] + values[:-1])
    ratio = np.asarray(restoring.half_period_ratio(swing), dtype=float)
    steps = np.concatenate(([0.0], np.cumsum(ratio)))
    design = np.column_stack([np.ones_like(steps), steps])
    (_, half), *_ = np.linalg.lstsq(design, times, rcond=None)
    if not (math.isfinite(half) and half > 0):
        raise BayestriboError(
            f"restoring force {restoring.name!r}: the turning times give no small-swing period"
        )
    return decay.natural_frequency_Hz / decay.damped_frequency_Hz / (2.0 * float(half))


def with_restoring(decay: EnergyDecay, restoring: Any) -> EnergyDecay:
    """The decay with the energy of a nonlinear restoring force, ``½y'² + V(y)``, and
    its Π (the decay as it is for None)."""
    if restoring is None:
        return decay
    energy = 0.5 * decay.yp * decay.yp + np.asarray(restoring.potential(decay.y), dtype=float)
    return dataclasses.replace(
        decay,
        energy=energy,
        pi=retrograde_integral(decay.tau, energy),
        restoring=restoring,
    )


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
    auto = dict(recording.metadata).get("restoring") == AUTO
    linear = auto or _linear_spring(recording)

    def analysed(linear_spring: bool) -> EnergyDecay:
        return energy_decay(
            recording.time,
            recording.displacement,
            recording.velocity,
            rig=recording.rig(),
            skip_oscillations=skip_oscillations,
            notch=notch,
            linear_spring=linear_spring,
            acceleration_edges=motion_edges(dict(recording.metadata)),
        )

    with warnings.catch_warnings(record=True) if auto else contextlib.nullcontext() as held:
        if auto:
            # what the linear analysis says of the record (a softening read as a soft
            # clip, the turning points it leaves out) holds for a linear choice only
            warnings.simplefilter("always")
        decay = analysed(linear)
    choice = None
    if auto:
        # restoring "auto": chosen from the linear analysis's turning times; a linear
        # choice keeps that analysis, as restoring "linear" would
        choice = choose_restoring(
            decay.turning_times,
            decay.peaks.value / decay.scaling.length_scale,
            length_unit=recording.length_unit,
            angle=decay.scaling.length_scale == 1.0,
            length_scale=decay.scaling.length_scale,
            name=_run_name(recording) or None,
        )
        recording = recording.with_metadata(restoring=choice.name)
        linear = _linear_spring(recording)
        if not linear:
            # analysed again as a run that names the force is (its turning points not
            # held to a linear oscillator's), which says what holds of it
            decay = analysed(False)
        else:
            for w in held or ():
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    restoring = None if linear else run_restoring(recording, decay)
    if restoring is not None:
        # the small swings' frequency scales time (τ = ω₀t), in which V is written
        measured_in = decay.scaling.length_scale
        decay = energy_decay(
            recording.time,
            recording.displacement,
            recording.velocity,
            rig=recording.rig(),
            skip_oscillations=skip_oscillations,
            notch=notch,
            frequency_Hz=small_swing_frequency(decay, restoring),
            linear_spring=False,
            acceleration_edges=motion_edges(dict(recording.metadata)),
        )
        # y's unit N/k moved with the frequency: the force's coefficients follow it
        restoring = rescaled(restoring, decay.scaling.length_scale / measured_in)
        decay = with_restoring(decay, restoring)
    noise_used = noise or noise_model(decay, dict(recording.metadata))
    if seed is None:
        mc_seed = data_seed(decay)
    else:
        mc_seed = int(np.random.default_rng(seed).integers(2**31))
    correlate = (
        restoring is not None
        and decay.derived_channel == "velocity"
        and force_settled(recording, decay, choice)
    )
    data = pi_data(
        decay, noise_used, grid_points=grid_points, seed=mc_seed, derivative_correlation=correlate
    )
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
        choice,
    )


def reframe(
    prepared: PreparedRun,
    frequency_Hz: float,
    *,
    restoring: Any = None,
    seed: int | None = None,
) -> PreparedRun:
    """The same run prepared again with time scaled by another natural frequency.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    frequency_Hz : float
        The natural frequency [Hz] that scales time (τ = 2πf t), e.g.
        :func:`law_frequency`.
    restoring : RestoringKernel, optional
        Another nonlinear restoring force for the energy (the same force at other
        parameters, :mod:`bayestribo.inference.restoring_error`), its coefficients in the
        unit of ``prepared``'s y; default the run's. Either is taken to the unit of y in
        the new frame (:func:`~bayestribo.model.restoring.rescaled`: y = x k/N, and k
        moves with the frequency).
    seed : int, optional
        Seed of the Monte Carlo noise of a derived channel's increments; default one
        computed from the decay (:func:`prepare`). The seed of ``prepared`` keeps the
        variances' Monte Carlo draws as they were, so that two preparations differ by
        their energy alone.

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
        linear_spring=old.restoring is None,
        acceleration_edges=motion_edges(dict(run.metadata)),
    )
    force = old.restoring if restoring is None else restoring
    force = rescaled(force, decay.scaling.length_scale / old.scaling.length_scale)
    decay = with_restoring(decay, force)
    noise_used = prepared.noise if prepared.noise_given else noise_model(decay, dict(run.metadata))
    mc_seed = data_seed(decay) if seed is None else seed
    data = pi_data(
        decay,
        noise_used,
        grid_points=prepared.grid_points,
        seed=mc_seed,
        derivative_correlation=_derivative_correlation(prepared),
    )
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
    data = pi_data(
        decay,
        prepared.noise,
        grid_points=int(grid_points),
        seed=data_seed(decay),
        derivative_correlation=_derivative_correlation(prepared),
    )
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
        frequency_Hz=None if old.restoring is None else old.scaling.omega / (2.0 * math.pi),
        linear_spring=old.restoring is None,
        acceleration_edges=motion_edges(dict(run.metadata)),
    )
    decay = with_restoring(
        decay, rescaled(old.restoring, decay.scaling.length_scale / old.scaling.length_scale)
    )
    data = pi_data(
        decay,
        prepared.noise,
        grid_points=prepared.grid_points,
        seed=data_seed(decay),
        derivative_correlation=_derivative_correlation(prepared),
    )
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
    return match_turning_times(tau_law, decay)


def match_turning_times(
    tau_law: NDArray, decay: EnergyDecay
) -> tuple[NDArray, NDArray, NDArray] | None:
    """The record's turning times τ (in its frame) that have a turning time of the law,
    ``tau_law`` (in the same frame), within a quarter period, the law's matched to
    them, and which of the record's have one; None with fewer than 3 of the law's,
    fewer than 90 % (and 4) of the record's matched, or two matched to one."""
    times = decay.turning_times
    if times is None or np.size(times) < 4 or tau_law.size < 3:
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
