r"""The observation of the likelihood: Π(τ) on a grid, as independent increments.

Π is a running integral of E, so its errors are correlated: with white noise on the
samples, the error of Π(τ_k) is a sum over all samples after τ_k, and

.. math::  \mathrm{Cov}[Π(τ_k), Π(τ_l)] = V(\max(k, l)),\qquad V(m) = \sum_{i \ge m} v_i,

a random walk run backwards from the end of motion. Its increments
``D_j = Π(τ_j) - Π(τ_{j+1}) = ∫_{τ_j}^{τ_{j+1}} E`` are independent, so the Gaussian
likelihood of Π on the grid with that covariance factorises exactly into independent
Gaussians on the increments, with variances ``V_j = Σ_{i ∈ j} w_i² Var(E_i)``. That is
how :mod:`bayestribo.inference.likelihood` evaluates it: O(grid) per evaluation, and a grid
four times denser carries the same information instead of four times as much (the
mistake an independent-errors model on Π makes).

Per sample, with white noise ε on y and η on y' (standard deviations σ_y, σ_y'):
``E = ½((y+ε)² + (y'+η)²)`` has mean ``E_true + ½(σ_y² + σ_y'²)`` (removed here: the
bias that noise adds to squared signals) and variance ``y²σ_y² + y'²σ_y'² +
½(σ_y⁴ + σ_y'⁴)``. When one channel was derived from the other (a derivative or an
integral), its noise is correlated with the recorded channel's and across samples;
the increment variances and the bias are then obtained by propagating simulated noise
through the same processing (Monte Carlo, ``n_replicates`` seeded draws).

**An integrated displacement** holds the velocity's noise integrated, a random walk;
the decay measures it about an equilibrium and its drift fitted as a line, which takes
the walk's line with it, so the Monte Carlo takes the walk about its least-squares line
(:func:`detrended`). Taken from the decay's first sample instead, the walk's variance
grew along the record: on an independent simulation (a velocity alone, white noise)
the second half's increment variances came out 3 to 8 times too large and the noise
bias removed from them too large (mean standardised error −0.36; now +0.07 ± 0.04,
χ²/n 1.05, ``tests/test_signal_integrated_noise.py``). **An accelerometer's velocity**
is itself an integral, its drift taken off as the line between the rests: its noise in
the motion is a random walk held at the rests and free between them, larger than the
rest shows (2.7 times in sd over 3 s of motion), so the Monte Carlo draws the sensor's
white noise through the integration itself (:func:`accelerometer_draws`,
:func:`bayestribo.signal.velocity_integral.velocity_noise`) instead of the rest's spectrum
(χ²/n of the increments 3.1 with the spectrum, 0.86 now, on the same test's
dry-friction record), each variance at least that of the velocity's noise at rest in
the velocity alone (which holds the integration's residue there, its edges' ringing;
the rest's spectrum integrated into the displacement would wander over a long record,
its low frequencies extrapolated from a short rest).

**The increments of an accelerometer's record are correlated.** Its velocity noise
is a random walk held at the rests and its displacement that walk integrated: over a
half cycle y and y' change sign, so the increments' errors alternate about a slowly
varying level (correlation -0.63 between neighbours on a dry-friction record, +0.27
at lag 2, -0.23 at lag 4, as the Monte Carlo's -0.65, +0.29, -0.22; a run of four
increments has 0.4 times the sum of their variances). The Monte Carlo then draws at
least ten per increment and gives their covariance
(:mod:`bayestribo.signal.increment_correlation`, :attr:`PiData.correlation`), which
the likelihood whitens the increments with. A velocity recorded alone keeps
independent increments: with white noise at 40 samples a period its increments' errors
are uncorrelated once the equilibrium's line is out (lag 1: 0.01 over 90 draws), and
at 10 samples a period (integrated as an oscillator, the Monte Carlo by the
trapezoids) whitening with the draws' correlation narrowed intervals that were
already a little narrow (``benchmarks/misspecification.py --cases velocity-10``: ζ's
z sd 1.20 to 1.30 at 30 times the resolution).

**A velocity derived from the displacement** (its Savitzky-Golay derivative) shares
the displacement's noise within half the derivative's window of a boundary between
increments, with opposite signs in the two neighbours where the motion is fast
(∫ y'δy' = [y'δy] − ∫ y''δy). The linear spring's grid keeps its boundaries near
turning points (neighbours uncorrelated, +0.015); a nonlinear force's half cycles
drift through the grid (−0.24 to −0.26), and :func:`pi_data` gives the likelihood
their first-order correlation there
(:mod:`bayestribo.signal.derivative_correlation`).

**Coloured noise.** A real signal chain filters the noise (anti-alias filter), adds
mains lines and 1/f noise: the samples' errors are then correlated, and the variance
of a weighted sum of them is ``wᵀ C w`` with C the noise's autocovariance, not
``σ² ‖w‖²`` (for a 2 kHz anti-alias filter at 10 kHz the latter underestimates the
increments' variance 2.5-fold, at 100 kHz 25-fold). :func:`pi_data` takes C from the
spectrum measured at rest (:class:`bayestribo.signal.spectrum.NoiseSpectrum`) when it
is flagged coloured; white noise at rest keeps the white formula exactly. Coloured
noise also correlates neighbouring increments (C reaching across their boundary: a
few samples for a filter, negligible; 1/f noise 5 times the white noise gives a
correlation of about 0.17 between neighbours, and a sum of increments 1.3 times the
variance of independent ones): the positive part of that covariance is added to
both neighbours' variances, which gives every run of increments at least its
variance (exactly, for the whole record, when all are positive).

**Grid.** Finer increments carry more information, not the same information
counted twice: within a half cycle the noise of E varies from y²σ_y² at a turning
point to y'²σ_y'² at a zero crossing, where the vibrometer's velocity channel makes
E hundreds of times more precise. Increments shorter than a half cycle exploit that
sub-oscillation structure, which rests on white, independent channel noise and on
the exact calibration of both channels; the default grid therefore uses one
increment per half cycle (the scale at which the paper smooths E into Π), where
the information is the envelope's.

The integral over each increment uses composite Simpson weights (error O(h⁴); the
trapezoidal rule's O(h²) error on an oscillating E is comparable to the noise of a
vibrometer-grade record). The sample on a grid boundary belongs to both neighbouring
increments with weight h/3 in each (Simpson's end weight), so white noise correlates
neighbours too (:func:`shared_sample_covariance`): by about 1e-3 at 300 samples per
period, but by up to 1.2e-2 at 31 (1 kHz on the paper's rig), where a half cycle has
only 15 samples and its boundary sample, near a turning point, carries the largest
noise of E (y²σ_y²). Measured on the paper's rig at 1 kHz, leaving it out makes the
standard deviations of ζ and μ_k 0.5-0.7 % too small. Its positive part is added to
both neighbours' variances as for coloured noise.

**A coarse digitiser** (steps the noise does not dither, :mod:`bayestribo.signal.coarse`)
rounds the signal the same way wherever it passes a level: its error does not average
out over an increment, and its variances come from rounding the channels without their
noise with the levels placed at random (:func:`~bayestribo.signal.coarse.
quantised_increments`; the bias is Sheppard's q²/24 per channel, the rest spectrum is
not used), the white formula keeping the rest of the noise. Its errors alternate
between half cycles (correlation about -0.6 between neighbours: a level above the zero
at one turning point is below it at the next), so its default grid is one increment a
cycle, whose variance holds the two together (with one a half cycle, the independent
increments left ζ's and μ_k's intervals twice too wide, sd(z) 0.47).

**A velocity-only record integrated as an oscillator** (below 50 samples a period,
:mod:`bayestribo.signal.integration`) carries the oscillator's exact ∫E between its
samples (:attr:`~bayestribo.signal.decay.EnergyDecay.energy_steps`): the observed
increments are their sums, not Simpson's rule on E, which errs by 1e-4 of an
increment at 10 samples a period; the variances keep the Simpson weights.

**Noise-free channels in the variances.** The variances need y and y' without their
noise. The observed ones stand in on a first pass only: below the noise their square
has the mean y² + σ_y² (the tail's variances come out about 3 times too large at 30
times the vibrometer's resolution), and each increment's variance then shares its
noise (an increment whose noise raised its energy gets less weight), which leans a
fit to low energies at small amplitude. The fit passes the law's motion at its
optimum (``motion``; :mod:`bayestribo.inference.reweight`) for the second pass.
Measured by ``benchmarks/noise_weights.py`` on 40 records of ``viscous+quadratic``
at 30 times the resolution: ζ's mean z +0.52 ± 0.17 with the observed channels,
+0.18 ± 0.19 with the noise-free ones.

**The noise level is measured, not known.** σ² measured on a rest of n samples is
known to about √(2/n) (±6.7 % for 0.1 s at 4 kHz), and the bias removed from every
increment, ½(σ_y² + σ_y'²) Σw, is off by as much, alike in every increment: an error
the likelihood would otherwise take as the law's. A third column of
``offset_design``, the bias times its relative standard error
(:func:`noise_bias_sd`), carries it as a linear nuisance with a standard normal
prior, marginalised with the equilibrium's.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal
from numpy.typing import NDArray
from scipy.integrate import cumulative_trapezoid

from bayestribo.signal.channel_noise import derived_noise, recorded_noise
from bayestribo.signal.coarse import coarse_steps, quantised_increments
from bayestribo.signal.decay import EnergyDecay, derivative_gain
from bayestribo.signal.derivative_correlation import derived_velocity_correlation
from bayestribo.signal.increment_correlation import (
    correlation_matrix,
    integrated_noise,
    replicates_for,
)
from bayestribo.signal.noise import NoiseModel
from bayestribo.signal.spectrum import NoiseSpectrum

__all__ = [
    "PiData",
    "accelerometer_draws",
    "correlated_sum_variance",
    "detrended",
    "increment_draws",
    "increment_noise",
    "increment_weights",
    "integrate_increments",
    "neighbour_covariance",
    "noise_bias_sd",
    "pi_data",
    "sample_noise_bias",
    "shared_sample_covariance",
    "simpson_weights",
    "spectral_options",
    "white_noise_bias",
]

#: Monte Carlo replicates drawn at once when the noise is propagated through the
#: derivation of a channel (memory: block × samples floats).
_BLOCK = 25
#: The same for an accelerometer's draws (:func:`accelerometer_draws`), whose
#: integration costs as much again per block as per draw (its edges' terms, their
#: least squares): 1390 draws of a 28 s record at 200 Hz took 2.8 s of CPU in blocks
#: of 25, 1.5 s in blocks of 100 (the draws the same, their variances to 2e-15).
_DRAW_BLOCK = 100


def simpson_weights(n_intervals: int, h: float) -> NDArray:
    """Weights of a composite rule over ``n_intervals`` equal steps of ``h``.

    Simpson's rule h/3·[1, 4, 2, 4, ..., 4, 1] for an even count; for an odd count
    Simpson on all but the last three intervals and the 3/8 rule
    3h/8·[1, 3, 3, 1] on those (both exact for cubics, error O(h⁴)); the trapezoidal
    rule for a single interval.

    Parameters
    ----------
    n_intervals : int
        Number of intervals (samples - 1), >= 1.
    h : float
        The step.

    Returns
    -------
    ndarray
        ``n_intervals + 1`` weights; ``weights @ f`` approximates the integral of f.
    """
    if n_intervals < 1:
        raise ValueError(f"n_intervals must be >= 1, got {n_intervals}")
    w = np.zeros(n_intervals + 1)
    if n_intervals == 1:
        w[:] = 0.5 * h
        return w
    simpson = n_intervals if n_intervals % 2 == 0 else n_intervals - 3
    if simpson > 0:
        w[0] += h / 3.0
        w[simpson] += h / 3.0
        w[1:simpson:2] += 4.0 * h / 3.0
        w[2 : simpson - 1 : 2] += 2.0 * h / 3.0
    if n_intervals % 2 == 1:
        w[simpson : simpson + 4] += np.array([1.0, 3.0, 3.0, 1.0]) * 3.0 * h / 8.0
    return w


def increment_weights(n_samples: int, h: float, n_increments: int) -> tuple[NDArray, list[NDArray]]:
    """Grid sample indices and the quadrature weights of each increment.

    Parameters
    ----------
    n_samples : int
        Samples in the analysed window (regularly spaced by ``h``).
    h : float
        Sample spacing in τ.
    n_increments : int
        Requested number of increments (reduced when there are too few samples).

    Returns
    -------
    edges : ndarray of int
        Sample indices of the grid points, ``edges[0] = 0``, ``edges[-1] = n_samples - 1``.
    weights : list of ndarray
        Quadrature weights over ``edges[j] .. edges[j+1]`` for each increment.
    """
    intervals = n_samples - 1
    if intervals < 2:
        raise ValueError(f"n_samples must be >= 3 for a Simpson grid, got {n_samples}")
    per = max(2, 2 * round(intervals / (2 * max(int(n_increments), 1))))
    edges = list(range(0, intervals, per))
    if intervals - edges[-1] < 2 and len(edges) > 1:
        edges.pop()  # merge a one-interval remainder into the previous increment
    edges.append(intervals)
    edges_arr = np.asarray(edges, dtype=int)
    weights = [simpson_weights(int(b - a), h) for a, b in itertools.pairwise(edges_arr)]
    return edges_arr, weights


@dataclass(frozen=True)
class PiData:
    """Observed Π increments with their noise, ready for the likelihood.

    Attributes
    ----------
    tau_grid : ndarray
        Grid points τ_0 = 0 < τ_1 < ... < τ_m = τ_end (sample times).
    increments : ndarray
        Observed D_j = ∫_{τ_j}^{τ_{j+1}} E, noise bias removed, shape (m,).
    variance : ndarray
        Noise variance of each increment, shape (m,).
    energy_squared : ndarray
        ∫ E² over each increment: the scale of the optional model-discrepancy term.
    motion_ended : bool
        True when the record holds the end of motion: the model's last increment then
        runs to the model's own end of motion (a creep to rest, which never ends, up to
        τ_end: :meth:`bayestribo.inference.likelihood.PiLikelihood.law_pi`), otherwise to
        τ_end.
    y0, yp0 : float
        Observed dimensionless state at τ = 0.
    noise_bias : ndarray
        Mean noise contribution removed from each increment.
    offset_design : ndarray
        Shape (m, 3): ∫ y dτ and ∫ τ y dτ over each increment, and the standard
        error of its noise bias. An error δ₀ + δ₁τ of the equilibrium changes the
        observed increments by -δ₀∫y - δ₁∫τy to first order (the second-order
        ½∫(δ₀ + δ₁τ)² is below 1e-6 per unit τ for equilibrium errors below 1e-3 of
        the length scale, and is neglected); an error of the measured noise level
        changes them by a multiple of the third column, ``noise_bias`` times
        :func:`noise_bias_sd` (a standard normal coefficient; see the module notes).
    spectral : bool
        True when the variances come from the coloured noise spectrum measured at
        rest, False for the white formula.
    neighbour_covariance : ndarray or None
        ``Cov[D_j, D_{j+1}]``, shape (m - 1,): from the spectrum
        (:func:`neighbour_covariance`) for coloured noise, from the shared boundary
        sample (:func:`shared_sample_covariance`) for white noise with both channels
        recorded, zeros for a derived channel. Its positive part is already added to
        ``variance`` on both sides (the likelihood takes the increments as
        independent; this gives any run of increments, from which ζ and μ_k are
        measured, at least its variance).
    preparation : mapping or None
        The keywords of :func:`pi_data` that made it (``noise``, ``grid_points``,
        ``n_replicates``, ``seed``, ``spectral``): the second pass computes the
        variances again with them from the law's motion
        (:mod:`bayestribo.inference.reweight`).
    law_increments : ndarray or None
        The law's increments where the second pass computed the variances, shape
        (m,): without the noise, they scale the shape discrepancy's columns
        (:mod:`bayestribo.inference.likelihood`). None on a first pass.
    restoring : RestoringKernel or None
        The nonlinear restoring force of the energy (:attr:`EnergyDecay.restoring`),
        which the likelihood's law takes; None for the linear spring.
    rounding : float
        The step of a coarse displacement (:mod:`bayestribo.signal.coarse`) in units
        of y, 0 otherwise: y0 and the equilibrium, read from rounded samples, are
        known to about half of it.
    correlation : ndarray or None
        The correlation of the increments' noise, shape (m, m), for an
        accelerometer's record, whose integrated noise reaches many increments alike
        (:mod:`bayestribo.signal.increment_correlation`), and for a velocity derived
        from the displacement on a nonlinear restoring force, whose neighbours share
        the derivative's noise (:mod:`bayestribo.signal.derivative_correlation`); the covariance is
        ``√V_i R_ij √V_j`` and the likelihood whitens the increments with it. None:
        independent increments (see the module notes).
    """

    tau_grid: NDArray
    increments: NDArray
    variance: NDArray
    energy_squared: NDArray
    motion_ended: bool
    y0: float
    yp0: float
    noise_bias: NDArray
    offset_design: NDArray
    spectral: bool = False
    neighbour_covariance: NDArray | None = None
    preparation: Mapping[str, Any] | None = None
    law_increments: NDArray | None = None
    restoring: Any = None
    rounding: float = 0.0
    correlation: NDArray | None = None

    @property
    def tau_end(self) -> float:
        """τ of the last analysed sample."""
        return float(self.tau_grid[-1])

    @property
    def pi(self) -> NDArray:
        """Observed Π at the grid points τ_0 .. τ_{m-1} (reverse cumulative sum)."""
        return np.cumsum(self.increments[::-1])[::-1]

    @property
    def pi_variance(self) -> NDArray:
        """Marginal noise variance of Π at the grid points."""
        return np.cumsum(self.variance[::-1])[::-1]


def integrate_increments(values: NDArray, edges: NDArray, weights: list[NDArray]) -> NDArray:
    """∫ values over each increment (``values`` of shape (..., samples)).

    One signal's sums are taken by einsum: each is bound by memory, and a threaded
    BLAS waits for a second core that a shared machine gives late (112 sums of a 1 MHz
    record took 0.9 s instead of 1 ms). Replicates (2-D) go to BLAS, which reuses each
    weight across them.
    """
    if np.ndim(values) == 1:
        return np.array(
            [
                np.einsum("i,i->", values[a : b + 1], w)
                for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
            ]
        )
    return _integrate_by_blas(values, edges, weights)


def _integrate_by_blas(values: NDArray, edges: NDArray, weights: list[NDArray]) -> NDArray:
    """:func:`integrate_increments` by BLAS, whatever the shape of ``values``."""
    return np.stack(
        [
            values[..., a : b + 1] @ w
            for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
        ],
        axis=-1,
    )


class _VelocityFilter:
    """The Savitzky-Golay derivative that derives the velocity from the displacement
    (rows of samples at ``tau``), and its settings as a key (``key``): linear in its
    input, edges included (``mode="interp"`` fits each edge by least squares)."""

    def __init__(self, tau: NDArray, savgol_window: int | None) -> None:
        self.window = min(int(savgol_window or 7), tau.size - (1 - tau.size % 2))
        self.step = float(tau[1] - tau[0])
        self.key = ("savgol", self.window, 5, 1, self.step)

    def __call__(self, y: NDArray) -> NDArray:
        return scipy.signal.savgol_filter(
            y, self.window, 5, deriv=1, delta=self.step, mode="interp", axis=-1
        )


def _integrated_displacement(
    tau: NDArray, yp_noisy: NDArray, y: NDArray, yp: NDArray
) -> tuple[NDArray, NDArray]:
    """The derivation of a missing displacement repeated on a perturbed velocity (rows
    of replicates): the displacement and the velocity.

    The equilibrium and its drift (a line in τ) are estimated from the record's own
    turning points, so the line the noise's integral holds goes with them and only its
    departure from a line remains."""
    walk = cumulative_trapezoid(yp_noisy - yp, tau, initial=0.0, axis=-1)
    return y + detrended(walk, tau), yp_noisy


def detrended(walk: NDArray, tau: NDArray) -> NDArray:
    """``walk`` (rows of samples at ``tau``) less its least-squares line in τ.

    The noise a derived displacement inherits from its velocity is that velocity's
    noise integrated: a random walk, whose variance grows with τ from wherever the
    integral starts. The decay measures the displacement about an equilibrium that
    drifts linearly (δ₀ + δ₁τ, fitted to the turning points,
    :mod:`bayestribo.signal.decay`), which takes the walk's line with it; what reaches
    E is the walk about its line, a bridge whose variance is largest near the middle
    and a small fraction of the walk's at the end (1/6 of it at a walk's midpoint
    against its variance at the end: T/4·σ² – about T/12 σ² at the ends).

    Parameters
    ----------
    walk : ndarray
        Integrated noise, shape (..., n) [units of y].
    tau : ndarray
        Dimensionless times of the samples, shape (n,).

    Returns
    -------
    ndarray
        ``walk`` less its least-squares line in τ, same shape.
    """
    centred = tau - tau.mean()
    mean = walk.mean(axis=-1, keepdims=True)
    slope = (walk @ centred)[..., None] / float(centred @ centred)
    return walk - mean - slope * centred


def _coarse(decay: EnergyDecay, noise: NoiseModel) -> dict[str, Any] | None:
    """The coarse channels of a record with both channels recorded (None when it has
    none): their steps in units of y and y', the rest of their noise, and the white
    levels left to the white formula (:mod:`bayestribo.signal.coarse`)."""
    if decay.derived_channel is not None:
        return None
    steps = coarse_steps(
        noise.quantisation_steps, (noise.measured_displacement, noise.measured_velocity)
    )
    if steps == (None, None):
        return None
    sc = decay.scaling
    units = (sc.length_scale, sc.length_scale * sc.omega)
    used = (noise.displacement, noise.velocity)
    scaled: list[float | None] = []
    other: list[float] = []
    white: list[float] = []
    for step, sd, unit in zip(steps, used, units, strict=True):
        if step is None:
            scaled.append(None)
            other.append(0.0)
            white.append(sd / unit)
            continue
        scaled.append(step / unit)
        other.append(math.sqrt(max(sd * sd - step * step / 12.0, 0.0)) / unit)
        white.append(0.0)
    return {"steps": tuple(scaled), "other": tuple(other), "white": tuple(white)}


def decay_motion(decay: EnergyDecay) -> tuple[NDArray, NDArray]:
    """The decay's channels smoothed over a quarter period (a cubic Savitzky-Golay
    filter): a first stand-in for the channels without their noise and rounding, where
    the law's motion is not yet known (:mod:`bayestribo.inference.reweight`)."""
    h = float(decay.tau[1] - decay.tau[0])
    window = int(0.5 * math.pi / h) // 2 * 2 + 1
    window = min(window, decay.tau.size - (1 - decay.tau.size % 2))
    if window < 5:
        return decay.y, decay.yp
    return tuple(  # type: ignore[return-value]
        scipy.signal.savgol_filter(c, window, 3, mode="interp") for c in (decay.y, decay.yp)
    )


