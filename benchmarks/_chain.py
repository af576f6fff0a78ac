"""Independent simulator of a recorded free decay: one law of motion, one signal chain.

Shared by ``benchmarks/misspecification.py`` and ``benchmarks/frontend.py``. Nothing
here comes from the package: the motion is ``scipy.integrate.solve_ivp`` half cycle by
half cycle (the friction's sign is constant between velocity zeros) of

    m x'' + c x' + c₂ |x'| x' + k x + k₃ x³ + μ(x) N sgn(x') = 0,
    μ(x) = μ_k (1 + a sin(2π x / λ)),

from x₀ at rest, sticking at the first turning point where the spring force is inside
±μ_s N, on the paper's rig (m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236,
μ_k = 0.0294, μ_s = 0.04, x₀ = 2 mm). With k₃ = c₂ = a = 0 this is the model the fit
assumes (the simulator of ``tests/test_signal_frontend.py``).

:func:`record` samples that motion at any rate with any rest before and after it;
:func:`apply_chain` then passes it through a signal chain: channel errors (velocity gain,
a band-limited displacement delay), white sensor noise in multiples of the vibrometer's
resolution, 50 Hz mains hum and 1/f noise in multiples of the white noise's rms, and a
causal 4th-order Butterworth anti-alias filter at 2 kHz on both channels (started in its
steady state, as on a card that has been running). At 10x the resolution the random
draws are those of ``tests/test_signal_frontend.py::add_effects`` for the same seed.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
import scipy.signal
from scipy import stats
from scipy.integrate import solve_ivp

__all__ = [
    "CHAIN_EFFECTS",
    "CUTOFF_HZ",
    "F_HZ",
    "LOAD",
    "MASS",
    "MU_K",
    "OMEGA",
    "RESOLUTION_V",
    "RESOLUTION_X",
    "X0",
    "ZETA",
    "C",
    "K",
    "apply_chain",
    "clopper_pearson",
    "metadata",
    "motion",
    "record",
]

MASS, F_HZ, LOAD = 0.035, 32.6, 0.31
ZETA, MU_K, MU_S, X0 = 0.0236, 0.0294, 0.04, 2e-3
RESOLUTION_X, RESOLUTION_V = 0.15e-6, 0.015e-6  # the vibrometer's resolution [m, m/s]
CUTOFF_HZ = 2000.0  # anti-alias filter
HUM_HZ = 50.0
OMEGA = 2 * math.pi * F_HZ
K, C = MASS * OMEGA**2, 2 * ZETA * MASS * OMEGA

#: The effects of a real signal chain, each alone: effect -> (sample rate [Hz], rest
#: after the stop [s] (0.1 s before the release in every case), options of
#: :func:`apply_chain`, notch for the fit). The 1/f noise is drawn over the whole
#: record; the hum has a random phase per channel.
CHAIN_EFFECTS: dict[str, tuple[float, float, dict[str, Any], str | None]] = {
    "clean": (10_000.0, 0.1, {}, None),
    "filter": (10_000.0, 0.1, {"filt": True}, None),
    "hum": (10_000.0, 0.1, {"hum": 5.0}, None),
    "hum-notch": (10_000.0, 0.1, {"hum": 5.0}, "auto"),
    "pink": (10_000.0, 0.1, {"pink": 5.0}, None),
    "rest-2s": (10_000.0, 2.0, {}, None),
    "rest-30s": (10_000.0, 30.0, {}, None),
    "1kHz": (1_000.0, 0.1, {}, None),
    "100kHz": (100_000.0, 0.1, {"filt": True}, None),
}


@functools.lru_cache(maxsize=8)
def motion(
    k3: float = 0.0,
    c2: float = 0.0,
    track: tuple[float, float] = (0.0, 1.0),
    pendulum: float = 0.0,
    zeta: float = ZETA,
    mu_k: float = MU_K,
    until: float = math.inf,
) -> tuple[tuple, float, float]:
    """Half cycles of the free decay from x₀ at rest at t = 0: (dense solutions per half
    cycle as (t_start, t_end, sol), the stop time [s], the displacement at rest [m]).

    ``k3`` [N/m³] cubic stiffness, ``c2`` [N s²/m²] quadratic drag, ``track`` = (a, λ [m])
    friction varying along the track; ``pendulum`` > 0: the spring force is
    k L sin(x/L) with L = x₀/pendulum (a pendulum released at ``pendulum`` rad, its
    small-swing stiffness k) instead of k x; ``zeta`` and ``mu_k`` the viscous damping
    ratio and the kinetic friction coefficient (the paper's rig's by default); ``until``
    [s]: no half cycle is begun after this time (a record that ends in motion; the stop
    time is then that of the last half cycle integrated)."""
    amplitude, wavelength = track
    length = X0 / pendulum if pendulum else 0.0
    c = 2 * zeta * MASS * OMEGA

    def mu(x: float) -> float:
        return mu_k * (1.0 + amplitude * math.sin(2 * math.pi * x / wavelength))

    def spring(x: float) -> float:
        linear = K * length * math.sin(x / length) if length else K * x
        return linear + k3 * x**3

    arcs, x, t0 = [], X0, 0.0
    while abs(spring(x)) > MU_S * LOAD * mu_k / MU_K and t0 <= until:
        s = -math.copysign(1.0, x)  # direction of the coming half cycle

        def rhs(_t, u, s=s):
            friction = mu(u[0]) * LOAD * s
            force = -c * u[1] - c2 * abs(u[1]) * u[1] - spring(u[0]) - friction
            return [u[1], force / MASS]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t0, t0 + (2.0 if pendulum else 1.0) / F_HZ),
            [x, 0.0],
            method="DOP853",
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-15,
        )
        t1, x = float(sol.t_events[0][0]), float(sol.y_events[0][0][0])
        arcs.append((t0, t1, sol.sol))
        t0 = t1
    return tuple(arcs), t0, x


def record(
    fs: float,
    rest_before: float,
    rest_after: float,
    *,
    k3: float = 0.0,
    c2: float = 0.0,
    track: tuple[float, float] = (0.0, 1.0),
    pendulum: float = 0.0,
    zeta: float = ZETA,
    mu_k: float = MU_K,
    duration: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Noise-free t [s], x [m], v [m/s] sampled at ``fs`` [Hz], with ``rest_before`` and
    ``rest_after`` [s] of rest around the motion of :func:`motion` (same law options);
    ``duration`` [s]: the record ends this long after the release, in motion (no rest
    after it; ``rest_after`` is then not used)."""
    until = math.inf if duration is None else duration
    arcs, stop, x_stop = motion(k3, c2, tuple(track), pendulum, zeta, mu_k, until)
    if duration is not None and duration > stop:
        raise ValueError(f"duration: the motion stops at {stop:.3f} s, before {duration} s")
    end = rest_before + (stop + rest_after if duration is None else duration)
    t = np.arange(round(end * fs) + 1) / fs
    tm = t - rest_before
    x, v = np.full(t.size, X0), np.zeros(t.size)
    for a, b, sol in arcs:
        m = (tm >= a) & (tm < b)
        if m.any():
            x[m], v[m] = sol(tm[m])
    x[tm >= stop] = x_stop
    return t, x, v


