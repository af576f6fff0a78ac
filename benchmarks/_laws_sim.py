"""Independent simulator of free decays under any dissipation law, for ``benchmarks/laws.py``.

Nothing here comes from :mod:`bayestribo.model` or :mod:`bayestribo.synthetic`: the
motion, in physical units,

    ẍ + Ω² x = -a_d(ẋ) - a_f(|ẋ|, |X_n|) sgn ẋ,

    a_d(v) = 2ζΩ v + q v|v| + b |v|^α sgn v                (drag, per unit mass)
    a_f    = μ(|ẋ|) N/m + η Ω² |X_n|                          (friction, per unit mass)
    μ(w)   = μ_k + (μ_s - μ_k) exp(-(w / v_s)^δ)  (Stribeck; μ_k when v_s = 0)

is integrated with :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-11) half cycle
by half cycle (each ends on the event ẋ = 0; within one the friction's sign is
constant), from x₀ at rest. X_n is the turning point the half cycle starts from. At
each turning point the contact sticks when the spring force is inside the static
friction, ``Ω²|X_n| <= s_ratio · a_f(0, |X_n|)`` (``s_ratio`` = μ_s/μ_k for the
Coulomb law, 1 for the Stribeck law whose a_f(0) is already μ_s N/m, and 1 without
static friction). A law without friction never stops: the record then ends after
``duration`` seconds.

:func:`simulate` samples that motion at any rate with rest before the release and
after the stop, and adds white noise on both channels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

__all__ = [
    "ELL",
    "F_HZ",
    "LOAD",
    "MASS",
    "OMEGA",
    "RESOLUTION_V",
    "RESOLUTION_X",
    "STIFFNESS",
    "Truth",
    "half_cycle_end",
    "harmonic_power_integral",
    "metadata",
    "motion",
    "simulate",
    "true_dissipation",
    "true_harmonic_dissipation",
]

MASS, F_HZ, LOAD = 0.035, 32.6, 0.31
OMEGA = 2.0 * math.pi * F_HZ
STIFFNESS = MASS * OMEGA**2
#: ℓ = N/k: one dimensionless unit of length [m].
ELL = LOAD / STIFFNESS
RESOLUTION_X, RESOLUTION_V = 0.15e-6, 0.015e-6  # the vibrometer's resolution [m, m/s]


def harmonic_power_integral(p: float) -> float:
    """∫₀^{2π} |sin τ|^p dτ (by quadrature, independent of the package's closed form)."""
    from scipy.integrate import quad

    return 4.0 * quad(lambda t: math.sin(t) ** p, 0.0, 0.5 * math.pi, limit=200)[0]


@dataclass(frozen=True)
class Truth:
    """One law in physical units (every coefficient 0 means that term is absent).

    Attributes
    ----------
    zeta : float
        Viscous damping ratio (a = 2ζΩ v).
    q : float
        Quadratic drag per unit mass [1/m] (a = q v|v|).
    b, alpha : float
        Power drag per unit mass [m^(1-α) s^(α-2)] and its exponent (a = b |v|^α sgn v).
    mu_k : float
        Kinetic friction coefficient (a = μ_k N/m).
    static_ratio : float
        μ_s/μ_k: static friction at a turning point (Coulomb, Coulomb with η).
    eta : float
        Friction per unit amplitude, dimensionless (a = η Ω² |X_n|).
    mu_s_stribeck, v_s : float
        Stribeck friction: static μ_s and the velocity scale v_s [m/s] (v_s = 0: none).
    stribeck_exponent : float
        Stribeck exponent δ: μ falls as exp(-(w/v_s)^δ) (1 by default).
    """

    zeta: float = 0.0
    q: float = 0.0
    b: float = 0.0
    alpha: float = 1.5
    mu_k: float = 0.0
    static_ratio: float = 1.0
    eta: float = 0.0
    mu_s_stribeck: float = 0.0
    v_s: float = 0.0
    stribeck_exponent: float = 1.0

    @property
    def stribeck(self) -> bool:
        return self.v_s > 0.0

    def drag(self, v: float) -> float:
        """Drag acceleration a_d(v) [m/s²], odd in v."""
        out = 2.0 * self.zeta * OMEGA * v + self.q * v * abs(v)
        if self.b:
            out += self.b * abs(v) ** self.alpha * math.copysign(1.0, v)
        return out

    def mu(self, w: float) -> float:
        """Friction coefficient at speed w >= 0 (Stribeck, or μ_k)."""
        if self.stribeck:
            fall = math.exp(-((w / self.v_s) ** self.stribeck_exponent))
            return self.mu_k + (self.mu_s_stribeck - self.mu_k) * fall
        return self.mu_k

    def friction(self, w: float, turning: float) -> float:
        """Friction acceleration magnitude [m/s²] at speed w from turning point |X_n|."""
        return self.mu(w) * LOAD / MASS + self.eta * OMEGA**2 * abs(turning)

    def sticks(self, x: float) -> bool:
        """Does the contact stick at the turning point x?"""
        has_friction = self.mu_k > 0.0 or self.eta != 0.0 or self.stribeck
        if not has_friction:
            return False
        ratio = 1.0 if self.stribeck else self.static_ratio
        return OMEGA**2 * abs(x) <= ratio * self.friction(0.0, x)

    # -- the package's parametrisation --------------------------------------------
    def dimensionless(self, reference_m: float, omega: float = OMEGA) -> dict[str, float]:
        """The parameters of the package's terms in the dimensionless frame of the
        circular frequency ``omega`` (τ = ωt, ℓ = N/(mω²); the true frame by default),
        with the power law's ζ_α at the reference amplitude ``reference_m`` [m]."""
        ell = LOAD / (MASS * omega**2)
        out = {
            "zeta": self.zeta * OMEGA / omega,  # c/(2mω) with c = 2ζmΩ
            "mu_k": self.mu_k,
            "mu_s_ratio": self.static_ratio,
            "c2": self.q * ell,
            "eta": self.eta * OMEGA**2 / omega**2,
            "alpha": self.alpha,
        }
        # a = b |v|^α = ℓω² c |y'|^α with v = ℓω y': c = b (ℓω)^α / (ℓω²)
        c = self.b * (ell * omega) ** self.alpha / (ell * omega**2)
        k = harmonic_power_integral(self.alpha + 1.0)
        ref = reference_m / ell
        out["zeta_alpha"] = c * k * ref ** (self.alpha - 1.0) / (2.0 * math.pi)
        return out


def true_harmonic_dissipation(truth: Truth, amplitude_m: np.ndarray) -> np.ndarray:
    """ΔE_h(A) [J] of one cycle of x = A cos Ωt under the true law, by quadrature of
    ∮ m (a_d(ẋ) + a_f sgn ẋ) ẋ dt (a_f at the turning amplitude A)."""
    from scipy.integrate import quad

    out = []
    for a in np.atleast_1d(np.asarray(amplitude_m, dtype=float)):

        def power(theta: float, a: float = a) -> float:
            w = a * OMEGA * math.sin(theta)  # speed over a half cycle, θ in (0, π)
            return MASS * (truth.drag(w) + truth.friction(w, a)) * w

        # energy over a half cycle: ∫ F v dt = ∫ F v dθ/Ω; a cycle is twice that
        half, _ = quad(power, 0.0, math.pi, limit=200, epsabs=0.0, epsrel=1e-11)
        out.append(2.0 * half / OMEGA)
    return np.array(out)


def half_cycle_end(truth: Truth, a: float) -> float:
    """|x| [m] at the turning point that ends the half cycle from rest at x = a > 0
    (the kinetic law: no sticking)."""
    turning = abs(a)

    def rhs(_t: float, u: np.ndarray) -> list[float]:
        w = max(-u[1], 0.0)
        return [u[1], -(OMEGA**2) * u[0] - truth.drag(u[1]) + truth.friction(w, turning)]

    def turned(_t: float, u: np.ndarray) -> float:
        return u[1]

    turned.terminal, turned.direction = True, 1.0
    sol = solve_ivp(
        rhs,
        (0.0, 2.0 * math.pi / OMEGA),
        [a, 0.0],
        method="DOP853",
        events=turned,
        rtol=1e-12,
        atol=1e-16 * a,
    )
    if sol.t_events[0].size == 0:
        raise RuntimeError(f"no turning point within a period from a = {a:g} m")
    return -float(sol.y_events[0][0][0])


def true_dissipation(truth: Truth, amplitude_m: np.ndarray) -> np.ndarray:
    """ΔE(A) [J] at each swing A as the package defines it: k(a_s² - a_e²) over the
    half cycle of the true motion from rest at a_s to the turning point a_e with
    (a_s + a_e)/2 = A (solve_ivp through the half cycle, a_s by Brent's method)."""
    from scipy.optimize import brentq

    out = []
    for amp in np.atleast_1d(np.asarray(amplitude_m, dtype=float)):
        a_s = brentq(
            lambda a, amp=amp: 0.5 * (a + half_cycle_end(truth, a)) - amp,
            amp,
            2.0 * amp,
            xtol=1e-15 * amp,
        )
        out.append(STIFFNESS * (a_s**2 - half_cycle_end(truth, a_s) ** 2))
    return np.array(out)


def motion(truth: Truth, x0: float, duration: float) -> tuple[list, float, float | None]:
    """Half cycles from x₀ at rest: (dense solutions as (t0, t1, sol), the last time,
    the rest position or None when the motion did not stop within ``duration``)."""
    arcs: list = []
    t, x = 0.0, x0
    period = 2.0 * math.pi / OMEGA
    while t < duration:
        if truth.sticks(x):
            return arcs, t, x
        s = -math.copysign(1.0, x)  # direction of the coming half cycle
        turning = abs(x)

        def rhs(_t: float, u: np.ndarray, s: float = s, turning: float = turning) -> list[float]:
            w = max(s * u[1], 0.0)
            return [u[1], -(OMEGA**2) * u[0] - truth.drag(u[1]) - s * truth.friction(w, turning)]

        def turned(_t: float, u: np.ndarray) -> float:
            return u[1]

        turned.terminal, turned.direction = True, -s
        sol = solve_ivp(
            rhs,
            (t, t + period),
            [x, 0.0],
            method="DOP853",
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-15,
        )
        if sol.t_events[0].size == 0:
            if truth.mu_k > 0.0 or truth.eta != 0.0 or truth.stribeck:
                raise RuntimeError(f"no turning point within a period from t = {t:g} s")
            # a drag alone that outgrows the spring (a power law below α = 1): the
            # motion ends by an overdamped creep towards the centre, recorded to the
            # end of the record
            creep = solve_ivp(
                rhs,
                (t, duration),
                [sol.y[0, 0], 0.0],
                method="LSODA",
                dense_output=True,
                rtol=1e-11,
                atol=1e-15,
            )
            arcs.append((t, duration, creep.sol))
            return arcs, duration, None
        t1, x = float(sol.t_events[0][0]), float(sol.y_events[0][0][0])
        arcs.append((t, t1, sol.sol))
        t = t1
    return arcs, t, None


def simulate(
    truth: Truth,
    *,
    x0: float,
    fs: float = 5000.0,
    rest_before: float = 0.1,
    rest_after: float = 0.2,
    duration: float = 4.0,
    noise: float = 10.0,
    seed: object = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """t [s], displacement [m], velocity [m/s] with white noise of ``noise`` x the
    vibrometer's resolution on both channels, and facts about the motion."""
    arcs, end, rest = motion(truth, x0, duration)
    stop = end if rest is not None else None
    total = rest_before + (end + rest_after if stop is not None else duration)
    t = np.arange(round(total * fs) + 1) / fs
    tm = t - rest_before
    x, v = np.full(t.size, x0), np.zeros(t.size)
    for a, b, sol in arcs:
        m = (tm >= a) & (tm < b)
        if m.any():
            x[m], v[m] = sol(tm[m])
    if stop is not None:
        x[tm >= stop] = rest
        v[tm >= stop] = 0.0
    rng = np.random.default_rng(seed)
    xs = x + noise * RESOLUTION_X * rng.standard_normal(t.size)
    vs = v + noise * RESOLUTION_V * rng.standard_normal(t.size)
    turns = [x0] + [float(sol(b)[0]) for _a, b, sol in arcs]
    facts = {
        "stopped_at_s": stop,
        "rest_position_m": rest,
        "half_cycles": len(arcs),
        "last_turning_point_m": turns[-1],
        "duration_s": float(t[-1]),
    }
    return t, xs, vs, facts


def metadata() -> dict[str, float]:
    """The run's metadata: the rig and the vibrometer's resolution (not the noise)."""
    return {
        "natural_frequency_Hz": F_HZ,
        "mass_kg": MASS,
        "load_N": LOAD,
        "displacement_resolution_m": RESOLUTION_X,
        "velocity_resolution_m_per_s": RESOLUTION_V,
        # the simulated sensor's gain is exact: the default 1 % of a sensor of unstated
        # kind would dominate the friction's interval and hide the likelihood's calibration
        "gain_uncertainty": 0.0,
    }