def white_noise_bias(sigma_y: float, sigma_yp: float) -> float:
    """Mean that white noise adds to E = (y² + y'²)/2 per sample: ½(σ_y² + σ_y'²).

    Parameters
    ----------
    sigma_y, sigma_yp : float
        Noise standard deviations of y and y' (dimensionless, as y and y').
    """
    return 0.5 * (sigma_y**2 + sigma_yp**2)


def sample_noise_bias(decay: EnergyDecay) -> float:
    """Mean that the measurement noise adds to each sample of a decay's E [-].

    ``½(σ_y² + σ_y'²)`` (:func:`white_noise_bias`, Eq. 26) with the noise levels the
    decay measured (:attr:`EnergyDecay.noise_y`, :attr:`EnergyDecay.noise_yp`; a
    channel without one counts 0). The noise of a derived velocity is the recorded
    displacement's through the derivative filter, ``σ_y' = g σ_y`` with the filter's
    gain g in τ (:func:`bayestribo.signal.decay.derivative_gain`): the mean square of
    correlated noise is still its variance. A derived displacement's integrated noise
    wanders along the record; only its level measured at rest counts here, and
    :func:`increment_noise` follows it increment by increment.

    Parameters
    ----------
    decay : EnergyDecay
        The recording's energy decay.

    Returns
    -------
    float
        The bias per sample, in units of E.
    """
    sigma_y = decay.noise_y or 0.0
    sigma_yp = decay.noise_yp or 0.0
    if decay.derived_channel == "velocity" and decay.savgol_window is not None:
        step = float(decay.tau[1] - decay.tau[0])
        sigma_yp = sigma_y * derivative_gain(decay.savgol_window, step)
    return white_noise_bias(sigma_y, sigma_yp)


