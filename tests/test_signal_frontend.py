"""The front end on real signal chains, against an independent simulator.

The simulator here shares nothing with the package: ``scipy.integrate.solve_ivp`` of
m x'' + c x' + k x + μ_k N sign(x') = 0, half cycle by half cycle, with sticking when
|k x| <= μ_s N at a turning point; then the signal chain's effects with scipy.signal:
white sensor noise, a causal 4th-order Butterworth anti-alias filter at 2 kHz on both
channels (started in its steady state, as on a card that has been running), 50 Hz mains
hum and 1/f noise, and rest segments of any length before and after the motion.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest
import scipy.signal
from scipy.integrate import solve_ivp

from bayestribo.errors import RecordingError
from bayestribo.model.scaling import Rig
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import (
    correlated_sum_variance,
    increment_noise,
    increment_weights,
    integrate_increments,
    pi_data,
    simpson_weights,
)
from bayestribo.signal.motion import check_turning_points
from bayestribo.signal.noise import noise_model
from bayestribo.signal.spectrum import noise_spectrum, notch_filter

MASS, F_HZ, LOAD = 0.035, 32.6, 0.31
ZETA, MU_K, MU_S, X0 = 0.0236, 0.0294, 0.04, 2e-3
RIG = Rig(natural_frequency_Hz=F_HZ, mass_kg=MASS, load_N=LOAD)
SIGMA_X, SIGMA_V = 1.5e-6, 1.5e-7  # white noise, 10x the vibrometer's resolution
CUTOFF_HZ = 2000.0


@functools.lru_cache(maxsize=1)
def _motion() -> tuple[list, np.ndarray, float]:
    """Half cycles of the free decay from x0 at rest at t = 0: dense solutions, turning
    points (t, x) including the release and the stop, and the stop time [s]."""
    omega = 2 * math.pi * F_HZ
    k, c = MASS * omega**2, 2 * ZETA * MASS * omega
    x, t0 = X0, 0.0
    arcs, turns = [], [(0.0, X0)]
    while abs(k * x) > MU_S * LOAD:
        s = -math.copysign(1.0, x)  # direction of the coming half cycle

        def rhs(_t, u, s=s):
            return [u[1], (-c * u[1] - k * u[0] - MU_K * LOAD * s) / MASS]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t0, t0 + 1 / F_HZ),
            [x, 0.0],
            method="DOP853",
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-15,
        )
        t1, x = float(sol.t_events[0][0]), float(sol.y_events[0][0][0])
        arcs.append((t0, t1, sol.sol))
        turns.append((t1, x))
        t0 = t1
    return arcs, np.array(turns), t0


def true_state(t: np.ndarray, rest_before: float) -> tuple[np.ndarray, np.ndarray]:
    """Displacement [m] and velocity [m/s] of the simulated pin at times t [s]."""
    arcs, turns, stop = _motion()
    tm = np.asarray(t, dtype=float) - rest_before
    x, v = np.full(tm.size, X0), np.zeros(tm.size)
    for a, b, sol in arcs:
        m = (tm >= a) & (tm < b)
        if m.any():
            x[m], v[m] = sol(tm[m])
    x[tm >= stop] = turns[-1, 1]
    return x, v


def record(fs: float, rest_before: float, rest_after: float):
    """Noise-free t [s], x [m], v [m/s] and the truth: turning points (t, x) and stop [s]."""
    _, turns, stop = _motion()
    t = np.arange(round((rest_before + stop + rest_after) * fs) + 1) / fs
    x, v = true_state(t, rest_before)
    return t, x, v, turns + np.array([rest_before, 0.0]), rest_before + stop


def add_effects(t, x, v, fs, *, seed, filt=False, hum=0.0, pink=0.0, n_noise=None):
    """White noise plus the chain's effects; ``hum`` and ``pink`` are rms multiples of the
    white noise; ``n_noise`` draws noise for that many samples and uses the first ones
    (the same realisation for records of different lengths)."""
    rng = np.random.default_rng(seed)
    n = t.size if n_noise is None else n_noise
    ex, ev = SIGMA_X * rng.standard_normal(n), SIGMA_V * rng.standard_normal(n)
    tt = np.arange(n) / fs
    if hum:
        phase = rng.uniform(0, 2 * math.pi, 2)
        ex += hum * SIGMA_X * math.sqrt(2) * np.sin(2 * math.pi * 50 * tt + phase[0])
        ev += hum * SIGMA_V * math.sqrt(2) * np.sin(2 * math.pi * 50 * tt + phase[1])
    if pink:
        f = np.fft.rfftfreq(n, 1 / fs)
        for e, sigma in ((ex, SIGMA_X), (ev, SIGMA_V)):
            spec = np.fft.rfft(rng.standard_normal(n))
            spec[0], spec[1:] = 0.0, spec[1:] / np.sqrt(f[1:])
            p = np.fft.irfft(spec, n)
            e += pink * sigma * p / p.std()
    xs, vs = x + ex[: t.size], v + ev[: t.size]
    if filt:
        sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
        zi = scipy.signal.sosfilt_zi(sos)
        xs = scipy.signal.sosfilt(sos, xs, zi=zi * xs[0])[0]
        vs = scipy.signal.sosfilt(sos, vs, zi=zi * vs[0])[0]
    return xs, vs


def group_delay(fs: float) -> float:
    """Group delay [s] of the anti-alias filter at the oscillation frequency."""
    b, a = scipy.signal.butter(4, CUTOFF_HZ, fs=fs)
    return float(scipy.signal.group_delay((b, a), w=[F_HZ], fs=fs)[1][0]) / fs


def stationary_noise(psd, n: int, fs: float, rng, size: int = 1) -> np.ndarray:
    """Gaussian stationary noise of one-sided PSD ``psd(f)`` [unit²/Hz], shape (size, n)."""
    amp = _shaping(psd, n, fs)
    z = rng.standard_normal((size, amp.size)) + 1j * rng.standard_normal((size, amp.size))
    return np.fft.irfft(z * amp, 2 * n, axis=-1)[:, :n]


@functools.lru_cache(maxsize=8)
def _shaping(psd, n: int, fs: float) -> np.ndarray:
    """Amplitudes that shape complex white noise into ``psd`` over 2n samples (half kept:
    no wrap-around correlation within the n returned)."""
    m = 2 * n
    f = np.fft.rfftfreq(m, 1 / fs)
    amp = np.sqrt(psd(f) * fs * m / 4.0)
    amp[0] = 0.0
    return amp


def _butterworth_psd(sigma: float, fs: float):
    """PSD of white noise of sd ``sigma`` through the anti-alias filter."""
    b, a = scipy.signal.butter(4, CUTOFF_HZ, fs=fs)

    def psd(f):
        _, h = scipy.signal.freqz(b, a, worN=f, fs=fs)
        return 2 * sigma**2 / fs * np.abs(h) ** 2

    return psd


def _pink_psd(sigma: float, fs: float, knee: float = 5.0):
    """White noise of sd ``sigma`` plus 1/f noise of 5x its rms above ``knee`` Hz."""
    top = fs / 2
    level = 25 * sigma**2 / math.log(top / knee)  # ∫_knee^top level/f df = 25 σ²

    def psd(f):
        return 2 * sigma**2 / fs + level / np.maximum(f, knee)

    return psd


# ---------------------------------------------------------------------------------------
# Each effect of a real signal chain: no refusal, and the truth recovered
# ---------------------------------------------------------------------------------------

EFFECTS = {
    "white": {},
    "filter": {"filt": True},
    "hum": {"hum": 5.0},
    "pink": {"pink": 5.0},
}
CASES = [
    ("white", 10_000.0),
    ("filter", 10_000.0),
    ("hum", 10_000.0),
    ("pink", 10_000.0),
    ("white", 1_000.0),
    ("pink", 1_000.0),
    ("white", 100_000.0),
    ("filter", 100_000.0),
]


def _check_against_truth(decay, truth, stop, fs, delay, sigma_total):
    """Turning points one to one with the simulation's, end and release within a sample."""
    dt = 1 / fs
    # The end of motion (sticking at the last turning point) and the release, both seen
    # through the filter's delay, within one sample.
    assert decay.motion_ended
    assert decay.stop_time == pytest.approx(stop + delay, abs=dt)
    assert decay.end_time - dt < stop + delay + dt
    assert decay.release_time == pytest.approx(truth[0, 0] + delay, abs=dt + 1e-9)
    # Every turning point found is one of the simulation's (no wiggle of the noise counted
    # as one): each maps to the nearest true turning point within a quarter period, the
    # map is one to one and runs over consecutive turning points (none missed between).
    t_true = truth[:, 0] + delay
    k = np.array([int(np.argmin(np.abs(t_true - tp))) for tp in decay.peaks.t])
    assert np.all(np.abs(t_true[k] - decay.peaks.t) < 0.25 / F_HZ)
    assert np.all(np.diff(k) == 1)
    # Large turning points are timed to 0.5 ms: the parabola vertex's noise is about
    # σ/(445 |Y|) s at these settings (±1/12 period fit), < 0.02 ms above 100 σ, and the
    # friction kink shifts it by (3/8)(μ_k ℓ/|Y|)(π/6)/Ω < 0.05 ms there.
    y_true = np.abs(truth[k, 1] - truth[-1, 1] * 0)  # equilibrium at 0 in the simulation
    big = y_true > 100 * sigma_total
    assert big.sum() >= 10
    np.testing.assert_allclose(decay.peaks.t[big], t_true[k][big], rtol=0, atol=5e-4)


