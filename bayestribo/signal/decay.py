"""Energy decay curve E(τ) and its retrograde integral Π(τ) from a recording.

Rigaud et al. (2010), Eq. 26 and 39: ``E = (y² + y'²)/2`` from the simultaneously
measured displacement and velocity, and ``Π(τ) = ∫_τ^{T} E dθ`` integrated backwards
from the end of motion T. A real recording needs some care first, and
:func:`energy_decay` takes it:

* **Time stamps** must be strictly increasing and regular (the error names the first
  sample that is not).
* **Release and end of motion** come first, from
  :func:`bayestribo.signal.motion.motion_span` on the velocity (recorded, or derived
  from the displacement): the motion is the run of two-period blocks holding a
  coherent oscillation at the record's frequency, whatever the colour of the noise;
  the release is where the velocity leaves its rest level and the end of motion where
  it reaches it for good (the sticking turning point), both extrapolated from the
  moving side and located near the motion only, so neither moves with the length of
  the rest (0.1 s to 30 s give the same end within a sample). When the record ends
  before the motion does (a test in air decays for many seconds), Π runs to the last
  sample and :attr:`EnergyDecay.tau_end` gives the τ at which model curves must be
  truncated (``exact_pi(..., tau_end=decay.tau_end)``).
* **Turning points** come from :func:`bayestribo.signal.peaks.find_peaks` on the
  displacement between the release and the end of motion only (sub-sample parabola
  fits), with the noise threshold measured at rest (a wiggle of filtered, humming
  or 1/f noise at rest is not a turning point), and are checked to be half a period
  apart (:func:`bayestribo.signal.motion.regular_turning_points`). A record whose
  first turning points are not (a pendulum's large swings, whose period grows with
  the amplitude; an oscillator still driven by a hand or a blow for its first cycles)
  is analysed from where the spacing becomes regular, the turning points before it
  named in an :class:`~bayestribo.signal.motion.IrregularStartWarning` (and the
  equilibrium estimated from the regular ones only); an interval off after two
  regular oscillations is a wiggle of the noise or a missed turning point, refused.
* **Noisy samples, many a period**: a record refused on its raw samples for no motion
  or too few turning points standing out of the noise, whose period holds 24 samples
  or more (a seismometer at 10 Hz with an 8.9 s period, its noise 5-15 % of its
  swings), is analysed again averaged in bins of consecutive samples that leave 12 a
  period (:mod:`bayestribo.signal.binning`, a
  :class:`~bayestribo.errors.BinnedRecordWarning`); its arrays (``t``, ``y``, the
  turning points' indices) are then the bins'. Refused binned too, the error names both
  refusals.
* **First oscillation**: the first ``skip_oscillations`` oscillations after the
  release are disturbed by the magnet and skipped (default one, as in the paper,
  section 2.1); the analysis starts at the sample nearest to the next displacement
  turning point. For a record that starts in motion, its first turning point stands
  for the release.
* **Equilibrium**: the displacement zero of a vibrometer is arbitrary and, with dry
  friction, the pin comes to rest off-centre, so neither the rest before release nor
  the tail is the equilibrium. It is estimated from the turning points themselves
  (:func:`bayestribo.signal.peaks.estimate_offset`, which uses Eq. 20), with a linear
  drift when there are enough of them.
* **Noise** is measured in the quiescent segments, the rest before release and the
  rest after the stop (standard deviation about the segment's mean, excluding a
  quarter period next to the motion), and as a spectrum there
  (:attr:`EnergyDecay.rest_noise`: Welch PSD, mains lines, colour; see
  :mod:`bayestribo.signal.spectrum`), from which the increments' variances are
  computed when the noise is not white. Without such a segment it comes from
  4th-order differences of the signal and the result says so.
* **Mains hum** can be removed first (``notch=50.0`` or ``"auto"``): measured at
  rest and subtracted (zero phase, no delay).
* **Filters of the signal chain**: a causal anti-alias filter on both channels delays
  displacement and velocity alike (v = dx/dt commutes with it), so E from one sample
  is the true E one group delay earlier; all times (release, turning points, end of
  motion) carry the same delay and Π is unbiased.
* **Natural frequency** is measured from the turning-point times (the damped
  half-period π/ω_d, Eq. 13) corrected by √(1+β²) with β from the peak decrement
  (Eq. 14, 20). By default τ = Ωt uses the measured frequency; a nominal one from
  the rig is reported beside it.
* **One channel only**: a missing velocity is the Savitzky-Golay derivative of the
  displacement (5th-order polynomial over about 1/8 of a period; the bias on a
  sinusoid is below 1e-5 and white noise is filtered above about 4 times the
  oscillation frequency). A missing displacement is the integral of the velocity,
  after removing the velocity's zero offset measured at rest (when a rest segment
  exists; where its levels before the release and after the motion differ beyond its
  noise, the offset drifts: the line between them is taken off and an
  :class:`~bayestribo.errors.OffsetDriftWarning` says the intervals are not calibrated);
  the integration constant is the equilibrium estimate above, and a residual
  velocity offset shows as the fitted drift. A velocity alone that fades into the noise
  (a viscous decay) is analysed to its last turning point before its swings sink below
  the motion threshold, with a :class:`~bayestribo.errors.FadeWarning`
  (:func:`bayestribo.signal.motion.motion_span`). The integral wanders (its noise over two
  periods at rest, far above its sample-to-sample noise): the equilibrium's fit weighs
  each turning point by that wander, or the smallest swings, the wander's own, would set
  the drift (integrated accelerometer records: the first swings off centre by up to
  11 % of their size, now about 1 %, ``tests/test_io_acceleration.py``). It is
  integrated as a damped oscillation with kinks at its turning points, the pole
  fitted to the velocity, and ∫E between samples is the oscillator's own
  (:mod:`bayestribo.signal.integration`; :attr:`EnergyDecay.energy_steps`); where no
  pole fits, by the trapezoidal rule with its gain at the record's frequency divided
  out. Its turning points are valued where the velocity crosses zero
  (:func:`_integral_turning_values`).
* **A coarse digitiser** (a channel quantised in steps its noise does not dither,
  :mod:`bayestribo.signal.coarse`) resolves neither the smallest swings nor the end of
  motion: the analysis ends at the turning point after the last one of at least one
  step of amplitude, like a record that ends in motion; its rest is not taken for the
  velocity's zero, and its extremes are not checked for soft clipping. Where its swings
  sink below two steps within three oscillations, two are analysed (the one skipped
  after the release too, where it is what the record lacks;
  :func:`~bayestribo.signal.coarse.coarse_window`). A coarse velocity recorded alone is
  searched for turning points only while it swings over four steps a period
  (:func:`~bayestribo.signal.coarse.swing_end`): below, its integral's turning points
  are the rounding's.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import cumulative_trapezoid

from bayestribo._clock import clock, on_grid
from bayestribo._stamps import stamp
from bayestribo._warnings import warn
from bayestribo.errors import (
    BinnedRecordWarning,
    ClippingWarning,
    ClockRestartWarning,
    CoarseSignalWarning,
    FadeWarning,
    GapWarning,
    OffsetDriftWarning,
    RecordingError,
    SeparateMotionWarning,
)
from bayestribo.model.plausible import MAX_SPEED
from bayestribo.model.scaling import Rig, Scaling
from bayestribo.signal.binning import bin_size, binned
from bayestribo.signal.clipping import flattened_turning_points, hard_clips
from bayestribo.signal.coarse import (
    MIN_COARSE_TURNING_POINTS,
    MIN_SWING_STEPS,
    RESOLVED_STEPS,
    coarse_steps,
    coarse_window,
    few_steps_note,
    resolved_end,
    resolved_turning_points,
    swing_end,
)
from bayestribo.signal.coverage import ShortAnalysisWarning, coverage_note
from bayestribo.signal.creep import Creep, CreepWarning, creeping_rest
from bayestribo.signal.creep_shape import ShapeCreep, creep_towards_equilibrium
from bayestribo.signal.integration import (
    integrate_oscillation,
    oscillation_energy,
    oscillation_pole,
)
from bayestribo.signal.motion import (
    SPACING_TOLERANCE,
    THRESHOLD,
    IrregularStartWarning,
    MotionSpan,
    RegularTurningPoints,
    block_noise,
    motion_span,
    regular_turning_points,
)
from bayestribo.signal.noise_colour import (
    WANDER_FLOOR,
    NoiseColour,
    goes_on,
    noise_colour,
    wander_end,
)
from bayestribo.signal.peaks import Peaks, estimate_noise, estimate_offset, find_peaks
from bayestribo.signal.period import MIN_PERIOD_SAMPLES, dominant_period, sample_step
from bayestribo.signal.quantisation import (
    QUANTISATION_NOISE_FACTOR,
    finely_dithered,
    quantisation_step,
    still_on_its_steps,
)
from bayestribo.signal.restarts import continue_clock
from bayestribo.signal.short import short_decay_note
from bayestribo.signal.spectrum import NoiseSpectrum, RestNoise, fit_line, noise_spectrum
from bayestribo.signal.spikes import SpikeWarning, bridged, describe, find_spikes
from bayestribo.signal.split_stop import split_stop

__all__ = [
    "EnergyDecay",
    "IrregularStartWarning",
    "NoiseLevels",
    "check_time",
    "derivative_gain",
    "derive_velocity",
    "energy_decay",
    "retrograde_integral",
    "savgol_window",
]

#: Largest accepted relative deviation of a time step from the median step.
TIME_STEP_TOLERANCE = 1e-3
#: Fewest oscillations needed after the skipped ones (the Bayesian fit's need).
MIN_OSCILLATIONS = 3
#: Fewest samples for a quiescent segment to give a noise estimate.
MIN_QUIET_SAMPLES = 20


@dataclass(frozen=True)
class NoiseLevels:
    """Measurement noise of each channel, in the signal's units.

    Parameters
    ----------
    displacement : float or None
        Standard deviation of the displacement noise per sample [length unit].
    velocity : float or None
        Standard deviation of the velocity noise per sample [length unit/s]; for a
        derived channel, the noise of the derived samples.
    source : str
        Where the figures come from: ``"rest before release"``, ``"rest after stop"``,
        both joined by ``" and "``, or ``"signal differences"`` when the record has no
        quiescent segment.
    n_samples : int
        Number of quiescent samples used (0 for ``"signal differences"``).
    displacement_step, velocity_step : float or None
        The step a channel is quantised in (:func:`bayestribo.signal.quantisation.
        quantisation_step`), None when it is not; the channel's noise is then at least
        step/√12 (the rounding error, which a channel flat at rest does not show).
    timing_jitter_s : float
        Standard deviation of the time stamps about a regular grid [s]
        (:mod:`bayestribo._clock`), recorded: it adds no noise to the energy
        to first order (see there).
    """

    displacement: float | None
    velocity: float | None
    source: str
    n_samples: int
    displacement_step: float | None = None
    velocity_step: float | None = None
    timing_jitter_s: float = 0.0


@dataclass(frozen=True)
class EnergyDecay:
    """Dimensionless signals, energy and retrograde energy integral of one recording.

    All arrays cover the analysed window, from the start turning point to the end of
    motion (or of the record).

    Attributes
    ----------
    t : ndarray
        Time stamps of the analysed samples [s], as recorded.
    tau : ndarray
        τ = Ω(t - start_time), 0 at the first analysed sample (Eq. 6).
    y, yp : ndarray
        y = (x - equilibrium)/ℓ and y' = v/(ℓΩ) (Eq. 6), ℓ = ``scaling.length_scale``.
    energy : ndarray
        E = (y² + y'²)/2 (Eq. 26).
    pi : ndarray
        Π(τ) = ∫_τ^{τ_end} E (Eq. 39), trapezoidal rule, 0 at the last sample.
    scaling : Scaling
        The scaling used (Ω and ℓ).
    start_time, end_time : float
        First and last analysed time stamps [s].
    motion_ended : bool
        True when the motion stopped inside the record (a rest tail follows).
    release_time : float
        Time of the release [s]: the last sample of the rest the record starts in, or,
        for a record that starts in motion, its first turning point.
    equilibrium : float
        Displacement of the equilibrium at ``start_time`` [length unit].
    equilibrium_drift : float
        Drift of the equilibrium [length unit/s].
    velocity_offset : float
        Velocity zero removed [length unit/s] (0 unless measured at rest).
    natural_frequency_Hz : float
        Natural frequency measured from the recording [Hz].
    nominal_frequency_Hz : float or None
        Nominal natural frequency of the rig [Hz], if one was given.
    damped_frequency_Hz : float
        Damped frequency of the turning points, f√(1-ζ²) [Hz].
    noise : NoiseLevels
        Noise measured in the record, in signal units.
    derived_channel : str or None
        ``"velocity"`` or ``"displacement"`` when that channel was derived.
    savgol_window : int or None
        Samples in the Savitzky-Golay window of a derived velocity.
    peaks : Peaks
        Displacement turning points of the analysed window (about the equilibrium).
    rest_noise : RestNoise or None
        Noise spectra of the recorded channels at rest (Welch; mains lines, colour),
        ``None`` without a rest segment (:mod:`bayestribo.signal.spectrum`).
    notch_Hz : tuple of float
        Mains line(s) measured at rest and subtracted before the analysis (their fitted
        frequency [Hz]); empty when none was (``notch=None``, or "auto" found no line).
    stop_time : float or None
        End of motion [s]: the velocity's last crossing of its rest level, linearly
        interpolated between samples (:func:`bayestribo.signal.motion.motion_span`);
        ``end_time`` is the first sample at or after it. ``None`` when the motion lasts
        to the end of the record.
    turning_times : ndarray or None
        Time [s] of each turning point of ``peaks``: the velocity's zero from each
        side's damped arc (:func:`_turning_times`), or the peak times when the
        velocity was derived; the damped frequency is fitted to them. ``None`` for a
        decay built without them.
    flattened_turning_points : int
        Leading turning points left out because their peaks are flattened (soft
        clipping of the displacement sensor,
        :func:`~bayestribo.signal.clipping.flattened_turning_points`); 0 when none was.
    irregular_turning_points : int
        Leading turning points left out because they are not half a period apart (large
        swings whose period depends on the amplitude, a start still driven:
        :func:`~bayestribo.signal.motion.regular_turning_points`), beyond the skipped
        oscillations; 0 when none was.
    restoring : RestoringKernel or None
        The nonlinear restoring force whose potential the energy holds,
        ``E = ½y'² + V(y)`` (:func:`bayestribo.inference.preparation.prepare`, from the
        run's ``restoring``); None for the linear spring's ``½(y² + y'²)``.
    energy_steps : ndarray or None
        ∫E dτ over each step between analysed samples (``tau.size - 1`` of them) where
        it is known exactly: a velocity-only record integrated as an oscillator
        (:mod:`bayestribo.signal.integration`); None otherwise (the increments then
        integrate ``energy`` by Simpson's rule).
    noise_colour : NoiseColour or None
        Spectral slope of the recorded displacement's noise at rest below the
        oscillation (:mod:`bayestribo.signal.noise_colour`); None without a rest long
        enough to measure it.
    wander_floor : float or None
        Where the decay faded into low-frequency noise at rest, the smallest swing
        analysed [length unit]: :data:`~bayestribo.signal.noise_colour.WANDER_FLOOR`
        times the noise's rms; the turning points below it were left out (a
        :class:`~bayestribo.errors.FadeWarning` said so). None otherwise.
    """

    t: NDArray
    tau: NDArray
    y: NDArray
    yp: NDArray
    energy: NDArray
    pi: NDArray
    scaling: Scaling
    start_time: float
    end_time: float
    motion_ended: bool
    release_time: float
    equilibrium: float
    equilibrium_drift: float
    velocity_offset: float
    natural_frequency_Hz: float
    nominal_frequency_Hz: float | None
    damped_frequency_Hz: float
    noise: NoiseLevels
    derived_channel: str | None
    savgol_window: int | None
    peaks: Peaks
    rest_noise: RestNoise | None = None
    notch_Hz: tuple[float, ...] = ()
    stop_time: float | None = None
    turning_times: NDArray | None = None
    flattened_turning_points: int = 0
    irregular_turning_points: int = 0
    restoring: Any = None
    energy_steps: NDArray | None = None
    noise_colour: NoiseColour | None = None
    wander_floor: float | None = None

    @property
    def tau_end(self) -> float:
        """τ of the last analysed sample: where model Π must be truncated."""
        return float(self.tau[-1])

    @property
    def frequency_difference_Hz(self) -> float | None:
        """Measured minus nominal natural frequency [Hz], or ``None`` without a nominal."""
        if self.nominal_frequency_Hz is None:
            return None
        return self.natural_frequency_Hz - self.nominal_frequency_Hz

    @property
    def y0(self) -> float:
        """Dimensionless displacement at the start of the analysed window."""
        return float(self.y[0])

    @property
    def noise_y(self) -> float | None:
        """Displacement noise in units of y."""
        d = self.noise.displacement
        return None if d is None else d / self.scaling.length_scale

    @property
    def noise_yp(self) -> float | None:
        """Velocity noise in units of y'."""
        v = self.noise.velocity
        return None if v is None else v / (self.scaling.length_scale * self.scaling.omega)


def retrograde_integral(tau: ArrayLike, energy: ArrayLike) -> NDArray:
    """Π_i = ∫_{τ_i}^{τ_last} E dτ by the trapezoidal rule, integrating backwards (Eq. 39).

    ``scipy.integrate.cumulative_trapezoid(energy[::-1], -tau[::-1], initial=0)[::-1]``
    to the bit (the same sums in the same order), with one array of the record's length
    made on the way instead of six.
    """
    tau = np.asarray(tau, dtype=float)
    energy = np.asarray(energy, dtype=float)
    if tau.ndim != 1 or tau.shape != energy.shape or tau.size == 0:
        return cumulative_trapezoid(energy[::-1], -tau[::-1], initial=0.0)[::-1]
    y = energy[::-1]
    # the steps of -τ reversed: (-τ_{i}) - (-τ_{i+1}) is τ_{i+1} - τ_i exactly
    area = y[1:] + y[:-1]
    area *= np.diff(tau)[::-1]
    area /= 2.0
    backwards = np.empty(tau.size)
    backwards[0] = 0.0
    np.cumsum(area, out=backwards[1:])
    return backwards[::-1]


def check_time(t: ArrayLike) -> NDArray:
    """Time stamps as a 1-D float array, checked: finite, strictly increasing, regular.

    Parameters
    ----------
    t : array_like
        Sample times [s].

    Returns
    -------
    ndarray
        The time stamps; for stamps jittered about a regular grid (within a quarter
        step, :mod:`bayestribo._clock`), that grid.

    Raises
    ------
    RecordingError
        Naming the first bad sample: too few samples, not finite, not increasing, or a
        step off the median by more than :data:`TIME_STEP_TOLERANCE` (relative) where
        the stamps leave the regular grid by more than a quarter step (a gap; stamps
        jittered about the grid pass, :mod:`bayestribo._clock`).
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise RecordingError(f"t must be a 1-D array of times [s], got shape {t.shape}")
    if t.size < 16:
        raise RecordingError(f"t has {t.size} samples; a free decay needs many more")
    if not np.isfinite(t).all():
        raise RecordingError(f"t is not finite at sample {np.flatnonzero(~np.isfinite(t))[0]}")
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise RecordingError(
            f"time stamps must increase strictly: t[{i}] = {t[i]!r} follows t[{i - 1}] = "
            f"{t[i - 1]!r} (t is not increasing at sample {i})"
        )
    step = sample_step(t, dt)  # float(np.median(dt)), remembered for a run's time stamps
    # the largest deviation from the extremes of the steps; the steps off only then
    if max(float(dt.max()) - step, step - float(dt.min())) > TIME_STEP_TOLERANCE * step:
        off = np.flatnonzero(np.abs(dt - step) > TIME_STEP_TOLERANCE * step)
        stamps = clock(t)
        if stamps.regular:  # jittered about a regular grid: the grid is the clock
            return stamps.grid(t.size)
        i = int(off[0]) + 1
        raise RecordingError(
            f"time stamps must be regular: the step before sample {i} is {dt[i - 1]!r} s, "
            f"the median step is {step!r} s (tolerance {TIME_STEP_TOLERANCE:g} relative); "
            "a gap or a resampled segment cannot be analysed as one free decay"
        )
    return t


def _check_signal(name: str, values: ArrayLike | None, n: int) -> NDArray | None:
    if values is None:
        return None
    s = np.asarray(values, dtype=float)
    if s.shape != (n,):
        raise RecordingError(f"{name} must have one value per time stamp ({n}), got {s.shape}")
    if not np.isfinite(s).all():
        raise RecordingError(f"{name} is not finite at sample {np.flatnonzero(~np.isfinite(s))[0]}")
    return s


def _check_count(name: str, value: object, least: int) -> None:
    """Refuse a count argument that is not an integer >= ``least``, naming it."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise RecordingError(f"{name} must be an integer >= {least}, got {value!r}")


def savgol_window(t: NDArray, period: float) -> int:
    """Odd Savitzky-Golay window of about 1/8 of a period, at least 7 samples.

    Raises
    ------
    RecordingError
        When no period could be measured (not a finite positive number).
    """
    step = sample_step(t)
    if not (math.isfinite(period) and period > 0 and step > 0):
        raise RecordingError(
            f"no oscillation period found in the record (got {period!r} s): the signal "
            "does not oscillate, or is not sampled regularly"
        )
    return max(7, round(period / step / 8.0) | 1)


def derive_velocity(t: ArrayLike, x: ArrayLike, period: float) -> tuple[NDArray, float]:
    """Velocity of a displacement record by a Savitzky-Golay derivative.

    A 5th-order polynomial over about 1/8 of a ``period`` [s] (bias below 1e-5 on a
    sinusoid; white noise filtered above about 4 times the oscillation frequency).

    Returns
    -------
    v : ndarray
        The derivative [length unit/s].
    gain : float
        Standard deviation of v per unit standard deviation of white noise on x [1/s].
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    dt = sample_step(t)
    window = savgol_window(t, period)
    if window > x.size:
        raise RecordingError(
            f"the displacement has {x.size} samples, fewer than the {window} needed to "
            "differentiate it over 1/8 of a period"
        )
    v = scipy.signal.savgol_filter(x, window, 5, deriv=1, delta=dt, mode="interp")
    return v, derivative_gain(window, dt)


def derivative_gain(window: int, step: float) -> float:
    """Noise gain of the Savitzky-Golay derivative of :func:`derive_velocity`.

    Parameters
    ----------
    window : int
        Samples in the filter window (odd, >= 7).
    step : float
        Sample spacing, in the unit of the derivative's variable ([s] for v, [-] in τ
        for y').

    Returns
    -------
    float
        Standard deviation of the derivative per unit standard deviation of white
        noise on the differentiated samples [1/step]: the norm of the filter's
        coefficients.
    """
    return float(np.linalg.norm(scipy.signal.savgol_coeffs(window, 5, deriv=1, delta=step)))


def _turning_times(t: NDArray, v: NDArray, peaks: Peaks, period: float) -> NDArray:
    """Turning times from the velocity's zero crossings next to each displacement peak.

    The velocity crosses zero exactly at a turning point; peak times from parabola
    fits are biased by friction (the arcs on either side of a turning point have
    different centres). The velocity itself has a kink there: Coulomb friction changes
    sign with the motion, so the slope is Ω²(|x| + x_c) before the turning point and
    Ω²(|x| - x_c) after it (x_c the friction displacement μ_k N/k). A straight line
    between the two bracketing samples then puts the zero late by about
    ``h a(1 - a) 2x_c/|x|`` (h the sample spacing, a the turning point's fraction of
    the way between the samples): a delay that grows as the amplitude decays, so the
    half period comes out long and the frequency low (by 2e-5 at 31 samples per
    period on the paper's rig, 2e-6 at 300; ζ, a rate per radian, inherits it).

    Each side of the turning point is instead one arc of the damped oscillation,
    ``v ∝ e^{-κs} sin(ω_d s)`` in s = t - t_turn (κ = ζΩ, exact for each half cycle
    of the linear law with Coulomb friction whatever its amplitude): the ratio of the
    two samples next to the crossing on one side gives t_turn in closed form, from
    that side alone (:func:`_one_sided_zero`). The two sides' estimates are averaged;
    a side whose samples are not a clean arc approaching zero (noise, the rest after
    the stop) is not used, and without either the straight line is kept.

    The crossing of a peak is the one nearest to the peak's time in the direction the
    velocity takes there (+ to - at a maximum, - to + at a minimum) within a quarter
    period: a small peak's parabola time can be several samples off (a few times the
    noise in amplitude), and the neighbouring turning points' crossings, half a
    period away, go the other way. Where there is none, the peak time is kept.
    """
    dt = sample_step(t)
    reach = max(2.0, 0.25 * period / dt)
    times = peaks.t.copy()
    negative = np.signbit(v)
    # crossings from + to - (at a maximum of x) and from - to + (at a minimum)
    down = np.flatnonzero(~negative[:-1] & negative[1:])
    up = np.flatnonzero(negative[:-1] & ~negative[1:])
    omega_d = 2.0 * math.pi / period
    kappa = omega_d * _decrement_beta(peaks.value)
    stop = math.inf if peaks.stop_time is None else float(peaks.stop_time) - 0.25 * period
    for j, (tp, value) in enumerate(zip(peaks.t.tolist(), peaks.value.tolist(), strict=True)):
        change = down if value > 0 else up
        if change.size == 0:
            continue
        at = (tp - float(t[0])) / dt - 0.5  # the peak between samples c and c + 1
        k = int(np.searchsorted(change, at))
        near = [c for c in change[max(k - 1, 0) : k + 1] if abs(c - at) <= reach]
        if not near:
            continue
        c = int(min(near, key=lambda c: abs(c - at)))
        v0, v1 = v[c], v[c + 1]
        estimates = []
        if c >= 1:
            s = _one_sided_zero(v[c - 1], v0, t[c] - t[c - 1], omega_d, kappa)
            if s is not None:
                estimates.append(t[c] + s)
        if c + 2 < t.size and t[c + 1] < stop:  # after the stop the velocity is rest
            s = _one_sided_zero(v[c + 2], v1, t[c + 1] - t[c + 2], omega_d, kappa)
            if s is not None:
                estimates.append(t[c + 1] + s)
        if estimates:
            times[j] = float(np.mean(estimates))
        else:
            times[j] = t[c] + (t[c + 1] - t[c]) * v0 / (v0 - v1)
    return times


def _integral_turning_values(
    t: NDArray, x: NDArray, v: NDArray, peaks: Peaks, period: float
) -> Peaks:
    """The turning points of a displacement integrated from the velocity, valued where
    the velocity crosses zero.

    A parabola through the samples around an extremum puts its vertex low by about
    3e-4 of the swing (:func:`~bayestribo.signal.peaks.find_peaks`), and not by the same
    fraction at a maximum and a minimum: the arcs on either side have their centres
    at ±x_c, and the sampling phase differs. The equilibrium fitted to those values
    (Eq. 20) is then off by some 1e-5 of ℓ and drifts, which a windowed fit of a
    velocity-only record, precise to 1e-4 of μ_k in a window, sees as a change of μ_k
    with the amplitude. The velocity says where the turning point is
    (:func:`_turning_times`, the velocity's zero from each side's damped arc), and the
    integral there is the sample before it plus the velocity's integral up to it, the
    velocity linear between the two samples around its zero (an error of the cube of
    the step). Turning points without a crossing keep their parabola values.
    """
    times = _turning_times(t, v, peaks, period)
    where = np.searchsorted(t, times, side="right") - 1
    ok = (where >= 0) & (where + 1 < t.size)
    if not np.any(ok):
        return peaks
    c = where[ok]
    before = times[ok] - t[c]
    after = t[c + 1] - times[ok]
    # each side's velocity runs straight to its zero (the kink between them): the
    # integral from either sample is a triangle's
    raw = 0.5 * ((x[c] + 0.5 * v[c] * before) + (x[c + 1] - 0.5 * v[c + 1] * after))
    value = peaks.value.copy()
    value[ok] = raw - (peaks.offset + peaks.drift * peaks.t[ok])
    return replace(peaks, value=value)


def _one_sided_zero(
    far: float, near: float, step: float, omega_d: float, kappa: float
) -> float | None:
    """Time [s] from the sample ``near`` to the zero of the damped arc through it and
    the sample ``far``, one ``step`` further from the zero; None if there is no such arc.

    In u, the distance of a sample from the zero, each side of a turning point is
    ``|v| ∝ e^{±κu} sin(ω_d u)`` (+ before the zero, the amplitude decaying towards
    it), so ``|far/near| e^{∓κh} = sin(ω_d(u + h))/sin(ω_d u) = cos ω_d h + sin ω_d h
    · cot ω_d u``, solved for u. ``step`` is ``t_near - t_far``: positive for samples
    before the zero (the zero is at ``t_near + u``), negative after it (``t_near - u``).
    None when the two samples are not an arc approaching zero (not of one sign, or
    ``|far| <= |near|``) or the zero found is more than one step from ``near``.
    """
    if near == 0.0:
        return 0.0
    if far == 0.0 or (far > 0.0) != (near > 0.0) or abs(far) <= abs(near):
        return None
    h = abs(step)
    direction = 1.0 if step > 0 else -1.0  # +1: the samples precede the zero
    # In u = direction·(t_zero - t) >= 0 (distance to the zero, towards it) the arc is
    # V' e^{direction·κu} sin(ω_d u) on both sides: far/near = e^{dκh} sin(ω(u+h))/sin(ωu)
    ratio = abs(far / near) * math.exp(-direction * kappa * h)
    wh = omega_d * h
    cot = (ratio - math.cos(wh)) / math.sin(wh)
    u = math.atan2(1.0, cot) / omega_d
    if not 0.0 <= u <= h * (1.0 + 1e-9):
        return None
    return direction * u


def _decrement_beta(values: NDArray) -> float:
    """β = ζ/√(1-ζ²) from the decrement of the peak-to-peak heights (Eq. 14, 20):
    ``h_{n+1} = e^{-βπ} h_n - const``; 0 when there are too few turning points or the
    heights do not decay."""
    heights = np.abs(np.diff(values))
    if heights.size >= 3:
        # heights that do not vary (a coarse channel's swings of a whole number of
        # steps) determine no slope: no decrement is measured
        if np.ptp(heights[:-1]) > 1e-9 * np.max(heights[:-1]):
            r = float(np.polyfit(heights[:-1], heights[1:], 1)[0])
            if 0.0 < r < 1.0:
                return -math.log(r) / math.pi
    return 0.0


def _rest_bounds(
    t: NDArray, rest_until: float | None, stop: float | None, margin: float
) -> tuple[int, int]:
    """The samples at rest, ``t[:head]`` before the release and ``t[tail:]`` after the
    stop, each a ``margin`` [s] from the motion: ``t < rest_until - margin`` and
    ``t > stop + margin`` of the increasing time stamps, found by bisection rather
    than by comparing every sample (``head`` 0 and ``tail`` the record's length when
    there is no rest on that side)."""
    head = 0 if rest_until is None else int(np.searchsorted(t, rest_until - margin, "left"))
    tail = t.size if stop is None else int(np.searchsorted(t, stop + margin, "right"))
    return head, tail


def _quiet_segments(
    t: NDArray, rest_until: float | None, stop: float | None, margin: float
) -> NDArray:
    """Boolean mask of samples at rest: before release and after the stop, with a margin."""
    head, tail = _rest_bounds(t, rest_until, stop, margin)
    quiet = np.zeros(t.shape, bool)
    quiet[:head] = True
    quiet[tail:] = True
    return quiet


def _dithered_rest(
    t: NDArray,
    x: NDArray,
    step: float | None,
    rest_until: float | None,
    stop: float | None,
    period: float,
) -> bool:
    """Whether a quantised displacement's rest toggles between two neighbouring levels
    at most, in each of its parts (before the release, after the stop).

    White noise of a fraction of a step before the rounding (dither) toggles a rest near
    a level's boundary between the two levels: a spread of about half a step that is
    the rounding's, not a noise of that size (which would reach a third level). Its
    turning points are then judged as on a rest on one level (:func:`_peak_noise`
    without the rest's σ): a swing across three levels (two steps) is one, which the
    noise reaches with a chance of a Gaussian beyond 1.5 steps.
    """
    if step is None:
        return False
    head, tail = _rest_bounds(t, rest_until, stop, 0.25 * period)
    parts = [p for p in (x[:head], x[max(head, tail) :]) if p.size >= MIN_QUIET_SAMPLES]
    return bool(parts) and all(float(np.ptp(p)) <= 1.5 * step for p in parts)


def _rest_samples(
    s: NDArray, t: NDArray, rest_until: float | None, stop: float | None, margin: float
) -> NDArray:
    """The samples of ``s`` at rest (:func:`_rest_bounds`), in order: ``s`` where
    :func:`_quiet_segments` is True."""
    head, tail = _rest_bounds(t, rest_until, stop, margin)
    return np.concatenate([s[:head], s[max(head, tail) :]])


def _rest_parts(
    t: NDArray, rest_until: float | None, stop: float | None, margin: float
) -> tuple[list[slice], list[str]]:
    """The rest segments of :func:`_rest_bounds` of at least :data:`MIN_QUIET_SAMPLES`
    samples, as slices, with their names."""
    head, tail = _rest_bounds(t, rest_until, stop, margin)
    parts, names = [], []
    for part, name in (
        (slice(0, head), "rest before release"),
        (slice(tail, t.size), "rest after stop"),
    ):
        if part.stop - part.start >= MIN_QUIET_SAMPLES:
            parts.append(part)
            names.append(name)
    return parts, names


def _noise(
    t: NDArray,
    x: NDArray,
    v: NDArray,
    rest_until: float | None,
    stop: float | None,
    period: float,
    derived: str | None,
    jitter: float = 0.0,
) -> NoiseLevels:
    """Noise of each channel in the quiescent segments (see the module notes).

    ``rest_until`` is the release time of a record that starts at rest (``None`` for
    a record that starts in motion), ``stop`` the start of the rest tail.
    """
    parts, names = _rest_parts(t, rest_until, stop, 0.25 * period)
    steps = {
        name: None if s is None or derived == name else quantisation_step(s)
        for name, s in (("displacement", x), ("velocity", v))
    }

    def floored(name: str, level: float | None) -> float | None:
        step = steps[name]
        if level is None or step is None:
            return level
        return max(level, step * QUANTISATION_NOISE_FACTOR)

    if not parts:
        return NoiseLevels(
            displacement=floored(
                "displacement", estimate_noise(x) if derived != "displacement" else None
            ),
            velocity=floored("velocity", estimate_noise(v) if derived != "velocity" else None),
            source="signal differences",
            n_samples=0,
            displacement_step=steps["displacement"],
            velocity_step=steps["velocity"],
            timing_jitter_s=jitter,
        )

    def pooled(s: NDArray) -> float:
        # Deviations about each segment's own mean (the rest positions differ).
        dev = np.concatenate([s[part] - np.mean(s[part]) for part in parts])
        dev *= dev
        return float(np.sqrt(np.mean(dev)))

    return NoiseLevels(
        displacement=floored("displacement", pooled(x)),
        velocity=floored("velocity", pooled(v)),
        source=" and ".join(names),
        n_samples=int(sum(m.stop - m.start for m in parts)),
        displacement_step=steps["displacement"],
        velocity_step=steps["velocity"],
        timing_jitter_s=jitter,
    )


#: Significance (estimate over standard error) the filter-lag term b/|Y_n| of the
#: turning times needs to be kept (:func:`_frequencies`).
LAG_Z = 3.0
#: Largest change of the filter lag b/|Y_n| over the turning points fitted, in half
#: periods, for the term to be kept: a filter's, not a period that depends on amplitude.
LAG_LIMIT = 0.01


def _frequencies(times: NDArray, values: NDArray) -> tuple[float, float]:
    """Damped and natural frequency [Hz] from turning times and peak values.

    The damped half-period π/ω_d is the least-squares slope of the turning times
    against their index (weighted by peak size, as small peaks are timed worse); the
    natural frequency is f_d√(1+β²) = f_d/√(1-ζ²) with β from the decrement of the
    peak-to-peak heights, h_{n+1} = e^{-βπ} h_n - const (Eq. 13, 14, 20). Where the
    period depends on the amplitude (a pendulum's large swings, a spring that stiffens
    or softens) the slope is the mean half period of the turning points fitted, a
    frequency inside the range of the record's periods
    (:func:`bayestribo.signal.frequency.turning_point_trend` measures the change).

    A low-pass filter in the signal chain (an anti-alias filter) smooths the kink
    friction puts in the velocity at each turning point (:func:`_turning_times`),
    which moves the filtered velocity's zero by about ``(x_c/|Y_n|)`` times the
    filter's spread in time, later and later as the amplitude decays. Measured on the
    paper's rig through a 4th-order Butterworth filter at 2 kHz, the slope alone gives
    a damped frequency low by 1.5e-6 at 10 kHz and 2.7e-6 at 100 kHz (ζ inherits it:
    0.07 posterior sd at 10 times the resolution at 100 kHz). With six turning points
    or more the times are therefore also fitted as ``t_0 + n π/ω_d + b/|Y_n|`` (Y_n
    the peak values), and that half period is taken (the filtered cases then within
    1e-7) when the term is a filter's lag: b > 0 (a delay), significant (b over its
    standard error at least :data:`LAG_Z`: 12 and 670 in those cases) and small (its
    change over the turning points, ``b(1/min|Y| - 1/max|Y|)``, at most
    :data:`LAG_LIMIT` of a half period: 5e-4 and 9e-4 there; the delay of a filter
    whose corner is above 5 times the oscillation frequency). Otherwise the slope
    alone is kept: b, nearly collinear with n, would absorb a half period that changes
    with the amplitude and move the frequency out of the record's range (a pendulum
    at 135° of 1.56 Hz measured 1.29 Hz with b = -61 s·unit, a pendulum of periods
    1.72 to 1.86 s at 0.646 Hz with b > 0 changing by two half periods), and without
    a filter b is noise (its term is then not significant).
    """
    n = np.arange(times.size, dtype=float)
    weights = np.abs(values) if np.any(values != 0) else None
    half_period = float(np.polyfit(n, times, 1, w=weights)[0])
    if times.size >= 6 and np.all(values != 0):
        lagged = _lagged_half_period(n, times, np.abs(values))
        if lagged is not None:
            half_period = lagged
    damped = 0.5 / half_period
    beta = _decrement_beta(values)
    return damped, damped * math.sqrt(1.0 + beta * beta)


def _lagged_half_period(n: NDArray, times: NDArray, size: NDArray) -> float | None:
    """Half period [s] of the fit ``t_0 + n h + b/|Y_n|`` (weights ``size`` = |Y_n|)
    when its b is a filter's lag (:func:`_frequencies`: positive, significant, small),
    else None."""
    design = np.column_stack([np.ones_like(n), n, 1.0 / size]) * size[:, None]
    target = times * size
    coef, _, rank, _ = np.linalg.lstsq(design, target, rcond=None)
    if rank < 3 or times.size <= 3:
        return None
    half, b = float(coef[1]), float(coef[2])
    if not (b > 0.0 and half > 0.0):
        return None
    residual = target - design @ coef
    s2 = float(residual @ residual) / (times.size - 3)
    try:
        var_b = s2 * float(np.linalg.inv(design.T @ design)[2, 2])
    except np.linalg.LinAlgError:
        return None
    if var_b > 0.0 and b < LAG_Z * math.sqrt(var_b):
        return None
    change = b * (1.0 / float(size.min()) - 1.0 / float(size.max()))
    if change > LAG_LIMIT * half:
        return None
    return half


def _timing_sd(t: NDArray, peaks: Peaks) -> NDArray:
    """Noise standard deviation of each turning-point time [s] from the parabola fit.

    The vertex t* = -c₁/(2c₂) of a parabola over ±h samples moves by δc₁/(2c₂), with
    sd(c₁) = σ/√(Σu²) (u the samples' offsets [s]) and 2c₂ ≈ -Ω²Y at a turning point
    of value Y (:func:`bayestribo.signal.peaks.find_peaks`, ±1/12 period).
    """
    dt = sample_step(t)
    omega = math.pi / peaks.half_period
    h = max(1, round(2.0 * peaks.half_period / dt / 12.0))
    sum_u2 = dt * dt * h * (h + 1) * (2 * h + 1) / 3.0
    amplitude = np.maximum(np.abs(peaks.value), 1e-300)
    return peaks.noise / (math.sqrt(sum_u2) * omega**2 * amplitude)


#: Turning points of a decay that fades into the noise whose decrement continues its
#: oscillation under the noise (:func:`_without_faded`).
FADED_POINTS = 6


def _without_faded(
    t: NDArray, v: NDArray, rest_from: float, peaks: Peaks, period: float
) -> NDArray:
    """``v`` with the oscillation that a decay fading into the noise keeps under it
    taken out from ``rest_from`` [s] on: e^(-λt)(a cos ω_d t + b sin ω_d t) with the
    decay rate λ of the last :data:`FADED_POINTS` turning points' swings and ω_d
    their half period's (2π/``period``), a and b (and a constant, kept) fitted by
    least squares to the samples there.

    At 1.4 times the noise per sample where the rest starts, the oscillation was
    counted as rest noise: its spectrum a line at the rig's frequency, the rest
    called coloured, and the Monte Carlo of a velocity alone drew that line into
    the increments (on a seismometer's record χ²/n of the fit 0.2, ζ's sd(z) 0.4)."""
    first = int(np.searchsorted(t, rest_from, "left"))
    tail = t[first:] - rest_from
    last = slice(max(0, len(peaks) - FADED_POINTS), len(peaks))
    swings = np.abs(np.asarray(peaks.value[last], dtype=float))
    if tail.size < 4 or swings.size < 3 or not np.all(swings > 0):
        return v
    rate = -float(np.polyfit(np.asarray(peaks.t[last], dtype=float), np.log(swings), 1)[0])
    rate = max(rate, 0.0)
    omega = 2.0 * math.pi / period
    envelope = np.exp(-rate * tail)
    wave = np.column_stack([envelope * np.cos(omega * tail), envelope * np.sin(omega * tail)])
    design = np.column_stack([np.ones(tail.size), wave])
    coef, *_ = np.linalg.lstsq(design, v[first:], rcond=None)
    out = v.copy()
    out[first:] -= wave @ coef[1:]
    return out


#: Difference of a velocity's levels at rest before the release and after the motion,
#: in standard errors of white noise, beyond which its offset drifts (a Gaussian
#: difference exceeds it with probability 1e-15).
OFFSET_DRIFT_Z = 8.0


def _offset_drift(
    t: NDArray, v: NDArray, rest_until: float | None, stop: float | None, sigma: float
) -> NDArray | None:
    """The offset of a velocity recorded alone where it drifts: its median at rest
    before the release and after the motion differ by more than
    :data:`OFFSET_DRIFT_Z` standard errors (white noise of sd ``sigma`` [unit/s]); the
    line between the two rests' medians (at their centres), each rest's own median
    beyond it, which is the best estimate of a random walk known at both ends; a
    :class:`~bayestribo.errors.OffsetDriftWarning` says so. None when the levels agree
    or there are not two rests."""
    head, tail = _rest_bounds(t, rest_until, stop, 0.0)
    if head < MIN_QUIET_SAMPLES or t.size - tail < MIN_QUIET_SAMPLES or not sigma > 0:
        return None
    before, after = float(np.median(v[:head])), float(np.median(v[tail:]))
    # the median's standard error is √(π/2) times the mean's for white noise
    se = sigma * math.sqrt(0.5 * math.pi * (1.0 / head + 1.0 / (t.size - tail)))
    z = abs(after - before) / se
    if z <= OFFSET_DRIFT_Z:
        return None
    t0, t1 = float(np.mean(t[:head])), float(np.mean(t[tail:]))
    origin, span = float(t[0]), float(t[-1] - t[0])
    warn(
        f"velocity offset: the velocity, recorded alone, rests at {before:.4g} before the "
        f"release (to t = {stamp(float(t[head - 1]), span, origin)}) and at {after:.4g} "
        f"after the motion (from t = {stamp(float(t[tail]), span, origin)}), {z:.0f} "
        "standard errors of its noise apart: "
        "its offset drifts. It is taken off as the line between the two rests, but the "
        "drift's wander between them, integrated into the displacement, moves it off its "
        "equilibrium, which the noise model does not hold: the intervals are not "
        "calibrated (on simulated records with a random-walk offset of 1e-4 per √s "
        "ζ was off by up to 6 sd); a record whose offset is steady, or one with the "
        "displacement recorded, can be fitted",
        OffsetDriftWarning,
    )
    return before + (after - before) * np.clip((t - t0) / (t1 - t0), 0.0, 1.0)


def _creep(
    t: NDArray,
    x: NDArray,
    v: NDArray,
    stop: float | None,
    period: float,
    derived: str | None,
    peaks: Peaks,
    rest_until: float | None,
) -> Creep | ShapeCreep | None:
    """The creep in the rest after ``stop``, from a quarter ``period`` after it: where both
    channels are recorded, the two moving as one
    (:func:`~bayestribo.signal.creep.creeping_rest`); where one is, the displacement
    (recorded or integrated) approaching the turning points' equilibrium
    (:func:`~bayestribo.signal.creep_shape.creep_towards_equilibrium`)."""
    if stop is None:
        return None
    head, tail = _rest_bounds(t, rest_until, stop, 0.25 * period)
    if derived is None:
        return creeping_rest(t, x, v, tail)
    if peaks.kind != "displacement" or len(peaks) == 0 or t.size - tail < MIN_QUIET_SAMPLES:
        return None
    recorded = "velocity" if derived == "displacement" else "displacement"
    channel = v if recorded == "velocity" else x
    sigma = estimate_noise(channel[tail:])
    if recorded == "displacement":
        # the equilibrium where the motion ends, held: its line's drift, fitted on the
        # turning points, is not extended over the rest (a law's misfit tilts it)
        equilibrium = np.full(t.size, peaks.offset + peaks.drift * float(peaks.t[-1]))
    else:
        # the integral of a velocity alone, whose offset was taken as its median at rest
        # (a creep's own pace there): the line's drift is the offset left in during the
        # motion, measured roughly; the approach is fitted with a pace of its own
        equilibrium = peaks.offset + peaks.drift * t
    return creep_towards_equilibrium(
        t,
        x,
        equilibrium,
        tail,
        recorded=recorded,
        sigma=sigma,
        stop_time=float(stop),
        last_swing=float(abs(peaks.value[-1])),
        omega=2.0 * math.pi / period,
        before=head if head >= MIN_QUIET_SAMPLES else 0,
        step=quantisation_step(channel),
        free_slope=recorded == "velocity",
    )


def _rest_noise(
    t: NDArray,
    x: NDArray,
    v: NDArray,
    rest_until: float | None,
    stop: float | None,
    period: float,
    derived: str | None,
) -> RestNoise | None:
    """Noise spectra of the recorded channels on the rest segments (as :func:`_noise`);
    None for the one channel recorded (the other derived) where it is quantised and
    still on its steps at rest (its noise is the rounding's, white:
    :func:`~bayestribo.signal.quantisation.still_on_its_steps`; with both channels
    recorded a coarse channel's rounding is modelled as such,
    :mod:`bayestribo.signal.coarse`)."""
    parts, names = _rest_parts(t, rest_until, stop, 0.25 * period)
    if not parts:
        return None
    fs = 1.0 / sample_step(t)

    def spectrum(s: NDArray) -> NoiseSpectrum | None:
        rests = [s[part] for part in parts]
        if derived is not None and still_on_its_steps(rests, quantisation_step(s)):
            return None
        return noise_spectrum(rests, fs, period_s=period)

    return RestNoise(
        displacement=None if derived == "displacement" else spectrum(x),
        velocity=None if derived == "velocity" else spectrum(v),
        source=" and ".join(names),
    )


def _rest_colour(
    t: NDArray,
    x: NDArray,
    v: NDArray,
    rest_until: float | None,
    stop: float | None,
    period: float,
    derived: str | None,
) -> NoiseColour | None:
    """The spectral slope of the recorded displacement's noise at rest below the
    oscillation (:func:`bayestribo.signal.noise_colour.noise_colour`); None for a
    displacement integrated from the velocity, or without a rest long enough."""
    if derived == "displacement":
        return None
    parts, _ = _rest_parts(t, rest_until, stop, 0.25 * period)
    if not parts:
        return None
    return noise_colour([x[part] for part in parts], 1.0 / sample_step(t), 1.0 / period)


def _check_notch(notch: object) -> None:
    if notch is None or (isinstance(notch, str) and notch == "auto"):
        return
    if isinstance(notch, bool) or not isinstance(notch, int | float | np.floating | np.integer):
        raise RecordingError(f"notch must be a frequency [Hz], 'auto' or None, got {notch!r}")
    if not (math.isfinite(float(notch)) and float(notch) > 0):
        raise RecordingError(f"notch must be a positive frequency [Hz], got {notch!r}")


def energy_decay(
    t: ArrayLike,
    displacement: ArrayLike | None = None,
    velocity: ArrayLike | None = None,
    *,
    rig: Rig | None = None,
    skip_oscillations: int = 1,
    use_nominal_frequency: bool = False,
    skip_turning_points: int | None = None,
    min_turning_points: int | None = None,
    offset: float | Literal["auto", "constant"] | None = "auto",
    notch: float | Literal["auto"] | None = None,
    motion_threshold: float = THRESHOLD,
    frequency_Hz: float | None = None,
    linear_spring: bool = True,
    acceleration_edges: tuple[float | None, float | None] | None = None,
) -> EnergyDecay:
    """Energy decay curve and Π(τ) of a free-decay recording (Eq. 6, 26, 39).

    Parameters
    ----------
    t : array_like
        Time stamps [s], strictly increasing and regular, any origin.
    displacement : array_like, optional
        Displacement x [m, or any length unit when ``rig`` has no load], any zero.
    velocity : array_like, optional
        Velocity v [m/s, or the same length unit per second].
    rig : Rig, optional
        Mass, nominal natural frequency and load. With a load and a mass, y = kx/N
        (friction as μ_k); otherwise y is the displacement in signal units (friction
        as a friction displacement).
    skip_oscillations : int
        Oscillations after the first turning point (the release) left out of the
        analysis, default 1 (paper, section 2.1).
    use_nominal_frequency : bool
        Scale time with the rig's nominal frequency instead of the measured one.
    skip_turning_points : int, optional
        Skip this many of the turning points found in the record instead, whether or
        not the record starts at rest: the convention of the peak-based estimators
        (:mod:`bayestribo.estimators`, 2 = the first oscillation of a record that
        starts in motion). Given, ``skip_oscillations`` is not used.
    min_turning_points : int, optional
        Fewest turning points needed after the skipped ones, default
        2 × :data:`MIN_OSCILLATIONS` (the Bayesian fit's three oscillations); for a
        coarse record whose swings sink below two steps sooner, down to
        :data:`~bayestribo.signal.coarse.MIN_COARSE_TURNING_POINTS` with the skipped
        oscillation analysed too where it is what the record lacks
        (:func:`~bayestribo.signal.coarse.coarse_window`; a
        :class:`~bayestribo.errors.CoarseSignalWarning` says so); for a free decay
        that stops or ends within three oscillations, likewise down to two
        (:mod:`bayestribo.signal.short`; a
        :class:`~bayestribo.errors.ShortAnalysisWarning` says so). Given, it is kept.
    offset : float, "auto", "constant" or None
        How the equilibrium of the displacement is found, as in
        :func:`bayestribo.signal.peaks.find_peaks`: "auto" from the turning points
        with a linear drift when there are enough of them, "constant" without the
        drift, a number [length unit] when it is known, ``None`` for 0.
    notch : float, "auto" or None
        Remove a mains line from both channels before the analysis: its nominal
        frequency [Hz], or "auto" to look for a 50 or 60 Hz line in the spectrum of the
        noise at rest and remove it when there is one (:attr:`EnergyDecay.notch_Hz`
        says what was removed, empty when nothing was). Default ``None``: no removal.
        The line is measured at rest: ``A cos(2πf t + φ)`` fitted on the rest before
        the release and after the stop, f refined within ±0.5 Hz
        (:func:`bayestribo.signal.spectrum.fit_line`), and subtracted from the whole
        record. This is zero-phase (it adds no delay) and touches nothing but the line.
        A zero-phase IIR notch (:func:`bayestribo.signal.spectrum.notch_filter`) is not
        used here: the release's onset puts about 1 % of the oscillation's amplitude
        into the 50 Hz band, 17 Hz from 32.6 Hz, and the notch rings it out for
        ``quality/(πf)`` s on both sides (measured on a simulated record at quality 30:
        release found 9 ms early, end of motion 18 ms early).
    motion_threshold : float
        Excursion of the velocity from its rest level, in rest noise standard
        deviations, that marks the motion when the release and the end of motion
        are located (:func:`bayestribo.signal.motion.motion_span`).
    frequency_Hz : float, optional
        Scale time with this natural frequency [Hz] instead of the measured one (the
        frequency that makes a nonlinear law's turning times match the record's,
        :func:`bayestribo.inference.pipeline.law_frequency`); the measured one is still
        reported in ``natural_frequency_Hz``.
    linear_spring : bool
        False for a run whose restoring force is declared nonlinear (a pendulum, a
        Duffing spring): its first half periods differ from the later ones and its peaks
        are not a linear oscillator's by the force itself, so that neither leaves
        turning points out (as an irregular start or soft clipping).
    acceleration_edges : (float or None, float or None), optional
        For a velocity integrated from an acceleration (alone): the release and the end
        of motion [s] as the acceleration shows them
        (:func:`bayestribo.io.acceleration.motion_edges`; either None: found in the
        velocity). The acceleration's noise is white, while the integral's, a random
        walk held at the rests and free next to them, wanders well beyond its rest
        noise there, and the velocity seemed to move on after the stop (on a 60 Hz
        decay, 11 to 30 ms late, its last turning points the noise's: μ_s/μ_k 4.0
        [2.9, 5.0] where it was 1). The integral's drift was taken off at the rests:
        its offset there is zero by construction, and none is measured or taken off
        (its levels next to the edges differ by the integration's error at the edges,
        which the rest's noise does not measure: an offset said to drift by 18 standard
        errors where there is none).

    Returns
    -------
    EnergyDecay

    Raises
    ------
    RecordingError
        No signal, bad time stamps or samples, a skip that is not an integer >= 0;
        and, naming the part of the analysis: "release: no motion found" (no
        oscillation above the noise), "turning points: ..." (too few after the
        skipped ones, or not half a period apart), "energy decay: the oscillation
        does not decay"; the first two, where the record was tried averaged in bins
        too, followed by "averaged in bins of k samples ..., the record is refused
        too: ..." and the binned record's refusal.
    """
    stamps = np.asarray(t, dtype=float)
    # a clock that restarts: continued where the signal is contiguous, cut where it
    # jumps, and said (signal/restarts.py)
    stamps, displacement, velocity, restarted, cut = continue_clock(stamps, displacement, velocity)
    if cut is not None:
        warn(
            "; ".join(r.describe() for r in restarted)
            + f": only samples 0 to {cut - 1} (the part holding the release) are analysed; "
            f"the samples from {cut} on were left out (save them as a record of their own "
            "to fit them)",
            ShortAnalysisWarning,
        )
    elif restarted:
        warn(
            "; ".join(r.describe() for r in restarted)
            + " (the continuation assumes no sample was lost at the restart)",
            ClockRestartWarning,
        )
    # samples missing from a regular clock: bridged on the grid, and said (_clock.py)
    stamps, displacement, velocity, gaps = on_grid(stamps, displacement, velocity)
    if gaps:
        warn(
            f"{len(gaps)} gap(s) in the time stamps bridged on the regular grid by the "
            "cubic through their neighbours: " + "; ".join(g.describe() for g in gaps),
            GapWarning,
        )
    t = check_time(stamps)
    # stamps jittered about a regular grid are replaced by it (bayestribo._clock)
    jitter = 0.0 if t is stamps else clock(stamps).jitter
    x = _check_signal("displacement", displacement, t.size)
    v = _check_signal("velocity", velocity, t.size)
    if x is None and v is None:
        raise RecordingError("give a displacement or a velocity signal (or both)")
    _check_count("skip_oscillations", skip_oscillations, 0)
    if skip_turning_points is not None:
        _check_count("skip_turning_points", skip_turning_points, 0)
    if min_turning_points is not None:
        _check_count("min_turning_points", min_turning_points, 2)
    if use_nominal_frequency and rig is None:
        raise RecordingError("use_nominal_frequency needs a rig with a natural frequency")
    if frequency_Hz is not None and not (math.isfinite(frequency_Hz) and frequency_Hz > 0):
        raise RecordingError(f"frequency_Hz must be a positive number [Hz], got {frequency_Hz!r}")
    if frequency_Hz is not None and use_nominal_frequency:
        raise RecordingError("give frequency_Hz or use_nominal_frequency, not both")
    _check_notch(notch)
    if not (math.isfinite(motion_threshold) and motion_threshold > 0):
        raise RecordingError(
            f"motion_threshold must be a positive number, got {motion_threshold!r}"
        )
    for name, s in (("displacement", x), ("velocity", v)):
        if s is not None and float(np.ptp(s)) == 0.0:
            raise RecordingError(f"release: no motion found: the {name} signal is constant")
    x, v = _despiked(t, x, v)
    settings: dict[str, Any] = dict(
        jitter=jitter,
        rig=rig,
        skip_oscillations=skip_oscillations,
        use_nominal_frequency=use_nominal_frequency,
        frequency_Hz=frequency_Hz,
        skip_turning_points=skip_turning_points,
        min_turning_points=min_turning_points,
        offset=offset,
        motion_threshold=motion_threshold,
        linear_spring=linear_spring,
        acceleration_edges=acceleration_edges,
    )
    bins = raw_refusal = None
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            decay = _decay(t, x, v, notch, settings)
        except RecordingError as refused:
            raw_refusal = refused
            bins = _bins(t, x, v, frequency_Hz, refused)
            if bins is not None:
                said.clear()  # the raw record's warnings: the binned one is analysed
    _say(said)
    if raw_refusal is None:
        return decay
    if bins is None:
        raise raw_refusal
    # a period of many samples, its swings within reach of the noise per sample: the
    # record averaged in bins (signal/binning.py), its noise measured anew from them
    tb, (xb, vb), how = binned(t, (x, v), *bins)
    try:
        decay = _decay(tb, xb, vb, notch, settings)
    except RecordingError as e:
        raise RecordingError(
            f"{raw_refusal}; averaged in bins of {how.size} samples ({how.period_samples:.0f} "
            f"a period), the record is refused too: {e}"
        ) from raw_refusal
    warn(
        f"binned record: on its raw samples the record was refused ({raw_refusal}); its "
        f"period holds {how.period_samples:.0f} samples, so it was analysed averaged in "
        f"bins of {how.size} consecutive samples (a noise {math.sqrt(how.size):.3g} times "
        f"smaller a sample, white as before; the oscillation's gain through a bin, "
        f"{how.gain:.5f}, divided out): {tb.size} samples {tb[1] - tb[0]:.4g} s apart",
        BinnedRecordWarning,
    )
    return decay


#: Refusals of the raw record that averaging in bins may lift: no oscillation above the
#: noise per sample, too few turning points standing out of it.
_BINNED_REFUSALS = ("release: no motion found", "turning points:")


def _bins(
    t: NDArray,
    x: NDArray | None,
    v: NDArray | None,
    frequency_Hz: float | None,
    refused: RecordingError,
) -> tuple[int, float] | None:
    """The bin and the period's samples for a record refused on its raw samples, or
    ``None`` where binning does not apply: another refusal, a period of few samples, or
    a channel on coarse steps that its noise does not dither (its rounding is no white
    noise, and a bin's mean of it is not the motion's: the coarse digitiser's own
    analysis and refusals hold, :mod:`bayestribo.signal.coarse`)."""
    if not str(refused).startswith(_BINNED_REFUSALS):
        return None
    for s in (x, v):
        step = None if s is None else quantisation_step(s)
        if step is not None and not finely_dithered(s, step):
            return None
    try:
        period = (
            1.0 / frequency_Hz
            if frequency_Hz is not None
            else dominant_period(t, x if x is not None else v)
        )
    except RecordingError:
        return None
    per_samples = period / sample_step(t)
    size = bin_size(per_samples, t.size)
    return None if size is None else (size, per_samples)


def _say(said: list[warnings.WarningMessage]) -> None:
    """The warnings of an analysis given again (recorded while it ran)."""
    for w in said:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def _decay(
    t: NDArray,
    x: NDArray | None,
    v: NDArray | None,
    notch: float | Literal["auto"] | None,
    options: dict[str, Any],
) -> EnergyDecay:
    """:func:`energy_decay` on checked, despiked signals, notched where asked."""
    if notch is None:
        return _analyse(t, x, v, notch_Hz=(), **options)
    # A first analysis finds the rest, where the line is measured.
    try:
        first = _analyse(t, x, v, notch_Hz=(), **options)
    except RecordingError as e:
        raise RecordingError(f"notch: the rest to measure the line on was not found: {e}") from e
    if notch == "auto":
        mains = None if first.rest_noise is None else first.rest_noise.mains_Hz()
        if mains is None:
            return first
        notch_Hz = float(mains)
    else:
        notch_Hz = float(notch)
    rest = _rest_mask(t, first)
    if not rest.any():
        raise RecordingError(
            "notch: the record has no rest before the release or after the stop to "
            f"measure the {notch_Hz:g} Hz line on"
        )
    fitted = []
    out = []
    for sig in (x, v):
        if sig is None:
            out.append(None)
            continue
        f, amplitude, phase = fit_line(t, sig, rest, notch_Hz)
        fitted.append(f)
        out.append(sig - amplitude * np.cos(2.0 * math.pi * f * (t - t[0]) + phase))
    return _analyse(t, out[0], out[1], notch_Hz=(float(np.mean(fitted)),), **options)


#: Peak-to-peak height, in quantisation steps, that a quantised displacement's
#: turning points must stand out by (a rounding error is at most half a step at each).
PEAK_STEPS = 2.0
#: Prominence of a turning point, in noise standard deviations (find_peaks' default).
PEAK_THRESHOLD = 10.0
#: Swings within this many times the turning points' threshold over the noise at rest
#: are in the noise's reach: where their turning points break the half period, the decay
#: has faded into the noise (:func:`bayestribo.signal.motion.regular_turning_points`).
FADE = 2.0


def _peak_noise(
    sigma: float | None, step: float | None
) -> tuple[float | None, float, float | None]:
    """Noise, threshold and rest band for the turning points of a displacement.

    Unquantised: the rest noise ``sigma``, :data:`PEAK_THRESHOLD` and the default band
    (None: :func:`~bayestribo.signal.peaks.find_peaks`' four noise sd). Quantised in
    ``step``: a rounding error is bounded (at most step/2 at each turning point), so a
    turning point is one whose swing stands :data:`PEAK_STEPS` steps out beyond ten
    times the noise other than rounding; the noise is at least step/√12 (a rest on one
    level shows none). A rounded swing reads in whole steps, so the threshold is half a
    step below :data:`PEAK_STEPS` (a swing between the levels two steps apart reads
    2.0 steps, give or take the rounding of floating point, and one a step apart 1.0).
    The rest band: a rest on a coarse channel holds one level, or two neighbouring ones
    where its other noise straddles their boundary (a range of one step); a swing across
    three levels (two steps) is motion. The band is √((3/4 step)² + (4 × other)²): a
    range of 1.5 steps without other noise, four sd of that noise where it dominates,
    and never wider than the unquantised band of four times the level (at least
    step/√12).
    """
    if step is None:
        return sigma, PEAK_THRESHOLD, None
    rounding = step * QUANTISATION_NOISE_FACTOR
    level = max(sigma or 0.0, rounding)
    other = math.sqrt(max(level * level - rounding * rounding, 0.0))
    floor = max(PEAK_THRESHOLD * other, (PEAK_STEPS - 0.5) * step)
    band = math.hypot(0.75 * step, 4.0 * other)
    return level, floor / level, band


def _despiked(
    t: NDArray, x: NDArray | None, v: NDArray | None
) -> tuple[NDArray | None, NDArray | None]:
    """The channels with their isolated spikes bridged (:mod:`bayestribo.signal.spikes`),
    and a :class:`~bayestribo.signal.spikes.SpikeWarning` naming them when there are
    any; the arrays given are not changed."""
    out = []
    said = []
    for name, s in (("displacement", x), ("velocity", v)):
        spikes = np.zeros(0, dtype=int) if s is None else find_spikes(s)
        if s is None or spikes.size == 0:
            out.append(s)
            continue
        said.append(describe(name, t, s, spikes))
        out.append(bridged(s, spikes))
    if said:
        warn(
            "; ".join(said) + ": single samples far off their neighbours (a sensor "
            "dropout); they are left out of the analysis (each replaced by the median of the five "
            "samples about it, the recording unchanged); if they are not spikes, crop the "
            "record around them (--window T0:T1)",
            SpikeWarning,
        )
    return out[0], out[1]


def _flattened(
    t: NDArray,
    x: NDArray | None,
    v: NDArray | None,
    peaks: Peaks,
    step: float,
    half_period: float,
) -> tuple[int, str] | None:
    """Leading turning points to leave out for soft clipping, and what to say of them.

    The recorded displacement ``x`` is checked at its turning points, the recorded
    velocity ``v`` at its extremes (one between each two turning points; v'' = -ω²v
    there, friction or not): a flattened velocity extreme between turning points k and
    k + 1 leaves out turning points up to k + 1. None when neither is flattened.
    ``step`` is the sample step [s], ``half_period`` the damped half period [s].
    """
    half_width = max(1, round(2.0 * half_period / step / 12.0))
    found = []
    if x is not None:
        flat = flattened_turning_points(t, x, peaks.index, peaks.value, half_width)
        if flat is not None and flat.count:
            found.append((flat.count, "turning points", "displacement", flat))
    if v is not None and len(peaks) > 1:
        index = np.asarray(peaks.index, dtype=int)
        extremes = np.array(
            [a + int(np.argmax(np.abs(v[a:b]))) for a, b in itertools.pairwise(index)]
        )
        flat = flattened_turning_points(t, v, extremes, v[extremes], half_width)
        if flat is not None and flat.count:
            found.append((flat.count + 1, "velocity extremes", "velocity", flat))
    if not found:
        return None
    count, what, channel, flat = max(found, key=lambda f: f[0])
    said = (
        f"soft clipping: the first {flat.count} {what} (swings of {flat.level:.4g} and "
        f"more) bend up to {float(np.max(flat.deficit[: flat.count])):.1%} less at their "
        f"peaks than the smaller swings say a linear oscillator does: the {channel} sensor "
        "saturates" + (" (or the spring softens)" if channel == "displacement" else "")
    )
    if channel == "displacement":
        # a pendulum's bob recorded as a length, x = r sin θ, bends so: no sensor's fault
        from bayestribo.signal.pendulum_arm import arm_advice, simple_pendulum_arm

        arm = simple_pendulum_arm(peaks.t, peaks.value)
        if arm is not None:
            said += f"; or, in metres, {arm_advice(arm)}"
    return count, said


def _irregular_start(spacing: RegularTurningPoints, peaks: Peaks, skipped: str, least: int) -> int:
    """Leave out the turning points before the regular run of ``spacing`` (beyond the
    ``skipped`` oscillations), saying which and why in an
    :class:`~bayestribo.signal.motion.IrregularStartWarning`; return how many.

    Raises
    ------
    RecordingError
        When fewer than ``least`` turning points remain from the regular run on, naming
        the intervals off and where the spacing becomes regular.
    """
    start = spacing.start
    off = spacing.off
    said = spacing.describe(off[off < start])
    remain = len(peaks) - start
    if remain < least:
        raise RecordingError(
            f"turning points: {said}; the spacing is regular only from turning point "
            f"{start} (t = {float(peaks.t[start]):.6g} s) on, where {remain} turning points "
            f"remain; {least} are needed: is the record of a free decay (not driven, the "
            "swings small enough for one period)?"
        )
    times = ", ".join(f"{float(tp):.6g}" for tp in peaks.t[:start])
    warn(
        f"irregular start: {said}; the first {start} turning points (0 to {start - 1}, at "
        f"t = {times} s) are left out: the analysis starts at turning point {start} "
        f"(t = {float(peaks.t[start]):.6g} s), where the spacing becomes regular, instead "
        f"of after {skipped} (large swings whose period depends on the amplitude, or a "
        "start still driven, are not of the free decay at one frequency)",
        IrregularStartWarning,
    )
    return start


def _equilibrium_from(
    peaks: Peaks,
    start: int,
    offset: float | Literal["auto", "constant"] | None,
    noise: float | None = None,
) -> Peaks:
    """The turning points about the equilibrium estimated from turning point ``start``
    on, as :func:`~bayestribo.signal.peaks.find_peaks` estimates it from all of them
    (Eq. 20: the irregular ones before do not follow it); unchanged for an ``offset``
    given as a number or None, or when fewer than 4 remain. ``noise``: the turning
    points' noise [signal unit] where it exceeds their value noise (a derived
    displacement's wander)."""
    if not isinstance(offset, str) or len(peaks) - start < 4:
        return peaks
    value_noise = peaks.value_noise if noise is None else max(noise, peaks.value_noise)
    raw = peaks.value + (peaks.offset + peaks.drift * peaks.t)
    tail = peaks.stop_time
    rest_raw = (
        None
        if peaks.rest_value is None or tail is None
        else peaks.rest_value + peaks.offset + peaks.drift * tail
    )
    if offset == "auto" and len(peaks) - start >= 8:
        level, slope = estimate_offset(raw[start:], peaks.t[start:], drift=True, noise=value_noise)
    else:
        level, slope = estimate_offset(raw[start:], noise=value_noise)[0], 0.0
    return replace(
        peaks,
        value=raw - (level + slope * peaks.t),
        offset=level,
        drift=slope,
        rest_value=None if rest_raw is None else rest_raw - level - slope * float(tail),
    )


def _clipped_start(found: tuple[int, str], n_peaks: int, least: int, how: str) -> int:
    """The turning point the analysis starts at after clipped ones (soft or hard):
    ``found`` is (their count, what was found); said with a ClippingWarning, or refused
    when fewer than ``least`` turning points remain after them."""
    count, said = found
    if n_peaks < count + least:
        raise RecordingError(
            f"{said}; {n_peaks - count} turning points remain after them, {least} are "
            "needed: record with a smaller initial displacement or a larger sensor range"
        )
    warn(
        f"{said}; {how}; record with a smaller initial displacement or a larger sensor "
        "range to keep them",
        ClippingWarning,
    )
    return count


def _hard_clipped(
    t: NDArray, x: NDArray | None, v: NDArray | None, peaks: Peaks, period: float
) -> tuple[int, str] | None:
    """Turning points to leave out for a signal cut flat (hard clipping), and what to
    say of them: every turning point before the end of the last clipped run of a
    recorded channel (:func:`bayestribo.signal.clipping.hard_clips`). None when no
    channel is clipped."""
    found = []
    for name, s in (("displacement", x), ("velocity", v)):
        if s is None:
            continue
        for clip in hard_clips(t, s, period):
            _, last = clip.times(t)
            count = int(np.count_nonzero(peaks.t <= last))
            found.append((count, clip.describe(name, t)))
    if not found:
        return None
    count = max(c for c, _ in found)
    return count, "hard clipping: " + "; ".join(said for _, said in found)


def _check_coverage(
    t: NDArray,
    start: int,
    stop: int,
    release: float,
    window: Peaks,
    left_out: int,
    stop_time: float | None,
    unresolved: str | None = None,
    *,
    faded: str | None = None,
) -> None:
    """Warn (:class:`~bayestribo.signal.coverage.ShortAnalysisWarning`) when the
    analysed samples ``t[start:stop]`` cover less than half of the recorded motion,
    saying why: the turning points that end before the motion does, the swings a
    coarse quantiser does not resolve (``unresolved``, its steps), a decay that fades
    (``faded``, in words), or the cycles left out at the start."""
    motion_end = float(t[-1]) if stop_time is None else float(stop_time)
    last_turn = float(window.t[-1])
    if unresolved is not None:
        end, why = (
            float(t[stop - 1]),
            f"the later amplitudes are below {RESOLVED_STEPS:g} quantisation step(s) "
            f"({unresolved})",
        )
    elif faded is not None:
        end, why = float(t[stop - 1]), faded
    elif stop_time is None and motion_end - last_turn > 0.5 * (motion_end - release):
        end, why = (
            last_turn,
            (f"its last turning point standing out of the noise is at {last_turn:.6g} s"),
        )
    else:
        end = float(t[stop - 1])
        why = (
            f"{left_out} turning points are left out at the start"
            if left_out
            else "the oscillations skipped after the release are that long"
        )
    note = coverage_note(float(t[start]), end, release, motion_end, why)
    if note is not None:
        warn(note, ShortAnalysisWarning)


#: Samples a period below which a velocity-only record's displacement is integrated
#: as an oscillator's (:mod:`bayestribo.signal.integration`): at any rate. The
#: trapezoids' error, though of the square of the step, is not below what the windows
#: of a velocity-only record resolve: at 300 samples a period (the paper's rig) the
#: damping's part of it, (ωh)²ζ/6 times the velocity, shifts the displacement against
#: the velocity, and the windows' μ_k came out 5e-4 low at the largest swings, tens of
#: their sd (``tests/test_adequacy_velocity_only.py``).
OSCILLATOR_RULE_SAMPLES = math.inf


def _integrated(
    t: NDArray, v: NDArray, period: float, release: int | None, stop: int | None
) -> tuple[NDArray, complex | None]:
    """The displacement of a velocity-only record, 0 at its first sample, and the pole
    it was integrated with (None for the trapezoids).

    Below :data:`OSCILLATOR_RULE_SAMPLES` samples a period (any rate), integrated as a
    damped oscillation with kinks at its turning points, its pole fitted to the velocity
    over the motion (:func:`~bayestribo.signal.integration.oscillation_pole`); otherwise,
    or when no pole fits, by the trapezoidal rule with its gain at the record's
    frequency, (ωh/2)cot(ωh/2) (0.967 at 10 samples a period), divided out as the
    channel check does (signal/channels.py).
    """
    step = sample_step(t)
    if period / step < OSCILLATOR_RULE_SAMPLES:
        lo = 0 if release is None else int(release)
        hi = t.size if stop is None else min(t.size, int(stop) + 1)
        pole = oscillation_pole(t[lo:hi], v[lo:hi])
        if pole is not None:
            return integrate_oscillation(t, v, pole), pole
    x = cumulative_trapezoid(v, t, initial=0.0)
    half = math.pi * step / period
    if 0.0 < half < 1.0:
        x /= half / math.tan(half)
    return x, None


def _head(peaks: Peaks, count: int) -> Peaks:
    """The first ``count`` turning points of ``peaks``."""
    return replace(peaks, t=peaks.t[:count], value=peaks.value[:count], index=peaks.index[:count])


def _steps_text(steps: tuple[float | None, float | None]) -> str:
    names = ("displacement", "velocity")
    return ", ".join(f"{n} {q:.3g}" for n, q in zip(names, steps, strict=True) if q is not None)


def _check_plausible(peaks: NDArray, natural_hz: float, derived: str | None) -> None:
    """Refuse a record in metres whose swing and frequency no rig makes.

    A displacement in millimetres read as metres (a MATLAB variable without a unit, a
    column named in the wrong unit with the velocity scaled alike, so that the two
    channels agree) gives a swing of metres at tens of hertz: peak speeds of hundreds
    of m/s, and a friction coefficient of 30 that converges. Peak speeds 2πfA above
    :data:`MAX_SPEED` are refused with the factor that brings them to a rig's and the
    option that applies it. (A limit on the acceleration would refuse a stiff rig: a
    0.3 mm swing at 1 kHz is 1200 g, and 1.9 m/s.)
    """
    amplitude = float(np.max(np.abs(peaks))) if peaks.size else 0.0
    speed = 2.0 * math.pi * natural_hz * amplitude
    if not speed > MAX_SPEED:
        return
    power = 3  # the factor 10^-power: millimetres, micrometres, nanometres read as metres
    while speed * 10.0**-power > MAX_SPEED and power < 12:
        power += 3
    factor = 10.0**-power
    unit = {3: "mm", 6: "µm", 9: "nm"}.get(power, f"{factor:g} m")
    channels = f"--scale x={factor:g}" + (f" --scale v={factor:g}" if derived is None else "")
    raise RecordingError(
        f"plausibility: a swing of {amplitude:.3g} m at {natural_hz:.4g} Hz means peak "
        f"speeds of {speed:.3g} m/s, which no free-decay rig makes (at most "
        f"{MAX_SPEED:g} m/s): the signals are likely in {unit} (a factor {factor:g}); give "
        f"the units in the column names (displacement_{unit}), or {channels}; or "
        "length_unit 'arbitrary' when the unit is unknown"
    )


def _rest_mask(t: NDArray, first: EnergyDecay) -> NDArray:
    """Samples at rest found by a first analysis (a quarter period from the motion)."""
    margin = 0.25 / first.natural_frequency_Hz
    rest_until = first.release_time if "rest before release" in first.noise.source else None
    stop = first.stop_time if "rest after stop" in first.noise.source else None
    return _quiet_segments(t, rest_until, stop, margin)


def _with_edges(
    t: NDArray, span: MotionSpan, edges: tuple[float | None, float | None]
) -> MotionSpan:
    """``span`` with its release and end of motion where another channel shows them
    (``edges`` [s], each None to keep the span's; one outside the record is not
    used). The end is moved only where the span itself ends in a stop: where it finds
    the oscillation fading into the noise, or going on to the record's end, that is
    kept (an acceleration under a mains line 2.5 times its noise showed a stop 0.1 s
    before the last swings, and μ_s/μ_k came out 7.3 [1.8, 9.9] where it is 1: the
    fade leaves it unconstrained)."""
    release, stop = edges
    changes: dict[str, Any] = {}
    if release is not None and t[0] < release < t[-1]:
        index = int(np.searchsorted(t, release, side="right")) - 1
        changes.update(release_index=index, release_time=float(release))
    if stop is not None and t[0] < stop < t[-1] and span.motion_ended:
        index = int(np.searchsorted(t, stop, side="right")) - 1
        changes.update(stop_index=index, stop_time=float(stop))
    return replace(span, **changes) if changes else span


def _analyse(
    t: NDArray,
    x: NDArray | None,
    v: NDArray | None,
    *,
    rig: Rig | None,
    skip_oscillations: int,
    use_nominal_frequency: bool,
    frequency_Hz: float | None,
    jitter: float,
    skip_turning_points: int | None,
    min_turning_points: int | None,
    offset: float | Literal["auto", "constant"] | None,
    motion_threshold: float,
    notch_Hz: tuple[float, ...],
    linear_spring: bool = True,
    acceleration_edges: tuple[float | None, float | None] | None = None,
) -> EnergyDecay:
    """:func:`energy_decay` on checked (and notched) signals."""
    least_by_default = min_turning_points is None
    if min_turning_points is None:
        min_turning_points = 2 * MIN_OSCILLATIONS
    derived: str | None = None
    velocity_offset = 0.0
    pole: complex | None = None
    reference = x if x is not None else v
    try:
        period0 = dominant_period(t, reference)
    except RecordingError as e:
        raise RecordingError(f"release: no motion found: {e}") from e
    per_samples = period0 / sample_step(t)
    if per_samples < MIN_PERIOD_SAMPLES:
        raise RecordingError(
            f"release: no motion found: the record's dominant period is {per_samples:.1f} "
            f"samples long; a free decay needs at least {MIN_PERIOD_SAMPLES} samples per "
            "period to locate its turning points (is there an oscillation above the noise, "
            "sampled fast enough?)"
        )
    v_span = v if v is not None else derive_velocity(t, x, period0)[0]
    x_step = None if x is None else quantisation_step(x)
    span = motion_span(
        t,
        v_span,
        period0,
        threshold=motion_threshold,
        displacement=x if v is None else None,
        # levels dithered finely by the noise are a continuous signal's: their toggling
        # at the rig's frequency marked a block holding the last swing and a rest
        # shorter than a block as motion, and the stop was not found
        periodic=x if x_step is not None and not finely_dithered(x, x_step) else None,
        velocity_alone=x is None,
        beside=x if v is not None else None,
    )
    if span.bounds is not None:
        # other motions than the largest (runs back to back, a knock after the stop):
        # they are not its rest; the record is analysed again without them
        lo_b, hi_b = span.bounds
        spans = ", ".join(f"t = {a:.6g} to {b:.6g} s" for a, b in span.others)
        warn(
            f"release: the record holds another motion than its largest ({spans}; another "
            "release, a knock), which is not a rest: the analysis takes the largest motion "
            f"and the rests beside it, t = {t[lo_b]:.6g} to {t[hi_b - 1]:.6g} s, and leaves "
            "the other out; give a window of the record's time (--window T0:T1) to analyse "
            "another",
            SeparateMotionWarning,
        )
        part = slice(lo_b, hi_b)
        return _analyse(
            t[part],
            None if x is None else x[part],
            None if v is None else v[part],
            rig=rig,
            skip_oscillations=skip_oscillations,
            use_nominal_frequency=use_nominal_frequency,
            frequency_Hz=frequency_Hz,
            jitter=jitter,
            skip_turning_points=skip_turning_points,
            min_turning_points=None if least_by_default else min_turning_points,
            offset=offset,
            motion_threshold=motion_threshold,
            notch_Hz=notch_Hz,
            linear_spring=linear_spring,
            acceleration_edges=acceleration_edges,
        )
    if acceleration_edges is not None and x is None:
        span = _with_edges(t, span, acceleration_edges)
    released_at = span.release_index
    rest_until = None if released_at is None else float(t[released_at])
    # a decay that fades into the noise (a velocity alone): its rest starts where its
    # oscillation ends, and the analysis ends where its swings sink below the threshold
    stop_time = span.stop_time if span.fade_time is None else span.fade_time

    quiet = _quiet_segments(t, rest_until, stop_time, 0.25 * period0)
    coarse_fade = None
    offset_drifts = False
    if x is None:
        derived = "displacement"
        at_rest = _rest_samples(v, t, rest_until, stop_time, 0.0)
        if at_rest.size >= MIN_QUIET_SAMPLES and acceleration_edges is None:
            velocity_offset = float(np.median(at_rest))
            drifting = _offset_drift(t, v, rest_until, stop_time, span.noise)
            v = v - (velocity_offset if drifting is None else drifting)
            if drifting is not None:
                velocity_offset = float(drifting[0])
                offset_drifts = True
        x, pole = _integrated(t, v, period0, released_at, span.stop_index)
        v_step = quantisation_step(v)
        if (
            v_step is not None
            and at_rest.size >= MIN_QUIET_SAMPLES
            and coarse_steps((None, v_step), (None, float(np.std(at_rest))))[1] is not None
        ):
            # a coarse velocity resolves no swing of the displacement below a step of
            # it, ω|Y| < q_v: there the integral's turning points are the rounding's
            coarse_fade = FADE * RESOLVED_STEPS * v_step * period0 / (2.0 * math.pi)
        sigma_x = None
        # the derived displacement's noise over two periods at rest (its wander, which
        # a sample-to-sample estimate does not see): where its swings fade into it
        band_x = block_noise(t, x, quiet, span.block)
    else:
        sigma_x = block_noise(t, x, quiet, span.block)
        band_x = sigma_x

    # Turning points inside the motion only: the rest holds none (a wiggle of the
    # noise there is not one), and the noise threshold is the one measured at rest.
    lo = 0 if released_at is None else int(released_at)
    hi = t.size
    if span.stop_index is not None:
        hi = min(t.size, int(span.stop_index) + 2 + span.block // 8)
    coarse_cut = None
    if coarse_fade is not None:
        # a coarse velocity alone: where its swing is within FADE steps (ω|Y| below
        # FADE q_v) the integral's turning points are the rounding's, its mean over a
        # cycle changing with the swing; the turning points are looked for before that
        cut = swing_end(v, v_step, period0 / sample_step(t), 2.0 * FADE * RESOLVED_STEPS)
        if cut is not None and lo < cut < hi:
            hi, coarse_cut = cut, float(t[cut - 1])
    if sigma_x is None and x_step is not None:
        sigma_x = estimate_noise(x[lo:hi])  # as find_peaks would, floored below
    peak_noise, peak_threshold, rest_band = _peak_noise(sigma_x, x_step)
    if (
        peak_noise is not None
        and peak_noise * peak_threshold >= 0.5 * float(np.ptp(x[lo:hi]))
        and _dithered_rest(t, x, x_step, rest_until, stop_time, period0)
    ):
        # a threshold of the first swing's amplitude or more, from a rest toggling
        # between two levels: the rounding's spread, not a noise of its size
        peak_noise, peak_threshold, rest_band = _peak_noise(None, x_step)
    try:
        # the record's period, which set the motion span (not estimated again on it)
        found = find_peaks(
            t[lo:hi],
            x[lo:hi],
            kind="displacement",
            min_peaks=2,
            offset=offset,
            noise=peak_noise,
            threshold=peak_threshold,
            rest_band=rest_band,
            period=period0,
        )
    except RecordingError as e:
        raise RecordingError(f"turning points: {e}") from e
    peaks = replace(found, index=found.index + lo)
    if derived == "displacement":
        peaks = _integral_turning_values(t, x, v, peaks, period0)
    fade_span = None
    if span.fade_time is not None:
        fade_span = float(peaks.t[-1])
        warn(
            f"turning points: the decay fades into the noise after turning point "
            f"{len(peaks) - 1} (t = {fade_span:.6g} s): its velocity's swings sink below "
            f"{span.threshold:.3g} ({motion_threshold:g} times the noise at rest) at "
            f"t = {span.stop_time:.6g} s and its oscillation goes on under them until "
            f"t = {span.fade_time:.6g} s, without stopping (a viscous decay); the analysis "
            "ends at that turning point, the last before the swings sink, as for a record "
            "that ends in motion",
            FadeWarning,
        )
    elif coarse_cut is not None:
        fade_span = float(peaks.t[-1])
        warn(
            f"turning points: the decay fades into the velocity's steps of {v_step:.3g} "
            f"after turning point {len(peaks) - 1} (t = {fade_span:.6g} s): from "
            f"t = {coarse_cut:.6g} s on its swing over a period is within "
            f"{2 * FADE * RESOLVED_STEPS:g} steps, where the displacement integrated from "
            "it follows the rounding more than the motion; the analysis ends at that "
            "turning point, as for a record that ends in motion",
            FadeWarning,
        )
    # the free decay starts where the turning points are half a period apart
    fade_level = None if not band_x else FADE * PEAK_THRESHOLD * band_x
    if coarse_fade is not None:
        fade_level = max(fade_level or 0.0, coarse_fade)
    if (
        span.stop_index is not None
        and fade_level is not None
        and split_stop(peaks.t, peaks.value, fade_level)
    ):
        # the stop's turning point found twice on its plateau's noise: the first is it
        peaks = _head(peaks, len(peaks) - 1)
    spacing = regular_turning_points(
        peaks.t,
        peaks.value,
        timing_sd=_timing_sd(t, peaks),
        tolerance=SPACING_TOLERANCE if linear_spring else math.inf,
        fade_level=fade_level,
    )
    faded_at = None
    if spacing.faded is not None:
        # the decay fades into the noise: its last swings' turning points are the
        # noise's; the analysis ends at the last turning point before them, as a record
        # that ends in the motion
        faded_at = float(peaks.t[spacing.faded - 1])
        warn(
            f"turning points: the decay fades into the noise after turning point "
            f"{spacing.faded - 1} (t = {faded_at:.6g} s): the {len(peaks) - spacing.faded} "
            f"turning points after it, of swings within {fade_level:.3g} ({FADE:g} times "
            "the turning points' threshold over the noise at rest), break the decay's half "
            "period; the analysis ends there",
            FadeWarning,
        )
        peaks = _head(peaks, spacing.faded)
    elif fade_span is not None:
        faded_at = fade_span
    # a derived displacement's turning points carry its wander (band_x), which its
    # sample-to-sample noise does not show: weighted by that alone, the smallest swings
    # weighed most in the equilibrium's fit, and its drift followed their wander
    wander = band_x if derived == "displacement" and band_x else None
    if spacing.start or faded_at is not None or derived == "displacement":
        # the equilibrium from the decay's own turning points (those of an irregular
        # start do not follow Eq. 20, nor those of the noise after a fade)
        peaks = _equilibrium_from(peaks, spacing.start, offset, noise=wander)
    peaks = replace(
        peaks, stop_time=stop_time if span.fade_time is None and coarse_cut is None else None
    )
    period = 2.0 * spacing.half_period
    if v is None:
        derived = "velocity"
        v, _ = derive_velocity(t, x, period)

    if skip_turning_points is not None:
        release = float(peaks.t[0]) if released_at is None else float(t[released_at])
        skip = int(skip_turning_points)
        skipped = f"{skip} turning points"
    elif released_at is None:
        # The record starts in motion: count oscillations from its first extremum.
        release = float(peaks.t[0])
        skip = 2 * int(skip_oscillations)
    else:
        # The held position is the release's turning point; the first extremum found
        # is half an oscillation later.
        release = float(t[released_at])
        skip = max(2 * int(skip_oscillations) - 1, 0)
    if skip_turning_points is None:
        skipped = f"{skip_oscillations} oscillations"
    base_skip = skip
    irregular = 0
    if spacing.start > skip:
        irregular = _irregular_start(spacing, peaks, skipped, int(min_turning_points))
        skip = irregular
    left_out = 0
    rest_until = None if released_at is None else release
    # the oscillation a fade leaves under the noise is not the rest's noise
    v_rest = v if span.fade_time is None else _without_faded(t, v, stop_time, peaks, period)
    # a mass that creeps on after the stop is not at rest: its creep is not the noise
    # (a velocity alone whose offset drifts, said by its OffsetDriftWarning, moves its
    # integral at rest as a creep would: its rest is not tested)
    creep = (
        None
        if span.fade_time is not None or offset_drifts
        else _creep(t, x, v, stop_time, period, derived, peaks, rest_until)
    )
    rest_stop = stop_time if creep is None else None
    noise = _noise(t, x, v_rest, rest_until, rest_stop, period, derived, jitter)
    if creep is not None:
        warn(
            f"rest: {creep.describe()}. No law's motion creeps (a friction sticks, a drag "
            "oscillates on): the friction vanishes towards zero speed, and a law's ΔE(A) "
            "at the smallest swings is not to be trusted; the turning points' ΔE(A) "
            "(printed as 'turning points (law-free)') holds whatever the law. The creep "
            f"is not rest: the noise is measured from the {noise.source} instead"
            + (
                ""
                if isinstance(creep, Creep)
                else " (with one channel a creep is told from a sensor's drift by its path "
                "alone: recording both channels tells them apart by their agreement)"
            ),
            CreepWarning,
        )
    motion_ended = stop_time is not None and faded_at is None
    truncated = False
    coarse = coarse_steps(
        (noise.displacement_step, noise.velocity_step), (noise.displacement, noise.velocity)
    )
    few = few_steps_note(
        (
            x[lo:hi] if derived != "displacement" else None,
            v[lo:hi] if derived != "velocity" else None,
        ),
        coarse,
    )
    if derived == "displacement" and coarse[1] is not None:
        warn(
            f"coarse digitiser: the displacement is the integral of the velocity, whose "
            f"steps of {coarse[1]:.3g} its noise does not dither; their rounding "
            "accumulates in the integral (its turning points and equilibrium), which the "
            "noise model does not hold: the intervals are not calibrated (on simulated "
            "records at 10 steps across the swing the means were off by up to 9 sd); a "
            "recorded displacement, or a finer velocity range, gives a record that can "
            "be fitted",
            CoarseSignalWarning,
        )
    if few is not None:
        warn(
            f"coarse digitiser: {few}; below {MIN_SWING_STEPS} steps the turning points "
            "stand on a few levels and the intervals are not calibrated (on simulated "
            "records at 3 steps they covered ζ and μ_k in 20 fits of 20, but wide and "
            "their centres off alike, μ_k's one sd above the truth in each); a finer "
            "range or gain of the recorder gives a record that can be fitted",
            CoarseSignalWarning,
        )
    flattened = (
        None
        if not linear_spring
        else _flattened(
            t,
            # recorded channels only (a derived one is distorted by its derivation), and
            # not a coarse one (its extremes dwell on a level, however round the motion)
            x if derived != "displacement" and coarse[0] is None else None,
            v if derived != "velocity" and coarse[1] is None else None,
            peaks,
            period0 / per_samples,
            spacing.half_period,
        )
    )
    if flattened is not None and flattened[0] > skip:
        skip = left_out = _clipped_start(
            flattened,
            len(peaks),
            int(min_turning_points),
            f"they are left out: the analysis starts at turning point {flattened[0]} "
            f"(instead of after {skipped})",
        )
    clipped = _hard_clipped(
        t,
        x if derived != "displacement" else None,
        v if derived != "velocity" else None,
        peaks,
        period0,
    )
    if clipped is not None and clipped[0] > skip:
        count = clipped[0]
        start = f"t = {float(peaks.t[count]):.6g} s" if count < len(peaks) else "none"
        skip = left_out = _clipped_start(
            clipped,
            len(peaks),
            int(min_turning_points),
            f"the clipped cycles are left out: the analysis starts at turning point {count} "
            f"({start}) instead of after {skipped}",
        )
    least = int(min_turning_points)
    if coarse != (None, None) and least_by_default:
        # a coarse record's swings may sink below two steps within three oscillations:
        # analysed on two (signal/coarse.py), the first one too when it is what it lacks
        omega_d = math.pi / spacing.half_period
        chosen = coarse_window(
            len(peaks),
            lambda s: min(
                resolved_turning_points(peaks.value[s:], omega_d, coarse) + 1, len(peaks) - s
            ),
            skip,
            least,
            keep_skip=skip != base_skip or skip_turning_points is not None,
        )
        if chosen.note is not None:
            if chosen.skip != skip:
                skipped = "0 oscillations"
            skip, least = chosen.skip, chosen.least
            warn(
                f"coarse digitiser: only {len(peaks)} turning points after the release "
                f"stand out of the rounding (steps {_steps_text(coarse)}): the analysis "
                f"takes {chosen.note}; with so short a decay ζ and μ_k are told apart "
                "by little, and the intervals are wide (on simulated records at 3 steps "
                "across the swing they covered ζ and μ_k in each of 9 such fits, μ_k's "
                "reaching 10 to 20 times μ_k); a finer range or gain of the recorder "
                "gives a record that can be fitted",
                CoarseSignalWarning,
            )
    elif least_by_default and len(peaks) < skip + least:
        # a short free decay (high friction stops it within two or three oscillations,
        # or the record ends after two): analysed on what it holds, down to two
        # oscillations, the first one too when it is what it lacks (signal/coarse.py)
        chosen = coarse_window(
            len(peaks),
            lambda s: len(peaks) - s,
            skip,
            least,
            keep_skip=skip != base_skip or skip_turning_points is not None,
        )
        if chosen.note is not None:
            if chosen.skip != skip:
                skipped = "0 oscillations"
            skip, least = chosen.skip, chosen.least
            warn(short_decay_note(len(peaks), chosen.note, motion_ended), ShortAnalysisWarning)
    min_turning_points = least
    needed = skip + int(min_turning_points)
    if len(peaks) < needed:
        why = ""
        if coarse[0] is not None and derived != "displacement":
            why = (
                f"; the displacement is quantised in steps of {coarse[0]:.3g} that its "
                f"noise does not dither ({float(np.ptp(x[lo:hi])) / coarse[0]:.0f} steps "
                "across its swing), and a swing of less than two steps is no turning point: "
                f"the swings after turning point {len(peaks) - 1} (t = "
                f"{float(peaks.t[-1]):.6g} s) hold fewer"
            )
            if least_by_default:
                kept = min(
                    resolved_turning_points(peaks.value, math.pi / spacing.half_period, coarse) + 1,
                    len(peaks),
                )
                why += (
                    f" (a coarse record is analysed on {MIN_COARSE_TURNING_POINTS} turning "
                    "points at least, the first oscillation's included, up to the one "
                    f"after the last of a swing of {RESOLVED_STEPS:g} step(s) or more "
                    f"about the equilibrium: {kept} here)"
                )
        if least_by_default and coarse == (None, None) and skip == base_skip:
            # below the short decay's least (signal/short.py): the count it needs
            raise RecordingError(
                f"turning points: the recording holds {len(peaks)} turning points after "
                f"the release; {MIN_COARSE_TURNING_POINTS} are needed at least (two "
                "oscillations, the first one after the release included; "
                f"{skip + int(min_turning_points)} for the full analysis, "
                f"{min_turning_points} after skipping {skipped}): is the record of a free "
                "decay, and does it hold two oscillations of it?"
            )
        if (
            skip_turning_points is None
            and skip == base_skip > 0
            and len(peaks) >= int(min_turning_points)
        ):
            # the first oscillation, skipped by default (the release's transient), is
            # what a short record needs: say so, as an option that can be followed
            why += (
                f"; skip_oscillations=0 (--skip 0) analyses the first oscillation too, "
                f"which leaves {len(peaks)} turning points"
            )
        raise RecordingError(
            f"turning points: the recording holds {len(peaks)} turning points after the "
            f"release; {needed} are needed ({min_turning_points} turning points after "
            f"skipping {skipped}){why}"
        )
    window = peaks.skip(skip)
    resolved = resolved_turning_points(window.value, math.pi / spacing.half_period, coarse)
    if coarse != (None, None) and (resolved < len(window) or motion_ended):
        # a coarse channel resolves neither the last swings nor the end of motion (a
        # velocity below half a step reads as rest cycles before the pin sticks, and
        # turning points of the smallest swings go unfound): the analysis ends at the
        # turning point after the last it resolves (the swing down to it starts
        # resolved), like a record that ends in motion
        kept = min(resolved + 1, len(window))
        if kept < int(min_turning_points):
            raise RecordingError(
                f"turning points: only {resolved} turning points after skipping {skipped} "
                f"have an amplitude of {RESOLVED_STEPS:g} quantisation step(s) or more "
                f"(steps {_steps_text(coarse)}); {min_turning_points} are needed"
            )
        window = _head(window, kept)
        motion_ended = False
        truncated = True
    colour = _rest_colour(t, x, v, rest_until, rest_stop, period, derived)
    kept_above = wander_end(window.value, colour, int(min_turning_points))
    if kept_above is not None and not goes_on(t, x, stop_time, period):
        kept_above = None  # a stop, not a fade: the rest after it holds no oscillation
    if kept_above is not None and colour is not None:
        window = _head(window, kept_above)
        faded_at = float(window.t[-1])
        motion_ended = False
        warn(
            f"turning points: the decay fades into {colour.describe()}: its wander moves "
            "the equilibrium and the energy of the smallest swings alike over many "
            "increments, which the noise model, spanning a few periods, does not hold; "
            f"the analysis ends at t = {faded_at:.6g} s, the last turning point whose "
            f"swing is at least {WANDER_FLOOR:g} times that rms "
            f"({WANDER_FLOOR * colour.rms:.3g})",
            FadeWarning,
        )
    # a coarse displacement's turning points stand on its levels: a decay within a
    # step reads as none there, but its swings then sink below the levels long before
    # the record ends (a driven oscillation's go on to its end)
    sinks = coarse[0] is not None and float(t[-1] - peaks.t[-1]) > 2.0 * period
    if stop_time is None and not sinks:
        amp = np.abs(window.value)
        if amp.size >= 6 and np.mean(amp[-3:]) >= 0.99 * np.mean(amp[:3]):
            raise RecordingError(
                "energy decay: the oscillation does not decay: its last turning points are "
                f"{100 * np.mean(amp[-3:]) / np.mean(amp[:3]):.1f} % of its first over "
                f"{window.t[-1] - window.t[0]:.3g} s and it does not stop; a free decay must "
                "lose amplitude (is the rig driven, or the record not of a free decay?)"
            )
    times = window.t if derived == "velocity" else _turning_times(t, v, window, period)
    damped_hz, natural_hz = _frequencies(times, window.value)
    if coarse[0] is not None:
        # the decrement of a coarse displacement's turning points (on its levels) is
        # not measured: √(1+β²) is left out, an error of β²/2 (3e-4 at ζ = 0.024),
        # where a decrement read off the levels gave a frequency 1.4 times the record's
        natural_hz = damped_hz
    # a rig whose frequency was itself measured from the record has no nominal one
    nominal_hz = None if rig is None or rig.frequency_measured else rig.natural_frequency_Hz
    if use_nominal_frequency and nominal_hz is None:
        raise RecordingError(
            "use_nominal_frequency: the rig's frequency is an estimate from the recording, "
            "not a nominal value (give natural_frequency_Hz)"
        )
    omega = 2.0 * math.pi * (nominal_hz if use_nominal_frequency else natural_hz)
    if frequency_Hz is not None:
        omega = 2.0 * math.pi * float(frequency_Hz)

    if rig is not None and rig.mass_kg is not None:  # a rig in SI units: lengths in m
        _check_plausible(window.value, natural_hz, derived)
    if rig is not None and rig.has_contact and rig.mass_kg is not None:
        scaling = Scaling(omega, rig.load_N / (rig.mass_kg * omega**2), friction_defined=True)
    else:
        scaling = Scaling(omega, 1.0, friction_defined=False)

    rest_noise = _rest_noise(t, x, v_rest, rest_until, rest_stop, period, derived)
    if derived is None and coarse[1] is None:
        # (a coarse velocity at rest sits on the level nearest its zero: the rest says
        # where that level is, not where the zero is, and the rounding, which averages
        # out while the velocity moves, is the variances' (signal/coarse.py))
        at_rest = _rest_samples(v, t, rest_until, rest_stop, 0.25 * period)
        if at_rest.size >= MIN_QUIET_SAMPLES:
            velocity_offset = float(np.median(at_rest))
            v = v - velocity_offset

    start = int(window.index[0])
    stop = t.size if stop_time is None else int(np.searchsorted(t, stop_time)) + 1
    if faded_at is not None:
        stop = min(stop, int(window.index[-1]) + 1)
    if truncated:
        # to the last sample the coarse channels still reach a step from their zero
        about = x - (peaks.offset + peaks.drift * t)
        last = resolved_end((about, v), coarse, int(window.index[-1]))
        stop = min(last, stop - 1) + 1
    stop = min(stop, t.size)
    _check_coverage(
        t,
        start,
        stop,
        release,
        window,
        max(left_out, irregular),
        stop_time,
        _steps_text(coarse) if truncated else None,
        faded=None
        if faded_at is None
        else (
            f"its velocity's swing over a period is within {2 * FADE * RESOLVED_STEPS:g} "
            f"of its steps of {v_step:.3g} from t = "
            f"{stamp(coarse_cut, float(t[-1] - t[0]), float(t[0]))} on"
            if coarse_cut is not None
            else "the decay fades into the noise after t = "
            f"{stamp(faded_at, float(t[-1] - t[0]), float(t[0]))}"
        ),
    )
    sl = slice(start, stop)
    # the same operations as x[sl] - (offset + drift t) and 0.5 (y² + y'²), in place
    relative = peaks.drift * t[sl]
    relative += peaks.offset
    np.subtract(x[sl], relative, out=relative)
    y = scaling.y(relative)
    del relative
    yp = scaling.yp(v[sl])
    tau = scaling.tau(t[sl] - t[start])
    energy = y * y
    energy += yp * yp
    energy *= 0.5
    energy_steps = None
    if pole is not None:
        # the oscillator's own ∫E between samples (Simpson's rule on E at 10 samples a
        # period errs by 1e-4 of an increment, hundreds of times a vibrometer's noise)
        x2, v2 = oscillation_energy(t[sl], v[sl], y * scaling.length_scale, pole)
        energy_steps = (0.5 * scaling.omega / scaling.length_scale**2) * (
            x2 + v2 / scaling.omega**2
        )
    return EnergyDecay(
        t=t[sl].copy(),
        tau=tau,
        y=y,
        yp=yp,
        energy=energy,
        pi=retrograde_integral(tau, energy),
        scaling=scaling,
        start_time=float(t[start]),
        end_time=float(t[stop - 1]),
        motion_ended=motion_ended,
        release_time=release,
        equilibrium=peaks.offset + peaks.drift * float(t[start]),
        equilibrium_drift=peaks.drift,
        velocity_offset=velocity_offset,
        natural_frequency_Hz=natural_hz,
        nominal_frequency_Hz=nominal_hz,
        damped_frequency_Hz=damped_hz,
        noise=noise,
        derived_channel=derived,
        savgol_window=savgol_window(t, period) if derived == "velocity" else None,
        peaks=window,
        rest_noise=rest_noise,
        notch_Hz=notch_Hz,
        stop_time=stop_time,
        turning_times=np.asarray(times, dtype=float).copy(),
        flattened_turning_points=left_out,
        irregular_turning_points=irregular,
        energy_steps=energy_steps,
        noise_colour=colour,
        wander_floor=None if kept_above is None else WANDER_FLOOR * colour.rms,
    )