#: Relative efficiency of the MAD of 4th differences against the rest's variance, and
#: the samples one 4th difference spans (:func:`bayestribo.signal.peaks.estimate_noise`,
#: the noise level of a record without a rest).
_MAD_EFFICIENCY, _DIFFERENCE_SPAN = 0.37, 5


def noise_bias_sd(decay: EnergyDecay, noise: NoiseModel) -> float:
    """Relative standard error of the noise bias ½(σ_y² + σ_y'²) that is removed from
    every increment [-].

    Per recorded channel, the standard error of σ² [unit²]:

    * measured at rest on n samples: √(2/n) σ² (white noise; the larger
      :attr:`NoiseModel.spectrum_rel_se` for coloured noise);
    * measured from the signal's 4th differences (no rest): √(2/n_eff) σ² with
      n_eff = 0.37 n / 5 (the MAD's efficiency, and the span of a difference);
    * the nominal resolution, used where it exceeds what was measured: the
      difference of the two, and at least the measurement's own error.

    A derived channel adds nothing (its noise is the recorded one's).

    Parameters
    ----------
    decay : EnergyDecay
        The recording's energy decay (its :attr:`EnergyDecay.noise` says where and on
        how many samples the noise was measured).
    noise : NoiseModel
        The noise model used.

    Returns
    -------
    float
        √(s_y² + s_y'²) / (σ_y² + σ_y'²) in units of y; 0 without noise.
    """
    sc = decay.scaling
    n = decay.noise.n_samples
    if n > 0:
        rel = math.sqrt(2.0 / n)
    else:
        n_eff = max(_MAD_EFFICIENCY * decay.tau.size / _DIFFERENCE_SPAN, 1.0)
        rel = math.sqrt(2.0 / n_eff)
    if noise.coloured and noise.spectrum_rel_se is not None:
        rel = max(rel, float(noise.spectrum_rel_se))
    total, spread = 0.0, 0.0
    units = {"displacement": sc.length_scale, "velocity": sc.length_scale * sc.omega}
    for channel, unit in units.items():
        if channel == noise.derived_channel:
            continue
        used = float(getattr(noise, channel)) ** 2
        sd = rel * used
        measured = getattr(noise, f"measured_{channel}")
        if getattr(noise, f"source_{channel}") == "nominal" and measured is not None:
            sd = max(rel * float(measured) ** 2, used - float(measured) ** 2)
        total += used / unit**2
        spread += (sd / unit**2) ** 2
    if not total > 0:
        return 0.0
    return math.sqrt(spread) / total