@pytest.mark.parametrize(("effect", "fs"), CASES, ids=[f"{e}-{f / 1000:g}kHz" for e, f in CASES])
def test_each_effect_is_analysed_and_matches_the_simulation(effect, fs):
    kw = EFFECTS[effect]
    t, x, v, truth, stop = record(fs, 0.1, 0.1)
    xs, vs = add_effects(t, x, v, fs, seed=11, **kw)
    decay = energy_decay(t, xs, vs, rig=RIG)
    delay = group_delay(fs) if kw.get("filt") else 0.0
    sigma_total = SIGMA_X * math.sqrt(1 + kw.get("hum", 0.0) ** 2 + kw.get("pink", 0.0) ** 2)
    _check_against_truth(decay, truth, stop, fs, delay, sigma_total)
    # the noise at rest is measured as a spectrum, and says what it is
    rest = decay.rest_noise
    assert rest is not None and rest.source == "rest before release and rest after stop"
    assert rest.coloured is (effect != "white")
    assert (rest.mains_Hz() == 50.0) is (effect == "hum")


@pytest.mark.parametrize("rest_after", [0.1, 1.0, 2.0, 10.0, 30.0])
def test_end_of_motion_does_not_move_with_the_rest(rest_after):
    # The same record (same noise on the motion: the noise of the longest record, cut)
    # with 0.1 to 30 s of rest after the stop, through the filter, with 1/f noise.
    fs = 10_000.0
    t, x, v, _, stop = record(fs, 0.1, rest_after)
    n_longest = round((0.1 + _motion()[2] + 30.0) * fs) + 1
    xs, vs = add_effects(t, x, v, fs, seed=5, filt=True, pink=5.0, n_noise=n_longest)
    decay = energy_decay(t, xs, vs, rig=RIG)
    delay = group_delay(fs)
    assert decay.stop_time == pytest.approx(stop + delay, abs=1 / fs)
    reference = _reference_stop()
    assert decay.stop_time == pytest.approx(reference, abs=1 / fs)
    assert decay.t.size == pytest.approx(_reference_size(), abs=1)


