"""A realistic free-decay recording, simulated on the exact model.

:func:`simulate` reproduces what the vibrometer of the tribometer records (Rigaud
et al. 2010, section 2): the pin held at rest by the electromagnet, its release
with a magnet pull that fades during the first oscillation, the free decay with
viscous damping and Coulomb friction (the exact piecewise solution, Eq. 16-17, with
sticking, Eq. 8), the pin at rest after the stop, a displacement offset, an
arbitrary time origin, white noise on each channel (by default at the sensor
resolution), optional quantisation at the resolution and optional saturation at the
sensor range.

The magnet phase. Before the release the magnet force balances the spring at the
initial displacement x₀. From the release it fades smoothly to zero over
``magnet_fade_s`` (``F(t) = k x₀ (1 + cos(π t/t_f))/2``); the pin breaks away when
the unbalanced spring force exceeds static friction. While the force fades the pin
slides in one direction, and this phase is integrated numerically (``solve_ivp``,
DOP853, relative tolerance 1e-11). At the end of the fade the state (y, y') is
handed to :func:`bayestribo.model.exact_response`, which is exact from there on.

Amplitude-dependent damping or friction. ``zeta`` and ``mu_k`` may be callables of
the amplitude [m]: each half cycle, from one turning point to the next, then uses
the values at the |x| of the turning point that starts it (the first, after the
magnet phase, the value at the initial displacement). Within a half cycle the
solution stays exact (Eq. 16-17 with that half cycle's constants).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.io.run import Run
from bayestribo.model.scaling import Rig

__all__ = [
    "DISPLACEMENT_RESOLUTION_M",
    "VELOCITY_RESOLUTION_M_PER_S",
    "AmplitudeLaw",
    "simulate",
]

#: Displacement resolution of the laser vibrometer of the paper, 0.15 µm (section 2.3).
DISPLACEMENT_RESOLUTION_M = 0.15e-6
#: Velocity resolution of the laser vibrometer of the paper, 0.015 µm/s (section 2.3).
VELOCITY_RESOLUTION_M_PER_S = 0.015e-6

#: Cap on the half cycles simulated one by one with amplitude-dependent parameters.
_MAX_HALF_CYCLES = 10_000

#: A parameter that depends on the oscillation amplitude: ``law(amplitude_m) -> value``.
AmplitudeLaw = Callable[[float], float]


def _positive(name: str, value: float, allow_zero: bool = False) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0.0 or (value == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be a finite number {bound}, got {value!r}")
    return value


def _decimals(step: float) -> int | None:
    """Number of decimals of ``step`` written as a short decimal (None if not short)."""
    for d in range(0, 16):
        scaled = step * 10.0**d
        if abs(scaled - round(scaled)) <= 1e-9 * scaled:
            return d
    return None


def _quantise(values: NDArray, step: float) -> NDArray:
    """Round to multiples of ``step``, as the nearest doubles of short decimals."""
    out = np.rint(values / step) * step
    d = _decimals(step)
    return np.round(out, d) if d is not None else out


@dataclass(frozen=True)
class _Segment:
    """Exact free motion from state (y, yp) at τ = start, with constant parameters."""

    start: float
    end: float  # inf for the last segment (which sticks by itself, or never stops)
    y: float
    yp: float
    zeta: float
    mu_k: float
    mu_s: float


def _law(value: float | AmplitudeLaw, name: str) -> Callable[[float], float]:
    if callable(value):

        def checked(amplitude: float) -> float:
            out = float(value(amplitude))
            if not math.isfinite(out) or out < 0.0:
                raise ValueError(
                    f"{name}({amplitude!r} m) returned {out!r}; expected a finite value >= 0"
                )
            return out

        return checked
    constant = float(value)
    return lambda amplitude: constant


def _free_segments(
    start: float,
    y: float,
    yp: float,
    zeta: float | AmplitudeLaw,
    mu_k: float | AmplitudeLaw,
    mu_s: float | None,
    length_scale: float,
    friction: bool,
    amplitude_m: float,
    tau_limit: float,
) -> list[_Segment]:
    """Segments of free motion from (y, yp) at τ = start until the stop or ``tau_limit``."""
    from bayestribo.model import stop_time, turning_points

    zeta_of, mu_of = _law(zeta, "zeta"), _law(mu_k, "mu_k")

    def params(amp: float) -> tuple[float, float, float]:
        z = zeta_of(amp)
        m = mu_of(amp) if friction else 0.0
        s = m if mu_s is None else float(mu_s)
        return z, m, s

    if not callable(zeta) and not callable(mu_k):
        return [_Segment(start, math.inf, y, yp, *params(amplitude_m))]
    segments: list[_Segment] = []
    amp = amplitude_m
    while True:
        if len(segments) >= _MAX_HALF_CYCLES:
            raise ValueError(
                f"the motion does not stop within {_MAX_HALF_CYCLES} half cycles: give "
                "motion_duration_s, the time to record after the release"
            )
        z, m, s = params(amp)
        stop = float(stop_time(y, z, m, s, yp))
        tau_n, y_n = turning_points(y, z, m, s, yp, max_count=2 if yp == 0.0 else 1)
        if stop <= tau_n[-1] * (1 + 1e-12) or tau_n[-1] == 0.0:
            segments.append(_Segment(start, math.inf, y, yp, z, m, s))
            return segments
        end = start + float(tau_n[-1])
        segments.append(_Segment(start, end, y, yp, z, m, s))
        if end >= tau_limit:
            return segments
        start, y, yp = end, float(y_n[-1]), 0.0
        amp = abs(y) * length_scale


@dataclass(frozen=True)
class _MagnetPhase:
    """Integrated motion while the magnet pull fades: 0 <= τ < τ_f."""

    tau_break: float  # breakaway time (static friction overcome)
    tau_fade: float
    solution: Any  # dense output of solve_ivp, (y, y') at τ in [tau_break, tau_fade]

    @property
    def end_state(self) -> tuple[float, float]:
        y, yp = self.solution(self.tau_fade)
        return float(y), float(yp)

    def fill(self, tau: NDArray, y: NDArray, yp: NDArray) -> None:
        """Fill the samples with tau_break <= τ < τ_f (in place)."""
        sel = (tau >= self.tau_break) & (tau < self.tau_fade)
        if sel.any():
            y[sel], yp[sel] = self.solution(tau[sel])


def _magnet_phase(
    y0: float, zeta: float, mu_k: float, mu_s: float, tau_fade: float
) -> _MagnetPhase:
    """Motion from rest at y0 > 0 while the magnet pull fades over τ_f.

    Dimensionless equation while sliding towards negative y (y' < 0):
    y'' + 2ζy' + y = μ_k + y0 g(τ),  g(τ) = (1 + cos(πτ/τ_f))/2,
    from the breakaway, where the unbalanced spring force y0 (1 - g) reaches μ_s.
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    def g(tau: float) -> float:
        return 0.5 * (1.0 + math.cos(math.pi * min(tau, tau_fade) / tau_fade))

    t_break = 0.0 if mu_s == 0.0 else brentq(lambda t: y0 * (1.0 - g(t)) - mu_s, 0.0, tau_fade)

    def rhs(tau: float, state: NDArray) -> list[float]:
        y, yp = state
        return [yp, -2.0 * zeta * yp - y + mu_k + y0 * g(tau)]

    sol = solve_ivp(
        rhs,
        (t_break, tau_fade),
        [y0, 0.0],
        method="DOP853",
        rtol=1e-11,
        atol=1e-12 * max(y0, 1.0),
        dense_output=True,
    )
    if not sol.success:  # pragma: no cover - smooth forcing, tight tolerance
        raise RuntimeError(f"magnet phase integration failed: {sol.message}")
    # The phase is integrated in one sliding direction: check that the pin never turns
    # back (y' = 0) before the end of the fade, on a grid of 50 points per period.
    check = np.linspace(t_break, tau_fade, 1 + max(200, int(50 * tau_fade / (2 * math.pi))))[1:]
    if np.any(sol.sol(check)[1] >= 0.0):
        raise ValueError(
            "magnet_fade_s is too long: the pin turns back before the magnet force has faded "
            "(this simulator slides it in one direction while the force fades); expected a "
            "fade within the first oscillation (the default is a quarter period)"
        )
    return _MagnetPhase(t_break, tau_fade, sol.sol)


def simulate(
    *,
    zeta: float | AmplitudeLaw = 0.0236,
    mu_k: float | AmplitudeLaw | None = None,
    mu_s: float | None = None,
    load_N: float = 0.31,
    mass_kg: float = 0.035,
    natural_frequency_Hz: float = 32.6,
    initial_displacement_m: float = 1.5e-3,
    sample_rate_Hz: float = 10_000.0,
    rest_before_s: float = 0.05,
    motion_duration_s: float | None = None,
    rest_after_s: float = 0.1,
    magnet_fade_s: float | None = None,
    offset_m: float = 0.0,
    time_origin_s: float = 0.0,
    displacement_noise_m: float | None = None,
    velocity_noise_m_per_s: float | None = None,
    displacement_resolution_m: float = DISPLACEMENT_RESOLUTION_M,
    velocity_resolution_m_per_s: float = VELOCITY_RESOLUTION_M_PER_S,
    quantise: bool = False,
    displacement_range_m: float | None = None,
    velocity_range_m_per_s: float | None = None,
    channels: tuple[str, ...] = ("displacement", "velocity"),
    seed: int | np.random.Generator | None = None,
    metadata: Mapping[str, Any] | None = None,
) -> Run:
    """Simulate one free-decay recording of the tribometer.

    Parameters
    ----------
    zeta : float or callable
        Equivalent viscous damping ζ [-] (Eq. 6), or ``zeta(amplitude_m)``.
    mu_k : float or callable, optional
        Kinetic friction coefficient μ_k [-] (Eq. 3), or ``mu_k(amplitude_m)``.
        Default 0.0294 with contact (``load_N > 0``), 0 without.
    mu_s : float, optional
        Static friction coefficient μ_s >= μ_k [-] (Eq. 2, 5); default μ_k.
    load_N : float
        Normal load N [N]; 0 for a test without contact (no friction).
    mass_kg : float
        Oscillating mass m [kg].
    natural_frequency_Hz : float
        Natural frequency f [Hz]; k = m(2πf)² (Eq. 6).
    initial_displacement_m : float
        Initial displacement x₀ > 0 where the magnet holds the pin [m].
    sample_rate_Hz : float
        Sample rate [Hz].
    rest_before_s : float
        Time at rest before the release [s].
    motion_duration_s : float, optional
        Time recorded after the release before the rest tail [s]; default until the
        motion stops (required when it never stops, e.g. without contact).
    rest_after_s : float
        Time recorded after the motion [s] (the pin at rest).
    magnet_fade_s : float, optional
        Duration over which the magnet pull fades after the release [s]; default a
        quarter of the natural period; 0 for an ideal release.
    offset_m : float
        Constant added to the displacement [m] (the sensor's zero is arbitrary).
    time_origin_s : float
        Time stamp of the first sample [s].
    displacement_noise_m, velocity_noise_m_per_s : float, optional
        Standard deviation of the white noise on each channel [m], [m/s]; default the
        sensor resolution; 0 for none.
    displacement_resolution_m, velocity_resolution_m_per_s : float
        Sensor resolution [m], [m/s] (default: the paper's vibrometer), recorded in the
        metadata and used for quantisation.
    quantise : bool
        Round each channel to multiples of its resolution.
    displacement_range_m, velocity_range_m_per_s : float, optional
        Sensor range [m], [m/s]: samples beyond are saturated at ±range (a clipped,
        invalid recording), and the range is recorded in the metadata.
    channels : tuple of str
        Which of ``"displacement"`` and ``"velocity"`` to record.
    seed : int or numpy.random.Generator, optional
        Seed of the noise; the same seed gives the same run.
    metadata : mapping, optional
        Further metadata (e.g. ``lubricant``, ``repeat``, ``run_id``); it may override
        the keys written by the simulator.

    Returns
    -------
    Run
        Time stamps ``time_origin_s + i/sample_rate_Hz`` rounded to 1 ns, signals, and
        metadata: the rig, resolutions, ``sample_rate_Hz``, and a ``"simulation"``
        mapping with the true parameters (ζ, μ_k, μ_s as numbers when constant), the
        release time and the noise levels.

    Raises
    ------
    ValueError
        Naming the argument, for values out of range, friction without a load, motion
        that never stops without ``motion_duration_s``, or an initial displacement
        inside the static-friction band.

    Examples
    --------
    >>> run = simulate(load_N=0.31, seed=1)
    >>> run.metadata["load_N"], run.velocity is not None
    (0.31, True)
    """
    from bayestribo.model import exact_response, stop_time

    rig = Rig(natural_frequency_Hz=natural_frequency_Hz, mass_kg=mass_kg, load_N=load_N)
    scaling = rig.scaling()
    friction = rig.has_contact
    if mu_k is None:
        mu_k = 0.0294 if friction else 0.0
    if not friction and (callable(mu_k) or float(mu_k) != 0.0):
        raise ValueError(
            f"mu_k must be 0 without contact (load_N = {load_N!r}); friction needs a load"
        )
    if not callable(zeta) and not 0.0 <= float(zeta) < 1.0:
        raise ValueError(f"zeta must satisfy 0 <= zeta < 1, got {zeta!r}")
    if not callable(mu_k):
        _positive("mu_k", mu_k, allow_zero=True)
    if mu_s is not None:
        _positive("mu_s", mu_s, allow_zero=True)
        if not callable(mu_k) and mu_s < float(mu_k):
            raise ValueError(f"mu_s must be >= mu_k, got mu_s={mu_s!r} < mu_k={mu_k!r}")
    x0 = _positive("initial_displacement_m", initial_displacement_m)
    fs = _positive("sample_rate_Hz", sample_rate_Hz)
    rest_before_s = _positive("rest_before_s", rest_before_s, allow_zero=True)
    rest_after_s = _positive("rest_after_s", rest_after_s, allow_zero=True)
    if motion_duration_s is not None:
        motion_duration_s = _positive("motion_duration_s", motion_duration_s)
    period = 1.0 / natural_frequency_Hz
    fade_s = 0.25 * period if magnet_fade_s is None else magnet_fade_s
    fade_s = _positive("magnet_fade_s", fade_s, allow_zero=True)
    for name, value in (("offset_m", offset_m), ("time_origin_s", time_origin_s)):
        if not math.isfinite(float(value)):
            raise ValueError(f"{name} must be finite, got {value!r}")
    sigma_x = displacement_resolution_m if displacement_noise_m is None else displacement_noise_m
    sigma_v = (
        velocity_resolution_m_per_s if velocity_noise_m_per_s is None else velocity_noise_m_per_s
    )
    sigma_x = _positive("displacement_noise_m", sigma_x, allow_zero=True)
    sigma_v = _positive("velocity_noise_m_per_s", sigma_v, allow_zero=True)
    _positive("displacement_resolution_m", displacement_resolution_m)
    _positive("velocity_resolution_m_per_s", velocity_resolution_m_per_s)
    unknown = set(channels) - {"displacement", "velocity"}
    if unknown or not channels:
        raise ValueError(f"channels must be some of ('displacement', 'velocity'), got {channels!r}")

    # Dimensionless initial state and parameters at the initial amplitude.
    ell, omega = scaling.length_scale, scaling.omega
    y0 = x0 / ell
    z0 = float(zeta(x0)) if callable(zeta) else float(zeta)
    m0 = (float(mu_k(x0)) if callable(mu_k) else float(mu_k)) if friction else 0.0
    s0 = m0 if mu_s is None else float(mu_s)
    if y0 <= s0:
        raise ValueError(
            f"initial_displacement_m = {x0!r} m is inside the static-friction band "
            f"±μ_s N/k = ±{s0 * ell!r} m: the pin would not move"
        )

    tau_fade = omega * fade_s
    magnet = _magnet_phase(y0, z0, m0, s0, tau_fade) if tau_fade > 0.0 else None
    y_f, yp_f = magnet.end_state if magnet is not None else (y0, 0.0)
    if motion_duration_s is None and not friction:
        raise ValueError(
            "the motion never stops (no friction without contact): give motion_duration_s, "
            "the time to record after the release"
        )
    tau_limit = math.inf if motion_duration_s is None else omega * motion_duration_s
    segments = _free_segments(
        tau_fade, y_f, yp_f, zeta, mu_k, mu_s, ell, friction, x0, max(tau_limit, tau_fade)
    )
    last = segments[-1]
    tau_stop = last.start + float(stop_time(last.y, last.zeta, last.mu_k, last.mu_s, last.yp))
    if motion_duration_s is None:
        if not math.isfinite(tau_stop):
            raise ValueError(
                "the motion never stops (no friction): give motion_duration_s, the time to "
                "record after the release"
            )
        motion_s = tau_stop / omega
    else:
        motion_s = motion_duration_s

    n = math.floor((rest_before_s + motion_s + rest_after_s) * fs + 1e-9) + 1
    t_rel = np.arange(n, dtype=np.float64) / fs
    tau = omega * (t_rel - rest_before_s)
    y = np.full(n, y0)
    yp = np.zeros(n)
    if magnet is not None:
        magnet.fill(tau, y, yp)
    for seg in segments:
        sel = (tau >= seg.start) & (tau < seg.end)
        if sel.any():
            ys, yps = exact_response(
                tau[sel] - seg.start, seg.y, seg.zeta, seg.mu_k, seg.mu_s, seg.yp
            )
            y[sel], yp[sel] = ys, yps

    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x = ell * y + offset_m + sigma_x * rng.standard_normal(n)
    v = ell * omega * yp + sigma_v * rng.standard_normal(n)
    if quantise:
        x = _quantise(x, displacement_resolution_m)
        v = _quantise(v, velocity_resolution_m_per_s)
    if displacement_range_m is not None:
        limit = _positive("displacement_range_m", displacement_range_m)
        x = np.clip(x, -limit, limit)
    if velocity_range_m_per_s is not None:
        limit = _positive("velocity_range_m_per_s", velocity_range_m_per_s)
        v = np.clip(v, -limit, limit)
    time = np.round(time_origin_s + t_rel, 9)

    truth: dict[str, Any] = {
        "zeta": None if callable(zeta) else float(zeta),
        "mu_k": None if callable(mu_k) else float(mu_k) if friction else 0.0,
        "mu_s": s0 if mu_s is not None or not callable(mu_k) else None,
        "amplitude_dependent": callable(zeta) or callable(mu_k),
        "initial_displacement_m": x0,
        "offset_m": float(offset_m),
        "release_time_s": float(time_origin_s + rest_before_s),
        "magnet_fade_s": fade_s,
        "motion_duration_s": motion_s,
        "displacement_noise_m": sigma_x,
        "velocity_noise_m_per_s": sigma_v,
        "quantised": bool(quantise),
        "seed": seed if isinstance(seed, int) else None,
    }
    meta: dict[str, Any] = {
        "load_N": float(load_N),
        "mass_kg": float(mass_kg),
        "natural_frequency_Hz": float(natural_frequency_Hz),
        "displacement_resolution_m": float(displacement_resolution_m),
        "velocity_resolution_m_per_s": float(velocity_resolution_m_per_s),
        "sample_rate_Hz": fs,
    }
    if displacement_range_m is not None:
        meta["displacement_range_m"] = float(displacement_range_m)
    if velocity_range_m_per_s is not None:
        meta["velocity_range_m_per_s"] = float(velocity_range_m_per_s)
    meta["simulation"] = truth
    meta.update(metadata or {})
    return Run(
        time,
        x if "displacement" in channels else None,
        v if "velocity" in channels else None,
        meta,
    )