def correlated_sum_variance(weights: NDArray, autocovariance: NDArray) -> float:
    """Variance ``wᵀ C w`` of ``Σ w_i ε_i`` for stationary noise ε of autocovariance c.

    ``C[i, j] = c[|i - j|]`` (Toeplitz), with c taken as 0 beyond its length; for white
    noise (``c = [σ²]``) this is ``σ² Σ w_i²``. Evaluated as ``c[0] r[0] + 2 Σ_m c[m]
    r[m]`` with r the autocorrelation of w (FFT, O(n log n)).

    Parameters
    ----------
    weights : ndarray
        The weights w (any units).
    autocovariance : ndarray
        c[0], c[1], ... at lags of 0, 1, ... samples [unit²].

    Returns
    -------
    float
    """
    w = np.asarray(weights, dtype=float)
    c = np.asarray(autocovariance, dtype=float)
    m = min(w.size, c.size)
    if m <= 1:
        return float(c[0] * (w @ w))
    r = scipy.signal.correlate(w, w, mode="full")[w.size - 1 : w.size - 1 + m]
    return float(c[0] * r[0] + 2.0 * (c[1:m] @ r[1:m]))


def neighbour_covariance(
    y: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    autocov_y: NDArray,
    autocov_yp: NDArray,
) -> NDArray:
    """Covariance of consecutive increments ``Cov[D_j, D_{j+1}]`` under coloured noise.

    With the notation of :func:`increment_noise`, the linear parts give
    ``(w_j∘y)ᵀ C_ε (w_{j+1}∘y) + (w_j∘y')ᵀ C_η (w_{j+1}∘y')`` and the quadratic parts
    ``½ w_jᵀ (C_ε∘C_ε + C_η∘C_η) w_{j+1}``, the weights placed at their samples (the
    shared boundary sample included). White noise gives only the boundary sample's
    term (:func:`shared_sample_covariance`; see the module notes).

    Parameters
    ----------
    y, yp : ndarray
        The channels about the equilibrium (dimensionless).
    edges, weights
        The grid (:func:`increment_weights`).
    autocov_y, autocov_yp : ndarray
        Autocovariances of the noise of y and y' at lags 0, 1, ... samples (0 beyond).

    Returns
    -------
    ndarray
        Shape (m - 1,) for m increments.
    """
    c_y = np.asarray(autocov_y, dtype=float)
    c_yp = np.asarray(autocov_yp, dtype=float)
    out = np.empty(edges.size - 2)
    for j in range(edges.size - 2):
        a, b, c = int(edges[j]), int(edges[j + 1]), int(edges[j + 2])
        n = c - a + 1
        w1, w2 = np.zeros(n), np.zeros(n)
        w1[: b - a + 1] = weights[j]
        w2[b - a :] = weights[j + 1]
        total = 0.0
        for kernel_c, s1, s2 in (
            (c_y, w1 * y[a : c + 1], w2 * y[a : c + 1]),
            (c_yp, w1 * yp[a : c + 1], w2 * yp[a : c + 1]),
            (0.5 * c_y * c_y, w1, w2),
            (0.5 * c_yp * c_yp, w1, w2),
        ):
            m = min(n, kernel_c.size)
            kernel = np.r_[kernel_c[m - 1 : 0 : -1], kernel_c[:m]]
            total += float(s1 @ scipy.signal.fftconvolve(s2, kernel, mode="same"))
        out[j] = total
    return out