@functools.lru_cache(maxsize=1)
def _reference_run():
    fs = 10_000.0
    t, x, v, _, _ = record(fs, 0.1, 0.1)
    n_longest = round((0.1 + _motion()[2] + 30.0) * fs) + 1
    xs, vs = add_effects(t, x, v, fs, seed=5, filt=True, pink=5.0, n_noise=n_longest)
    return energy_decay(t, xs, vs, rig=RIG)


def _reference_stop() -> float:
    return _reference_run().stop_time


def _reference_size() -> int:
    return _reference_run().t.size


def test_filter_delay_does_not_bias_the_energy():
    # Causal anti-alias filtering on both channels delays x and v alike (v = dx/dt
    # commutes with the filter), so E from one sample is the true E one group delay
    # earlier: its error stays far below the noise of E, sample by sample and over each
    # Π increment.
    fs = 10_000.0
    t, x, v, _, _ = record(fs, 0.1, 0.1)
    sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
    zi = scipy.signal.sosfilt_zi(sos)
    xf = scipy.signal.sosfilt(sos, x, zi=zi * x[0])[0]
    vf = scipy.signal.sosfilt(sos, v, zi=zi * v[0])[0]
    decay = energy_decay(t, xf, vf, rig=RIG)
    xt, vt = true_state(decay.t - group_delay(fs), 0.1)
    sc = decay.scaling
    eq = decay.equilibrium + decay.equilibrium_drift * (decay.t - decay.start_time)
    y, yp = sc.y(xt - eq), sc.yp(vt)
    e_true = 0.5 * (y * y + yp * yp)
    sd_e = np.sqrt((y * SIGMA_X / sc.length_scale) ** 2 + (yp * sc.yp(SIGMA_V)) ** 2)
    # per sample: below 0.5 sd of the white noise at 10x the resolution (measured 0.18,
    # at the turning points where the filter rounds the friction's jump of acceleration)
    assert np.max(np.abs(decay.energy - e_true) / sd_e) < 0.5
    noise = noise_model(decay, displacement_resolution=SIGMA_X, velocity_resolution=SIGMA_V)
    data = pi_data(decay, noise)
    edges, weights = _grid_of(decay, data)
    bias = integrate_increments(decay.energy - e_true, edges, weights)
    assert np.all(np.abs(bias) < 0.01 * np.sqrt(data.variance))
    # without the delay the same comparison is off by thousands of sd: the test can fail
    xt0, vt0 = true_state(decay.t, 0.1)
    e0 = 0.5 * (sc.y(xt0 - eq) ** 2 + sc.yp(vt0) ** 2)
    assert np.max(np.abs(decay.energy - e0) / sd_e) > 100


