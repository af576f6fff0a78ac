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

Any other law. With :class:`~bayestribo.synthetic.setup.LawParameters` (any law of
the registry, :mod:`bayestribo.model.laws`) the motion, the magnet's fade included,
is integrated by :func:`bayestribo.synthetic.motion.integrate_law` (``solve_ivp`` half
cycle by half cycle, independent of the fit's integrator), and the metadata say so:
``simulation["solver"]``, with the law, its parameters and their units.
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
from bayestribo.synthetic.setup import (
    PAPER_RIG,
    AmplitudeLaw,
    DissipationLaw,
    LawParameters,
    Release,
    Sensor,
)

__all__ = ["simulate"]

#: Cap on the half cycles simulated one by one with amplitude-dependent parameters.
_MAX_HALF_CYCLES = 10_000


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


def _checked_rig(rig: Rig) -> tuple[Rig, float, float]:
    """The rig with its mass and load (both needed to simulate friction), as floats."""
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be a bayestribo Rig, got {type(rig).__name__}")
    if rig.mass_kg is None or rig.load_N is None:
        raise ValueError(
            "rig must give mass_kg and load_N to simulate (load_N = 0 for a test without "
            f"contact), got {rig!r}"
        )
    return rig, float(rig.mass_kg), float(rig.load_N)


def _friction_law(law: DissipationLaw, friction: bool, load_N: float) -> DissipationLaw:
    """The law with its default μ_k for this rig, checked against the contact."""
    mu_k = law.mu_k
    if mu_k is None:
        mu_k = 0.0294 if friction else 0.0
    if not friction and (callable(mu_k) or float(mu_k) != 0.0):
        raise ValueError(
            f"mu_k must be 0 without contact (load_N = {load_N!r}); friction needs a load"
        )
    return DissipationLaw(law.zeta, mu_k, law.mu_s)


@dataclass(frozen=True)
class _Motion:
    """The noise-free dimensionless motion sampled on the record's time grid."""

    t_rel: NDArray  # time since the first sample [s]
    y: NDArray
    yp: NDArray
    mu_s0: float  # μ_s at the initial amplitude
    fade_s: float
    motion_s: float


def _motion(law: DissipationLaw, rig: Rig, release: Release, sample_rate_Hz: float) -> _Motion:
    """Magnet phase, then exact free motion (piecewise for an amplitude law), sampled."""
    from bayestribo.model import exact_response, stop_time

    scaling = rig.scaling()
    friction = rig.has_contact
    zeta, mu_k, mu_s = law.zeta, law.mu_k, law.mu_s
    assert mu_k is not None  # set by _friction_law
    x0 = float(release.initial_displacement_m)
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
    fade_s = release.fade_s(rig)
    tau_fade = omega * fade_s
    magnet = _magnet_phase(y0, z0, m0, s0, tau_fade) if tau_fade > 0.0 else None
    y_f, yp_f = magnet.end_state if magnet is not None else (y0, 0.0)
    duration = release.motion_duration_s
    if duration is None and not friction:
        raise ValueError(
            "the motion never stops (no friction without contact): give motion_duration_s, "
            "the time to record after the release"
        )
    tau_limit = math.inf if duration is None else omega * duration
    segments = _free_segments(
        tau_fade, y_f, yp_f, zeta, mu_k, mu_s, ell, friction, x0, max(tau_limit, tau_fade)
    )
    last = segments[-1]
    tau_stop = last.start + float(stop_time(last.y, last.zeta, last.mu_k, last.mu_s, last.yp))
    if duration is None:
        if not math.isfinite(tau_stop):
            raise ValueError(
                "the motion never stops (no friction): give motion_duration_s, the time to "
                "record after the release"
            )
        motion_s = tau_stop / omega
    else:
        motion_s = duration

    fs = sample_rate_Hz
    n = math.floor((release.rest_before_s + motion_s + release.rest_after_s) * fs + 1e-9) + 1
    t_rel = np.arange(n, dtype=np.float64) / fs
    tau = omega * (t_rel - release.rest_before_s)
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
    return _Motion(t_rel, y, yp, s0, fade_s, motion_s)


def _law_motion(
    law: LawParameters, rig: Rig, release: Release, sample_rate_Hz: float
) -> tuple[_Motion, dict[str, Any]]:
    """The motion of any registered law (:func:`~bayestribo.synthetic.motion.integrate_law`)
    sampled on the record's grid, and its truth for the metadata."""
    from bayestribo.model.laws import PhysicalScale
    from bayestribo.synthetic.motion import SOLVER, LawForces, integrate_law

    if law.friction and not rig.has_contact:
        raise ValueError(
            f"law {law.name} has friction, which needs a load: load_N must be > 0, got "
            f"{rig.load_N!r}"
        )
    scaling = rig.scaling()
    ell, omega = scaling.length_scale, scaling.omega
    x0 = float(release.initial_displacement_m)
    y0 = x0 / ell
    forces = LawForces.of(law.law, law.values, y0)
    if forces.sticks(y0):
        raise ValueError(
            f"initial_displacement_m = {x0!r} m is inside the static-friction band "
            f"±{forces.ratio * forces.friction(y0) * ell!r} m: the pin would not move"
        )
    duration = release.motion_duration_s
    if duration is None and not law.friction:
        raise ValueError(
            f"the motion never stops (law {law.name} has no friction): give "
            "motion_duration_s, the time to record after the release"
        )
    fade_s = release.fade_s(rig)
    # integrated over the whole record: a motion that goes on fills the rest after it
    tau_limit = math.inf if duration is None else omega * (duration + release.rest_after_s)
    moved = integrate_law(law.law, law.values, y0, tau_fade=omega * fade_s, tau_limit=tau_limit)
    motion_s = moved.tau_stop / omega if duration is None else float(duration)
    fs = sample_rate_Hz
    n = math.floor((release.rest_before_s + motion_s + release.rest_after_s) * fs + 1e-9) + 1
    t_rel = np.arange(n, dtype=np.float64) / fs
    y, yp = moved.sample(omega * (t_rel - release.rest_before_s))

    k = float(rig.mass_kg) * omega**2  # type: ignore[arg-type]
    scale = PhysicalScale(ell, omega, "m", k, float(rig.mass_kg), rig.load_N or None)  # type: ignore[arg-type]
    as_arrays = {name: np.array([value]) for name, value in law.values.items()}
    physical = law.law.physical(as_arrays, y0, scale)
    truth = {
        "law": law.name,
        "solver": SOLVER,
        "parameters": {
            p.name: {"value": law.values[p.name], "unit": p.unit, "symbol": p.symbol}
            for p in law.law.parameters
        },
        "length_scale_m": ell,
        "reference_amplitude_m": x0,
        "physical": {
            name: {"value": float(np.ravel(v)[0]), "unit": unit, "symbol": symbol, "label": label}
            for name, (v, unit, symbol, label) in physical.items()
        },
        "stopped": moved.stopped,
        "half_cycles": moved.half_cycles,
    }
    mu_s0 = forces.ratio * forces.friction(y0) if law.friction else 0.0
    return _Motion(t_rel, y, yp, mu_s0, fade_s, motion_s), truth


def _record(
    motion: _Motion, rig: Rig, release: Release, sensor: Sensor, rng: np.random.Generator
) -> tuple[NDArray, NDArray]:
    """What the sensor records: signal units, offset, noise, quantisation, saturation."""
    scaling = rig.scaling()
    ell, omega = scaling.length_scale, scaling.omega
    sigma_x, sigma_v = sensor.noise
    n = motion.t_rel.size
    x = ell * motion.y + release.offset_m + sigma_x * rng.standard_normal(n)
    v = ell * omega * motion.yp + sigma_v * rng.standard_normal(n)
    if sensor.quantise:
        x = _quantise(x, sensor.displacement_resolution_m)
        v = _quantise(v, sensor.velocity_resolution_m_per_s)
    if sensor.displacement_range_m is not None:
        limit = float(sensor.displacement_range_m)
        x = np.clip(x, -limit, limit)
    if sensor.velocity_range_m_per_s is not None:
        limit = float(sensor.velocity_range_m_per_s)
        v = np.clip(v, -limit, limit)
    return x, v


def _law_truth(law: DissipationLaw, rig: Rig, motion: _Motion) -> dict[str, Any]:
    """The true ζ, μ_k and μ_s of a :class:`DissipationLaw` (None where they vary)."""
    zeta, mu_k, mu_s = law.zeta, law.mu_k, law.mu_s
    return {
        "zeta": None if callable(zeta) else float(zeta),
        "mu_k": None if callable(mu_k) else float(mu_k) if rig.has_contact else 0.0,  # type: ignore[arg-type]
        "mu_s": motion.mu_s0 if mu_s is not None or not callable(mu_k) else None,
        "amplitude_dependent": law.amplitude_dependent,
    }


def _metadata(
    law_truth: Mapping[str, Any],
    rig: Rig,
    release: Release,
    sensor: Sensor,
    motion: _Motion,
    seed: int | np.random.Generator | None,
) -> dict[str, Any]:
    """The run's metadata: the rig, the sensor, and the true law (``law_truth``) with
    the release and the noise."""
    sigma_x, sigma_v = sensor.noise
    truth: dict[str, Any] = {
        **law_truth,
        "initial_displacement_m": float(release.initial_displacement_m),
        "offset_m": float(release.offset_m),
        "release_time_s": float(release.time_origin_s + release.rest_before_s),
        "magnet_fade_s": motion.fade_s,
        "motion_duration_s": motion.motion_s,
        "displacement_noise_m": sigma_x,
        "velocity_noise_m_per_s": sigma_v,
        "quantised": bool(sensor.quantise),
        "seed": seed if isinstance(seed, int) else None,
    }
    meta: dict[str, Any] = {
        "load_N": float(rig.load_N),  # type: ignore[arg-type]
        "mass_kg": float(rig.mass_kg),  # type: ignore[arg-type]
        "natural_frequency_Hz": float(rig.natural_frequency_Hz),
        "displacement_resolution_m": float(sensor.displacement_resolution_m),
        "velocity_resolution_m_per_s": float(sensor.velocity_resolution_m_per_s),
        "sample_rate_Hz": float(sensor.sample_rate_Hz),
        # the simulated sensor's gain is exact (bayestribo.signal.sensor)
        "gain_uncertainty": 0.0,
    }
    if sensor.displacement_range_m is not None:
        meta["displacement_range_m"] = float(sensor.displacement_range_m)
    if sensor.velocity_range_m_per_s is not None:
        meta["velocity_range_m_per_s"] = float(sensor.velocity_range_m_per_s)
    meta["simulation"] = truth
    return meta


def simulate(
    law: DissipationLaw | LawParameters | None = None,
    *,
    rig: Rig = PAPER_RIG,
    release: Release | None = None,
    sensor: Sensor | None = None,
    seed: int | np.random.Generator | None = None,
    metadata: Mapping[str, Any] | None = None,
) -> Run:
    """Simulate one free-decay recording of the tribometer.

    Parameters
    ----------
    law : DissipationLaw or LawParameters, optional
        ζ, μ_k and μ_s (constants or amplitude laws, on the exact solution); default
        ζ = 0.0236 and, with contact, μ_k = μ_s = 0.0294. Or any registered law with
        its parameters (:class:`~bayestribo.synthetic.setup.LawParameters`), whose
        motion :func:`bayestribo.synthetic.motion.integrate_law` integrates.
    rig : Rig
        Natural frequency [Hz], mass [kg] and load [N] (0 without contact); default
        the paper's rig, :data:`~bayestribo.synthetic.setup.PAPER_RIG`.
    release : Release, optional
        Initial displacement, rests before and after, recorded duration, magnet fade,
        offset and time origin (default :class:`Release`).
    sensor : Sensor, optional
        Sample rate, noise, resolution, quantisation, ranges and channels (default
        :class:`Sensor`: the paper's vibrometer at 10 kHz, noise at its resolution).
    seed : int or numpy.random.Generator, optional
        Seed of the noise; the same seed gives the same run. Without one a seed is
        drawn from fresh entropy and recorded in ``metadata["simulation"]["seed"]``.
    metadata : mapping, optional
        Further metadata (e.g. ``lubricant``, ``repeat``, ``run_id``); it may override
        the keys written by the simulator.

    Returns
    -------
    Run
        Time stamps ``time_origin_s + i/sample_rate_Hz`` rounded to 1 ns, signals, and
        metadata: the rig, resolutions, ``sample_rate_Hz``, and a ``"simulation"``
        mapping with the true parameters (ζ, μ_k, μ_s as numbers when constant; for
        :class:`LawParameters` the law, the solver, each parameter's value with its
        unit and symbol, and the law's quantities in physical units), the release time
        and the noise levels.

    Raises
    ------
    ValueError
        Naming the field, for values out of range, friction without a load, motion
        that never stops without ``motion_duration_s``, or an initial displacement
        inside the static-friction band.

    Examples
    --------
    >>> from dataclasses import replace
    >>> run = simulate(DissipationLaw(zeta=0.02), rig=replace(PAPER_RIG, load_N=0.46), seed=1)
    >>> run.metadata["load_N"], run.velocity is not None
    (0.46, True)
    """
    rig, _, load_N = _checked_rig(rig)
    release = release or Release()
    sensor = sensor or Sensor()
    if isinstance(law, LawParameters):
        motion, law_truth = _law_motion(law, rig, release, float(sensor.sample_rate_Hz))
    else:
        law = _friction_law(law or DissipationLaw(), rig.has_contact, load_N)
        motion = _motion(law, rig, release, float(sensor.sample_rate_Hz))
        law_truth = _law_truth(law, rig, motion)
    if seed is None:
        # Fresh entropy, but recorded: the run's metadata give the seed that remakes it.
        seed = int(np.random.SeedSequence().generate_state(1)[0])
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    x, v = _record(motion, rig, release, sensor, rng)
    time = np.round(release.time_origin_s + motion.t_rel, 9)
    meta = _metadata(law_truth, rig, release, sensor, motion, seed)
    meta.update(metadata or {})
    return Run(
        time,
        x if "displacement" in sensor.channels else None,
        v if "velocity" in sensor.channels else None,
        meta,
    )