def shared_sample_covariance(
    y: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    sigma_y: float,
    sigma_yp: float,
) -> NDArray:
    """Covariance of consecutive increments under white noise: their shared sample.

    The sample on the boundary between increments j and j + 1 is the last of one
    Simpson rule and the first of the next, so with white, independent channel noise
    ``Cov[D_j, D_{j+1}] = w_j[-1] w_{j+1}[0] Var(E_b)``, ``Var(E_b) = y_b²σ_y² +
    y'_b²σ_y'² + ½(σ_y⁴ + σ_y'⁴)`` at that sample b (the white case of
    :func:`neighbour_covariance`, in O(m)).

    Parameters
    ----------
    y, yp : ndarray
        The channels about the equilibrium (dimensionless).
    edges, weights
        The grid (:func:`increment_weights`).
    sigma_y, sigma_yp : float
        Noise standard deviations of y and y'.

    Returns
    -------
    ndarray
        Shape (m - 1,) for m increments, all >= 0.
    """
    b = np.asarray(edges[1:-1], dtype=int)
    var_e = y[b] ** 2 * sigma_y**2 + yp[b] ** 2 * sigma_yp**2 + 0.5 * (sigma_y**4 + sigma_yp**4)
    ends = np.array([w0[-1] * w1[0] for w0, w1 in itertools.pairwise(weights)])
    return ends * var_e