# ---------------------------------------------------------------------------------------
# Increment variances from the measured spectrum, against a Monte Carlo
# ---------------------------------------------------------------------------------------


def _grid_of(decay, data):
    """Sample indices and quadrature weights of the increments of ``data``."""
    edges = np.flatnonzero(np.isin(decay.tau, data.tau_grid))
    assert edges.size == data.increments.size + 1
    h = decay.tau[1] - decay.tau[0]
    return edges, [simpson_weights(int(b - a), h) for a, b in itertools.pairwise(edges)]


NOISES = {
    "filter-10kHz": (10_000.0, _butterworth_psd),
    "pink+hum-10kHz": (10_000.0, _pink_psd),
    "filter-100kHz": (100_000.0, _butterworth_psd),
}


@pytest.mark.parametrize(
    "name",
    [
        "filter-10kHz",
        "pink+hum-10kHz",
        pytest.param("filter-100kHz", marks=pytest.mark.validation),
    ],
)
def test_spectral_increment_variance_matches_monte_carlo(name):
    """pi_data's variances, from the noise measured at rest, against 400 noisy copies."""
    fs, make_psd = NOISES[name]
    psd_x, psd_v = make_psd(SIGMA_X, fs), make_psd(SIGMA_V, fs)
    hum = name.startswith("pink+hum")
    rng = np.random.default_rng(21)
    t, x, v, _, _ = record(fs, 3.0, 3.0)

    def noise(psd, sigma, size, n):
        e = stationary_noise(psd, n, fs, rng, size)
        if hum:
            phase = rng.uniform(0, 2 * math.pi, (size, 1))
            e += 5 * sigma * math.sqrt(2) * np.sin(2 * math.pi * 50 * t[:n] + phase)
        return e

    # the recording: its rest (3 s before, 3 s after) is where the noise is measured
    xs = x + noise(psd_x, SIGMA_X, 1, t.size)[0]
    vs = v + noise(psd_v, SIGMA_V, 1, t.size)[0]
    decay = energy_decay(t, xs, vs, rig=RIG)
    assert decay.rest_noise.coloured
    nm = noise_model(decay, displacement_resolution=0.15e-6, velocity_resolution=0.015e-6)
    data = pi_data(decay, nm)
    white = pi_data(decay, nm, spectral=False)
    assert data.spectral and not white.spectral
    assert nm.coloured and "coloured noise at rest" in nm.describe()
    # Monte Carlo: fresh noise of the same process on the decay's own y, y' (the variance
    # formula is evaluated at the observed signals, as in the white case's test)
    sc = decay.scaling
    y, yp = decay.y, decay.yp
    edges, weights = _grid_of(decay, data)
    clean = integrate_increments(decay.energy, edges, weights)
    reps, block = 400, 50
    draws = np.empty((reps, clean.size))
    for first in range(0, reps, block):
        ex = noise(psd_x, SIGMA_X, block, y.size) / sc.length_scale
        ev = sc.yp(noise(psd_v, SIGMA_V, block, y.size))
        e = 0.5 * ((y + ex) ** 2 + (yp + ev) ** 2)
        draws[first : first + block] = integrate_increments(e, edges, weights) - clean
    mc = draws.var(axis=0, ddof=1)[:-1]  # the last increment carries the end allowance
    plus = np.maximum(data.neighbour_covariance, 0.0)
    own = data.variance - np.r_[0.0, plus] - np.r_[plus, 0.0]  # each increment's own
    log_ratio = np.log(own[:-1] / mc)
    # Tolerances: a variance from 400 draws has a relative sd of √(2/399) = 7 %; the
    # spectrum measured on 6 s of rest is off by a few % for all increments alike (its
    # variance alone: √(2/n_eff) ≈ 2-4 %). Each log ratio: sd ≈ 0.08, bound 0.3 (3.5 sd);
    # their mean: sd ≈ 0.04, bound 0.12 (3 sd).
    assert np.all(np.abs(log_ratio) < 0.3), np.exp(log_ratio)
    assert abs(np.mean(log_ratio)) < 0.12
    # The white formula (σ²‖w‖² with σ² the rest variance) is far off: the test can fail.
    assert abs(np.mean(np.log(white.variance[:-1] / mc))) > 0.5
    # Neighbours' covariance against the draws': the sd of a sample covariance is about
    # √(v_j v_{j+1}/400) (5 of them, plus the spectrum's few % of the covariance).
    mc_cov = np.array([np.cov(draws[:, j], draws[:, j + 1])[0, 1] for j in range(mc.size - 1)])
    se_cov = np.sqrt(mc[:-1] * mc[1:] / reps)
    cov = data.neighbour_covariance[: mc.size - 1]
    assert np.all(np.abs(cov - mc_cov) < 5 * se_cov + 0.1 * np.abs(mc_cov))
    # and the variance of the sum of all increments (but the last) is not understated
    total = draws[:, :-1].sum(axis=1).var(ddof=1)
    assert data.variance[:-1].sum() >= total * math.exp(-3 * math.sqrt(2 / reps) - 0.1)
    # the mean shift of each increment is the bias ½(c_ε[0] + c_η[0])∫1 (5 standard errors)
    se = np.sqrt(mc / reps)
    assert np.all(np.abs(draws.mean(axis=0)[:-1] - data.noise_bias[:-1]) < 5 * se)