def _delayed(t: np.ndarray, signal: np.ndarray, delay: float) -> np.ndarray:
    """``signal`` delayed by ``delay`` [s] (band-limited, through an FFT of twice the
    length padded with the last value, so nothing wraps around)."""
    n = signal.size
    padded = np.concatenate((signal, np.full(n, signal[-1])))
    f = np.fft.rfftfreq(2 * n, t[1] - t[0])
    return np.fft.irfft(np.fft.rfft(padded) * np.exp(-2j * np.pi * f * delay), 2 * n)[:n]


def apply_chain(
    t: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    fs: float,
    *,
    seed: Any,
    noise: float = 10.0,
    filt: bool = False,
    hum: float = 0.0,
    pink: float = 0.0,
    velocity_gain: float = 1.0,
    displacement_delay_s: float = 0.0,
    one_pole_hz: float = 0.0,
    steps: float = 0.0,
    spikes: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """The recorded displacement and velocity: the true ``x``, ``v`` through the chain.

    ``noise``: white noise sd in multiples of the resolution (1.5 µm, 0.15 µm/s at 10);
    ``hum``, ``pink``: 50 Hz line (random phase per channel) and 1/f noise, rms in
    multiples of the white noise's sd; ``filt``: the 2 kHz anti-alias filter after the
    noise; ``velocity_gain`` and ``displacement_delay_s``: channel errors on the true
    signals; ``one_pole_hz``: a first-order low-pass at that cutoff on both channels
    (bilinear, steady state at the start); ``steps``: both channels rounded to a digitiser
    step of 1/``steps`` of their peak-to-peak swing; ``spikes``: that many single
    samples of the displacement moved by 30 % of x₀ (a sensor's dropouts), at random
    times in the motion. ``seed``: anything :func:`numpy.random.default_rng` takes."""
    rng = np.random.default_rng(seed)
    sigma_x, sigma_v = noise * RESOLUTION_X, noise * RESOLUTION_V
    n = t.size
    if displacement_delay_s:
        x = _delayed(t, x, displacement_delay_s)
    v = v * velocity_gain
    ex, ev = sigma_x * rng.standard_normal(n), sigma_v * rng.standard_normal(n)
    if hum:
        phase = rng.uniform(0, 2 * math.pi, 2)
        ex += hum * sigma_x * math.sqrt(2) * np.sin(2 * math.pi * HUM_HZ * t + phase[0])
        ev += hum * sigma_v * math.sqrt(2) * np.sin(2 * math.pi * HUM_HZ * t + phase[1])
    if pink:
        f = np.fft.rfftfreq(n, 1 / fs)
        for e, sigma in ((ex, sigma_x), (ev, sigma_v)):
            spec = np.fft.rfft(rng.standard_normal(n))
            spec[0], spec[1:] = 0.0, spec[1:] / np.sqrt(f[1:])
            p = np.fft.irfft(spec, n)
            e += pink * sigma * p / p.std()
    xs, vs = x + ex, v + ev
    if filt:
        sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
        zi = scipy.signal.sosfilt_zi(sos)
        xs = scipy.signal.sosfilt(sos, xs, zi=zi * xs[0])[0]
        vs = scipy.signal.sosfilt(sos, vs, zi=zi * vs[0])[0]
    if one_pole_hz:
        b, a = scipy.signal.butter(1, one_pole_hz, fs=fs)
        zi = scipy.signal.lfilter_zi(b, a)
        xs = scipy.signal.lfilter(b, a, xs, zi=zi * xs[0])[0]
        vs = scipy.signal.lfilter(b, a, vs, zi=zi * vs[0])[0]
    if steps:
        qx, qv = np.ptp(x) / steps, np.ptp(v) / steps
        xs, vs = np.round(xs / qx) * qx, np.round(vs / qv) * qv
    if spikes:
        moving = np.flatnonzero(np.abs(v) > 0)
        where = rng.choice(moving[: moving.size // 2], size=spikes, replace=False)
        xs = xs.copy()
        xs[where] += 0.3 * X0 * rng.choice([-1.0, 1.0], size=spikes)
    return xs, vs


def clopper_pearson(k: int, n: int) -> list[float]:
    """Clopper-Pearson 95 % interval of a binomial proportion k/n."""
    if n == 0:
        return [math.nan, math.nan]
    lo = stats.beta.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
    hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
    return [float(lo), float(hi)]


def metadata() -> dict[str, float]:
    """The run's metadata: the rig and the vibrometer's resolution (not the noise)."""
    return {
        "natural_frequency_Hz": F_HZ,
        "mass_kg": MASS,
        "load_N": LOAD,
        "displacement_resolution_m": RESOLUTION_X,
        "velocity_resolution_m_per_s": RESOLUTION_V,
        # the simulated chain's gain is exact (a case with a filter says otherwise)
        "gain_uncertainty": 0.0,
    }