def increment_noise(
    tau: NDArray,
    y: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    sigma_y: float,
    sigma_yp: float,
    *,
    derived: str | None = None,
    savgol_window: int | None = None,
    n_replicates: int = 300,
    seed: int = 0,
    autocov_y: NDArray | None = None,
    autocov_yp: NDArray | None = None,
    spectrum: NoiseSpectrum | None = None,
    spectrum_scale: float = 1.0,
    potential: Callable[[NDArray], NDArray] | None = None,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None = None,
) -> tuple[NDArray, NDArray]:
    """Noise bias and noise variance of each increment of E = (y² + y'²)/2.

    With a nonlinear restoring force's ``potential`` V the Monte Carlo of a derived
    channel takes E = ½y'² + V(y); with recorded channels the caller passes V'(y)
    for y (the white and coloured formulas are linear in the noise).

    With both channels recorded (``derived`` None) the noise is white and
    independent per channel: per sample E has the bias ½(σ_y² + σ_y'²) and the
    variance y²σ_y² + y'²σ_y'² + ½(σ_y⁴ + σ_y'⁴), summed over each increment with the
    squared quadrature weights. When one channel was derived from the other, its
    noise is the derivation of the recorded channel's: white noise is drawn on the
    recorded channel (``n_replicates`` seeded replicates), the derivation is repeated
    (Savitzky-Golay derivative with ``savgol_window``, or the cumulative trapezoid)
    and the bias and variance are the mean and variance of the increments' change.

    Parameters
    ----------
    tau, y, yp : ndarray
        Dimensionless time (regular) and the channels about the equilibrium.
    edges, weights
        The grid (:func:`increment_weights`).
    sigma_y, sigma_yp : float
        Noise standard deviations of the recorded channels in units of y and y'.
    derived : {None, "velocity", "displacement"}
        The channel derived from the other.
    savgol_window : int, optional
        Window of the derivative filter (``derived="velocity"``).
    n_replicates, seed : int
        Monte Carlo replicates and their seed (derived channel only).
    autocov_y, autocov_yp : ndarray, optional
        Autocovariance of each channel's noise at lags of 0, 1, ... samples, in units
        of y², y'² (both channels recorded): coloured noise (filtered, 1/f, a line) is
        correlated across samples. With ε, η Gaussian, stationary and independent of
        each other, the increment ``Σ w_i E_i`` changes by ``Σ w_i (y_i ε_i + y'_i
        η_i) + ½ Σ w_i (ε_i² + η_i²)``, whose variance is ``(w∘y)ᵀ C_ε (w∘y) +
        (w∘y')ᵀ C_η (w∘y') + ½ wᵀ (C_ε∘C_ε + C_η∘C_η) w`` (the two parts are
        uncorrelated, odd moments of a Gaussian being 0), and whose mean is
        ``½(c_ε[0] + c_η[0]) Σ w``. A channel without one is white at its sigma, and
        then this is exactly the white formula above.
    spectrum : NoiseSpectrum, optional
        The recorded channel's noise spectrum (derived channel only): the Monte Carlo
        draws noise with this spectrum (:func:`bayestribo.signal.spectrum.colored_noise`)
        times ``spectrum_scale`` (the conversion to y or y' units) instead of white
        noise of ``sigma_y`` or ``sigma_yp``.
    spectrum_scale : float
        Factor from the spectrum's units to y (or y') units.
    velocity_draws : callable, optional
        ``velocity_draws(count, rng)``: ``count`` draws of the recorded velocity's noise
        on the samples, in units of y' (``derived="displacement"``; a velocity
        integrated from an acceleration, :func:`accelerometer_draws`). Used in place of
        white noise or ``spectrum``.

    Returns
    -------
    bias, variance : ndarray
        Per increment.
    """
    if derived is None and (autocov_y is not None or autocov_yp is not None):
        c_y = np.array([sigma_y**2]) if autocov_y is None else np.asarray(autocov_y, float)
        c_yp = np.array([sigma_yp**2]) if autocov_yp is None else np.asarray(autocov_yp, float)
        bias = 0.5 * (c_y[0] + c_yp[0]) * np.array([w.sum() for w in weights])
        variance = np.array(
            [
                correlated_sum_variance(w * y[a : b + 1], c_y)
                + correlated_sum_variance(w * yp[a : b + 1], c_yp)
                + 0.5 * correlated_sum_variance(w, c_y * c_y)
                + 0.5 * correlated_sum_variance(w, c_yp * c_yp)
                for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
            ]
        )
        return bias, variance
    if derived is None:
        bias_per_sample = white_noise_bias(sigma_y, sigma_yp)
        var_e = y**2 * sigma_y**2 + yp**2 * sigma_yp**2 + 0.5 * (sigma_y**4 + sigma_yp**4)
        bias = bias_per_sample * np.array([w.sum() for w in weights])
        variance = np.array(
            [
                np.einsum("i,i->", w**2, var_e[a : b + 1])  # not BLAS: see above
                for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
            ]
        )
        return bias, variance
    draws = increment_draws(
        tau,
        y,
        yp,
        edges,
        weights,
        sigma_y,
        sigma_yp,
        derived=derived,
        savgol_window=savgol_window,
        n_replicates=n_replicates,
        seed=seed,
        spectrum=spectrum,
        spectrum_scale=spectrum_scale,
        potential=potential,
        velocity_draws=velocity_draws,
    )
    return draws.mean(axis=0), draws.var(axis=0, ddof=1)


def increment_draws(
    tau: NDArray,
    y: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    sigma_y: float,
    sigma_yp: float,
    *,
    derived: str,
    savgol_window: int | None = None,
    n_replicates: int = 300,
    seed: int = 0,
    spectrum: NoiseSpectrum | None = None,
    spectrum_scale: float = 1.0,
    potential: Callable[[NDArray], NDArray] | None = None,
    velocity_draws: Callable[[int, np.random.Generator], NDArray] | None = None,
) -> NDArray:
    """Monte Carlo draws of the noise of each increment when one channel is derived.

    Noise is drawn on the recorded channel (white at ``sigma_y`` or ``sigma_yp``, with
    ``spectrum``, or from ``velocity_draws``), the derivation is repeated on it, and
    the increments' change is returned: their mean is the noise bias, their variance
    the increments' variances (:func:`increment_noise`) and, for an integrated
    channel, their covariance the increments' correlation
    (:mod:`bayestribo.signal.increment_correlation`). The arguments are those of
    :func:`increment_noise`.

    Returns
    -------
    ndarray
        Shape (n_replicates, m): the change of each increment in each draw.
    """
    if derived not in ("velocity", "displacement"):
        raise ValueError(f"derived must be None, 'velocity' or 'displacement', got {derived!r}")

    # by BLAS as the replicates are: their differences from it are small, and the two
    # sums must round alike for them
    def energy_of(y: NDArray, yp: NDArray) -> NDArray:
        if potential is None:
            return 0.5 * (y * y + yp * yp)
        return 0.5 * yp * yp + potential(y)

    reference = _integrate_by_blas(energy_of(y, yp), edges, weights)
    draws = np.empty((n_replicates, edges.size - 1))
    integrated = velocity_draws is not None and derived == "displacement"
    first = 0
    if derived == "velocity":
        # the derivative is linear: the noisy motion's is the motion's plus the noise's,
        # which is kept with the noise for the next motion (channel_noise.derived_noise)
        slope = _VelocityFilter(tau, savgol_window)
        motion_slope = slope(y)
        for draw, draw_slope in derived_noise(
            tau.size,
            sigma_y,
            n_replicates=n_replicates,
            seed=seed,
            block=_BLOCK,
            derive=slope,
            derive_key=slope.key,
            spectrum=spectrum,
            spectrum_scale=spectrum_scale,
        ):
            count = draw.shape[0]
            energy = energy_of(y + draw, motion_slope + draw_slope)
            draws[first : first + count] = integrate_increments(energy, edges, weights) - reference
            first += count
        return draws
    # the recorded channel's noise, the same whatever the motion (drawn once per
    # recipe inside bayestribo.signal.channel_noise.reused_noise)
    for draw in recorded_noise(
        tau.size,
        sigma_yp,
        n_replicates=n_replicates,
        seed=seed,
        block=_DRAW_BLOCK if integrated else _BLOCK,
        spectrum=spectrum,
        spectrum_scale=spectrum_scale,
        velocity_draws=velocity_draws if integrated else None,
    ):
        count = draw.shape[0]
        yn, ypn = _integrated_displacement(tau, yp + draw, y, yp)
        energy = energy_of(yn, ypn)
        draws[first : first + count] = integrate_increments(energy, edges, weights) - reference
        first += count
    return draws