def test_correlated_sum_variance_against_dense_algebra():
    rng = np.random.default_rng(3)
    w = rng.normal(size=40)
    c = 0.8 ** np.arange(25) * np.cos(0.3 * np.arange(25))  # lags beyond 24 are zero
    lag = np.abs(np.subtract.outer(np.arange(40), np.arange(40)))
    dense = np.where(lag < 25, c[np.minimum(lag, 24)], 0.0)
    assert correlated_sum_variance(w, c) == pytest.approx(w @ dense @ w, rel=1e-12)
    assert correlated_sum_variance(w, np.array([2.0])) == pytest.approx(2.0 * w @ w, rel=1e-12)


def test_white_autocovariance_gives_the_white_formula_exactly():
    t, x, v, _, _ = record(10_000.0, 0.1, 0.1)
    decay = energy_decay(t, x, v, rig=RIG)
    edges, weights = increment_weights(decay.tau.size, decay.tau[1] - decay.tau[0], 33)
    sy, syp = 7e-3, 3e-4
    white = increment_noise(decay.tau, decay.y, decay.yp, edges, weights, sy, syp)
    spectral = increment_noise(
        decay.tau,
        decay.y,
        decay.yp,
        edges,
        weights,
        sy,
        syp,
        autocov_y=np.array([sy**2]),
        autocov_yp=np.array([syp**2]),
    )
    np.testing.assert_allclose(spectral[0], white[0], rtol=1e-12)
    np.testing.assert_allclose(spectral[1], white[1], rtol=1e-12)


def test_white_rest_noise_keeps_todays_increment_variances():
    fs = 10_000.0
    t, x, v, _, _ = record(fs, 1.0, 1.0)
    xs, vs = add_effects(t, x, v, fs, seed=2)
    decay = energy_decay(t, xs, vs, rig=RIG)
    assert not decay.rest_noise.coloured
    nm = noise_model(decay)
    spectral, white = pi_data(decay, nm), pi_data(decay, nm, spectral=False)
    assert not spectral.spectral and not nm.coloured
    np.testing.assert_array_equal(spectral.variance, white.variance)
    np.testing.assert_array_equal(spectral.increments, white.increments)


# ---------------------------------------------------------------------------------------
# The noise spectrum at rest
# ---------------------------------------------------------------------------------------