def spectral_options(decay: EnergyDecay, noise: NoiseModel, n_lags: int) -> dict:
    """Keywords of :func:`increment_noise` for the coloured noise measured at rest.

    ``autocov_y``/``autocov_yp`` (in units of y², y'², ``n_lags`` lags) for recorded
    channels, or ``spectrum``/``spectrum_scale`` for the Monte Carlo of a derived
    channel, for each channel whose rest noise is coloured and is the figure the noise
    model uses (measured above the nominal resolution). Empty when the rest noise is
    white or was not measured: :func:`increment_noise` then keeps the white formula.

    Parameters
    ----------
    decay : EnergyDecay
        The recording's energy decay (its :attr:`EnergyDecay.rest_noise`).
    noise : NoiseModel
        The noise model used.
    n_lags : int
        Lags needed: at least the samples of the longest increment.

    Returns
    -------
    dict
    """
    rest = decay.rest_noise
    if rest is None or not rest.coloured:
        return {}
    sc = decay.scaling
    to_y = 1.0 / sc.length_scale
    to_yp = 1.0 / (sc.length_scale * sc.omega)
    # a channel's spectrum counts where the noise model uses the measured noise (not
    # where the instrument's nominal resolution is the larger figure)
    use_x = rest.displacement is not None and rest.displacement.coloured
    use_x = use_x and noise.source_displacement == "measured"
    use_v = rest.velocity is not None and rest.velocity.coloured
    use_v = use_v and noise.source_velocity == "measured"
    derived = decay.derived_channel
    if derived == "velocity":
        return {"spectrum": rest.displacement, "spectrum_scale": to_y} if use_x else {}
    if derived == "displacement":
        return {"spectrum": rest.velocity, "spectrum_scale": to_yp} if use_v else {}
    options = {}
    if use_x:
        options["autocov_y"] = rest.displacement.autocovariance(n_lags) * to_y**2
    if use_v:
        options["autocov_yp"] = rest.velocity.autocovariance(n_lags) * to_yp**2
    return options


def accelerometer_draws(
    decay: EnergyDecay, noise: NoiseModel
) -> Callable[[int, np.random.Generator], NDArray] | None:
    """Draws of the noise of a velocity integrated from an accelerometer's record, on
    the decay's samples in units of y' (for :func:`increment_noise`), or None.

    The sensor's white noise is put through the integration over the whole record
    (:func:`bayestribo.signal.velocity_integral.velocity_noise`) and the decay's samples taken
    from it. None when the noise model holds no integration
    (:attr:`NoiseModel.integrated_velocity`), or when the decay's samples are not the
    integrated record's (a run cut or resampled after reading).

    Parameters
    ----------
    decay : EnergyDecay
        The recording's energy decay, its displacement derived from the velocity.
    noise : NoiseModel
        The noise model used.

    Returns
    -------
    callable or None
        ``draws(count, rng)``, shape (count, decay samples).
    """
    plan = noise.integrated_velocity
    if plan is None or decay.derived_channel != "displacement":
        return None
    step = float(plan["step_s"])
    first = round((float(decay.t[0]) - float(plan["start_s"])) / step)
    expected = float(plan["start_s"]) + step * (first + np.arange(decay.t.size))
    if (
        first < 0
        or first + decay.t.size > int(plan["samples"])
        or not np.allclose(decay.t, expected, rtol=0.0, atol=1e-3 * step)
    ):
        return None
    sc = decay.scaling
    unit = sc.length_scale * sc.omega

    def draws(count: int, rng: np.random.Generator) -> NDArray:
        from bayestribo.signal.velocity_integral import velocity_noise

        return velocity_noise(plan, count, rng)[:, first : first + decay.t.size] / unit

    return draws


def _velocity_rest_floor(
    decay: EnergyDecay, yp: NDArray, edges: NDArray, weights: list[NDArray], sigma_yp: float
) -> NDArray:
    """Increment variances from the velocity's noise measured at rest (its spectrum's
    autocovariance where coloured, else white at ``sigma_yp``), in the velocity alone."""
    rest = decay.rest_noise
    spectrum = None if rest is None else rest.velocity
    if spectrum is not None and spectrum.coloured:
        sc = decay.scaling
        lags = 2 * (int(np.max(np.diff(edges))) + 1)
        autocov = spectrum.autocovariance(lags) / (sc.length_scale * sc.omega) ** 2
    else:
        autocov = np.array([sigma_yp**2])
    zero = np.zeros_like(yp)
    _, floor = increment_noise(
        decay.tau, zero, yp, edges, weights, 0.0, sigma_yp, autocov_yp=autocov
    )
    return floor


def pi_data(
    decay: EnergyDecay,
    noise: NoiseModel,
    *,
    grid_points: int | None = None,
    n_replicates: int = 300,
    seed: int = 0,
    spectral: bool = True,
    motion: tuple[NDArray, NDArray] | None = None,
    derivative_correlation: bool = True,
) -> PiData:
    """Build the likelihood's observation from a recording's energy decay.

    Parameters
    ----------
    decay : EnergyDecay
        The recording (:func:`bayestribo.signal.decay.energy_decay`).
    noise : NoiseModel
        Noise standard deviations per channel, in signal units.
    grid_points : int, optional
        Number of Π increments (the grid is on samples, Simpson-compatible). Default:
        one per half cycle of the analysed window, one per cycle for a coarse
        digitiser (see the notes).
    n_replicates : int
        Monte Carlo replicates for a derived channel (relative error of each variance
        about √(2/n)).
    seed : int
        Seed of those replicates.
    spectral : bool
        When the noise measured at rest is coloured (:attr:`EnergyDecay.rest_noise`,
        a :class:`~bayestribo.signal.spectrum.RestNoise` with ``coloured`` true:
        filtered, 1/f, or with a mains line), compute the increment variances from its
        autocovariance (``wᵀ C w``, :func:`increment_noise`) and, for a derived
        channel, draw the Monte Carlo noise with its spectrum; each variance is at
        least the white one at the nominal resolution, when known. White noise at rest
        (or ``spectral=False``, or no rest) gives the white formula with the noise
        model's levels, plus the covariance of the sample neighbouring increments share
        (:func:`shared_sample_covariance`) when both channels are recorded.
    motion : (y, y') arrays, optional
        The channels without their noise (dimensionless, on the decay's samples), from
        which the increments' variances are computed: the law's motion at the
        optimum (:func:`bayestribo.inference.reweight.law_motion`). Default: the
        observed channels (see the module notes for what that costs below the
        noise). The observed increments are the same either way.
    derivative_correlation : bool
        On a nonlinear restoring force with a derived velocity, give the likelihood the
        correlation the derivative's noise makes between neighbouring increments
        (:mod:`bayestribo.signal.derivative_correlation`); False keeps them
        independent, as on the linear spring (:func:`bayestribo.inference.preparation.
        prepare` does so where the force is in doubt).

    Returns
    -------
    PiData
    """
    tau = decay.tau
    h = float(tau[1] - tau[0])
    coarse = _coarse(decay, noise)
    if grid_points is None:
        # a coarse digitiser's errors alternate between half cycles (a level above the
        # zero at one turning point is below it at the next): one increment a cycle
        # holds both, and its variance their sum
        grid_points = max(4, round(float(tau[-1]) / (math.pi if coarse is None else 2 * math.pi)))
    edges, weights = increment_weights(tau.size, h, grid_points)
    sc = decay.scaling
    sig_y = noise.displacement / sc.length_scale
    sig_yp = noise.velocity / (sc.length_scale * sc.omega)
    if motion is None:
        y, yp = decay.y, decay.yp
    else:
        y, yp = (np.asarray(c, dtype=float) for c in motion)
        if y.shape != decay.tau.shape or yp.shape != decay.tau.shape:
            raise ValueError(
                f"motion: expected two arrays of shape {decay.tau.shape} (the decay's "
                f"samples), got {y.shape} and {yp.shape}"
            )
    restoring = decay.restoring
    potential = None
    if restoring is not None and decay.derived_channel is not None:
        potential = restoring.potential  # the Monte Carlo takes E = ½y'² + V(y)
    elif restoring is not None:
        # the noise of E = ½y'² + V(y) takes V'(y) where the linear spring's takes y
        y = np.asarray(restoring.spring(y), dtype=float)
    e2 = integrate_increments(decay.energy**2, edges, weights)
    longest = int(np.max(np.diff(edges))) + 1
    if coarse is not None:
        # the rounding of a coarse channel is left to quantised_increments (its rest
        # shows no spectrum of it), the white formula keeps the rest of the noise
        sig_y, sig_yp = coarse["white"]
        spectral = False
    draws = accelerometer_draws(decay, noise)
    options = spectral_options(decay, noise, 2 * longest) if spectral and draws is None else {}
    covariance = None
    if draws is not None:
        # an accelerometer's record: the noise of its integrals correlates the
        # increments, whose covariance the draws give
        # (bayestribo.signal.increment_correlation)
        mc = increment_draws(
            tau,
            y,
            yp,
            edges,
            weights,
            sig_y,
            sig_yp,
            derived="displacement",
            n_replicates=replicates_for(edges.size - 1, n_replicates),
            seed=seed,
            potential=potential,
            velocity_draws=draws,
            **options,
        )
        bias, covariance = integrated_noise(mc)
        variance = np.diag(covariance).copy()
    else:
        bias, variance = increment_noise(
            tau,
            y,
            yp,
            edges,
            weights,
            sig_y,
            sig_yp,
            derived=decay.derived_channel,
            savgol_window=decay.savgol_window,
            n_replicates=n_replicates,
            seed=seed,
            potential=potential,
            velocity_draws=draws,
            **options,
        )
    if draws is not None:
        # the sensor's noise through the integration, which the rest does not show in
        # the motion; never below the velocity's own noise as the rest shows it, which
        # also holds what the integration leaves there without noise (its edges'
        # ringing, 3e-5 of the swing): that noise in the velocity channel alone, its
        # integral's wander being the sensor's
        variance = np.maximum(variance, _velocity_rest_floor(decay, yp, edges, weights, sig_yp))
    if options:
        # never below the white noise at the instrument's nominal resolution
        nominal_y = (noise.nominal_displacement or 0.0) / sc.length_scale
        nominal_yp = (noise.nominal_velocity or 0.0) / (sc.length_scale * sc.omega)
        if decay.derived_channel is None and (nominal_y > 0 or nominal_yp > 0):
            _, floor = increment_noise(tau, y, yp, edges, weights, nominal_y, nominal_yp)
            variance = np.maximum(variance, floor)
    neighbours = np.zeros(edges.size - 2)
    if "autocov_y" in options or "autocov_yp" in options:
        neighbours = neighbour_covariance(
            y,
            yp,
            edges,
            weights,
            options.get("autocov_y", np.array([sig_y**2])),
            options.get("autocov_yp", np.array([sig_yp**2])),
        )
    elif decay.derived_channel is None:
        neighbours = shared_sample_covariance(y, yp, edges, weights, sig_y, sig_yp)
    if coarse is not None:
        q_bias, q_variance, q_neighbours = quantised_increments(
            *(decay_motion(decay) if motion is None else (y, yp)),
            edges,
            weights,
            coarse["steps"],
            coarse["other"],
            n_replicates=n_replicates,
            seed=seed,
        )
        bias = bias + q_bias
        variance = variance + q_variance
        neighbours = neighbours + q_neighbours
    if neighbours.any():
        # The likelihood takes the increments as independent: a positive covariance
        # with a neighbour is added to the variance (any run of increments then has at
        # least its variance); a negative one, which would sharpen it, is not.
        plus = np.maximum(neighbours, 0.0)
        variance = variance + np.r_[0.0, plus] + np.r_[plus, 0.0]
    if decay.energy_steps is not None:
        observed = np.add.reduceat(decay.energy_steps, edges[:-1]) - bias
    else:
        observed = integrate_increments(decay.energy, edges, weights) - bias
    force = decay.y if restoring is None else np.asarray(restoring.spring(decay.y), dtype=float)
    if decay.motion_ended:
        # The end of motion is located within about a sample: allow for the energy of
        # ±2 samples at the end in the last increment.
        end_energy = float(np.max(decay.energy[edges[-2] :]))
        variance[-1] += (2.0 * h * end_energy) ** 2
    if (
        derivative_correlation
        and covariance is None
        and restoring is not None
        and decay.derived_channel == "velocity"
        and coarse is None
        and not options
    ):
        # a nonlinear force's half cycles drift through the grid: neighbours share the
        # derivative's noise at boundaries where the motion is fast
        # (bayestribo.signal.derivative_correlation); the linear spring's grid keeps
        # its boundaries near turning points, its increments independent
        correlation = derived_velocity_correlation(
            np.asarray(restoring.spring(y), dtype=float),
            yp,
            edges,
            weights,
            variance,
            sig_y,
            decay.savgol_window,
            h,
        )
    else:
        correlation = None if covariance is None else correlation_matrix(covariance, variance)
    return PiData(
        tau_grid=tau[edges],
        increments=observed,
        variance=variance,
        energy_squared=e2,
        motion_ended=decay.motion_ended,
        y0=float(decay.y[0]),
        yp0=float(decay.yp[0]),
        noise_bias=bias,
        spectral=bool(options),
        neighbour_covariance=neighbours,
        correlation=correlation,
        preparation={
            "noise": noise,
            "grid_points": int(grid_points),
            "n_replicates": n_replicates,
            "seed": seed,
            "spectral": spectral,
            "derivative_correlation": derivative_correlation,
        },
        restoring=restoring,
        rounding=0.0 if coarse is None else float(coarse["steps"][0] or 0.0),
        offset_design=np.column_stack(
            [
                integrate_increments(force, edges, weights),
                integrate_increments(tau * force, edges, weights),
                bias * noise_bias_sd(decay, noise),
            ]
        ),
    )