def test_white_noise_spectrum():
    rng = np.random.default_rng(8)
    e = 2.0 * rng.standard_normal(40_000)
    spec = noise_spectrum([e[:1000], e[1000:]], 10_000.0, period_s=1 / F_HZ)
    # 40 000 samples: the variance is known to √(2/40000) = 0.7 %
    assert spec.variance == pytest.approx(4.0, rel=0.04)
    assert spec.white_level == pytest.approx(2 * 4.0 / 10_000.0, rel=0.04)
    assert not spec.coloured and spec.lines_Hz == ()
    c = spec.autocovariance(5)
    assert np.all(np.abs(c[1:]) < 0.05 * c[0])


def test_filtered_noise_spectrum_and_autocovariance():
    fs = 10_000.0
    rng = np.random.default_rng(9)
    sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
    e = scipy.signal.sosfilt(sos, rng.standard_normal(60_000))[1000:]
    spec = noise_spectrum([e], fs, period_s=1 / F_HZ)
    assert spec.coloured
    # exact autocovariance of filtered white noise: Σ h_i h_{i+m}
    h = scipy.signal.sosfilt(sos, np.r_[1.0, np.zeros(999)])
    exact = np.array([h[: h.size - m] @ h[m:] for m in range(8)])
    # 59 000 samples: each lag's estimate is known to about 1 % of the variance
    np.testing.assert_allclose(spec.autocovariance(8), exact, rtol=0, atol=0.04 * exact[0])
    # In the signal band the PSD is the unfiltered white noise's, 2·1²/fs (|H| = 1 there),
    # while white noise of the filtered variance would have 2·var/fs: ratio 1/var (2.5).
    assert spec.colour_ratio == pytest.approx(1.0 / exact[0], rel=0.1)


def test_mains_line_is_found_with_its_amplitude():
    fs = 10_000.0
    rng = np.random.default_rng(10)
    t = np.arange(3000) / fs
    e = rng.standard_normal(t.size) + 5 * math.sqrt(2) * np.sin(2 * math.pi * 50.0 * t + 0.4)
    spec = noise_spectrum([e], fs, period_s=1 / F_HZ)
    assert len(spec.lines_Hz) == 1
    assert spec.lines_Hz[0] == pytest.approx(50.0, abs=1.0)
    assert spec.line_rms[0] == pytest.approx(5.0, rel=0.1)
    assert spec.coloured


def test_line_search_window_holds_every_bin_the_whole_grid_would():
    # the line search tests only the bins about each mains frequency; on a Welch grid
    # (rfftfreq), at any centre and reach, the window gives what the whole grid gives
    from bayestribo.signal.spectrum import _around

    rng = np.random.default_rng(11)
    for _ in range(400):
        freq = np.fft.rfftfreq(int(rng.integers(64, 1 << 16)), 1.0 / rng.uniform(50.0, 1e6))
        centre = float(rng.choice([rng.uniform(-10.0, freq[-1] + 10.0), rng.choice(freq)]))
        reach = float(rng.choice([0.0, rng.uniform(0.0, 2.0), rng.uniform(0.0, freq[-1])]))
        window = _around(freq, centre, reach)
        whole = np.abs(freq - centre) <= reach
        inside = np.zeros(freq.size, bool)
        inside[window] = np.abs(freq[window] - centre) <= reach
        np.testing.assert_array_equal(inside, whole)


# ---------------------------------------------------------------------------------------
# Mains hum removed by the zero-phase notch
# ---------------------------------------------------------------------------------------


def test_notch_removes_the_line_without_delay_or_gain():
    fs = 10_000.0
    t = np.arange(40_000) / fs
    signal = np.sin(2 * math.pi * F_HZ * t + 0.3)
    out = notch_filter(signal + 0.5 * np.sin(2 * math.pi * 50.0 * t), 50.0, fs, oscillation_Hz=F_HZ)
    mid = slice(15_000, 25_000)  # 1.5 s (7 ring times) from the edges
    # zero phase and unit gain at the oscillation: the oscillation comes out unchanged
    # to 1e-3 of its amplitude, and the 50 Hz line is gone to 1 %
    assert np.max(np.abs(out[mid] - signal[mid])) < 1e-3
    residue = out[mid] - signal[mid]
    assert np.std(residue) < 0.01 * 0.5
    with pytest.raises(RecordingError, match="notch"):
        notch_filter(signal, 6000.0, fs)


@pytest.mark.parametrize("notch", [50.0, "auto"])
def test_hum_measured_at_rest_is_removed(notch):
    fs = 10_000.0
    t, x, v, truth, stop = record(fs, 0.5, 0.5)
    xs, vs = add_effects(t, x, v, fs, seed=4, hum=5.0)
    plain = energy_decay(t, xs, vs, rig=RIG)
    assert plain.notch_Hz == () and plain.rest_noise.mains_Hz() == 50.0
    decay = energy_decay(t, xs, vs, rig=RIG, notch=notch)
    # says what it removed: the line's frequency fitted at rest (the simulation's 50 Hz)
    assert len(decay.notch_Hz) == 1 and decay.notch_Hz[0] == pytest.approx(50.0, abs=0.01)
    assert decay.rest_noise.lines_Hz == ()  # the line is gone from the rest
    assert not decay.rest_noise.coloured
    _check_against_truth(decay, truth, stop, fs, 0.0, SIGMA_X)
    # the increments agree with a hum-free copy (same white noise) within 1 sd each:
    # the subtraction touches nothing but the line (measured: 0.2 sd at most)
    xw, vw = add_effects(t, x, v, fs, seed=4)
    clean = energy_decay(t, xw, vw, rig=RIG)
    np.testing.assert_array_equal(decay.t, clean.t)
    nm = noise_model(clean)
    ref = pi_data(clean, nm)
    got = pi_data(decay, nm)
    z = (got.increments - ref.increments)[:-1] / np.sqrt(ref.variance[:-1])
    assert np.max(np.abs(z)) < 1.0


def test_auto_notch_without_a_line_changes_nothing():
    fs = 10_000.0
    t, x, v, _, _ = record(fs, 0.2, 0.2)
    xs, vs = add_effects(t, x, v, fs, seed=6)
    a, b = energy_decay(t, xs, vs, rig=RIG), energy_decay(t, xs, vs, rig=RIG, notch="auto")
    assert b.notch_Hz == ()
    np.testing.assert_array_equal(a.energy, b.energy)


# ---------------------------------------------------------------------------------------
# Bad input: the error says which part and why
# ---------------------------------------------------------------------------------------


def test_record_without_motion_is_refused():
    fs = 10_000.0
    rng = np.random.default_rng(1)
    t = np.arange(20_000) / fs
    with pytest.raises(RecordingError, match="release: no motion found"):
        energy_decay(
            t,
            1e-3 + SIGMA_X * rng.standard_normal(t.size),
            SIGMA_V * rng.standard_normal(t.size),
            rig=RIG,
        )


def test_motion_that_never_decays_is_refused():
    fs = 10_000.0
    t = np.arange(20_000) / fs
    w = 2 * math.pi * F_HZ
    with pytest.raises(RecordingError, match="energy decay: the oscillation does not decay"):
        energy_decay(t, 1e-3 * np.cos(w * t), -1e-3 * w * np.sin(w * t), rig=RIG)


def test_turning_points_not_half_a_period_apart_are_named():
    times = np.array([0.0, 0.5, 1.0, 1.3, 2.0])
    with pytest.raises(RecordingError, match=r"turning points: turning points 2 and 3 .* apart"):
        check_turning_points(times, 0.5)
    check_turning_points(times[:3], 0.5)


def test_bad_notch_argument_is_refused():
    t, x, v, _, _ = record(10_000.0, 0.1, 0.1)
    for bad in ("fifty", -50.0, True):
        with pytest.raises(RecordingError, match="notch"):
            energy_decay(t, x, v, notch=bad)


def test_band_level_standard_error_matches_its_scatter():
    # 40 short rests (2 × 0.09 s at 10 kHz) of filtered noise: the scatter of the band
    # level agrees with the stated standard error (the sd of a sd from 40 draws is 11 %:
    # a factor 1.4 is 3 of them).
    fs = 10_000.0
    rng = np.random.default_rng(12)
    sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
    levels, stated = [], []
    for _ in range(40):
        e = scipy.signal.sosfilt(sos, rng.standard_normal(2300))[500:]
        spec = noise_spectrum([e[:900], e[900:]], fs, period_s=1 / F_HZ)
        levels.append(spec.band_level)
        stated.append(spec.band_rel_se)
    observed = np.std(levels, ddof=1) / np.mean(levels)
    assert 1 / 1.4 < observed / np.mean(stated) < 1.4
