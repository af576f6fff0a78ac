"""Recordings of laws the package's simulator does not make, from an independent ODE.

The equation of motion in physical units, ``ẍ + Ω²x = -a_d(ẋ) - a_f sgn ẋ`` (a drag
acceleration ``a_d`` and a Coulomb friction acceleration ``a_f = μ_k N/m``), is
integrated with :func:`scipy.integrate.solve_ivp` half cycle by half cycle (each ends
on the event ẋ = 0), with the stick rule ``|k x| <= μ_s N`` at each turning point.
Nothing is shared with :mod:`bayestribo.model` or :mod:`bayestribo.synthetic`: this
is how a user would simulate a rig with drag to check the package.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

from bayestribo.io.run import Run

__all__ = ["law_recording", "swing_dissipation"]


def law_recording(
    drag: Callable[[float], float],
    *,
    friction: float = 0.0,
    friction_slope: float = 0.0,
    friction_change: tuple[float, float] | None = None,
    static_ratio: float = 1.5,
    x0: float = 1.0e-3,
    frequency_Hz: float = 32.6,
    mass_kg: float = 0.035,
    load_N: float | None = 0.31,
    sample_rate_Hz: float = 5000.0,
    noise_x: float = 1.5e-6,
    noise_v: float = 1.5e-7,
    rest_before_s: float = 0.1,
    duration_s: float = 3.0,
    seed: int = 0,
) -> Run:
    """A free-decay recording of a drag law (and Coulomb friction), with noise.

    Parameters
    ----------
    drag : callable
        Drag acceleration a_d(v) [m/s²] at velocity v [m/s], odd in v.
    friction : float
        Coulomb friction acceleration μ_k N/m [m/s²].
    friction_slope : float
        Its change per metre of the turning point |X_n| each half cycle starts from
        [1/s²]: the friction acceleration of that half cycle is
        ``friction + friction_slope |X_n|`` (a friction that varies with amplitude).
    friction_change : (float, float), optional
        ``(t, a)``: from the first half cycle that starts at or after the time t [s]
        after the release, the friction acceleration is a [m/s²] instead of
        ``friction`` (a contact that changes during the run: a film that thins).
    static_ratio : float
        μ_s/μ_k.
    x0 : float
        Release displacement [m].
    frequency_Hz, mass_kg, load_N : float
        The rig (``load_N`` goes into the metadata; ``friction`` is what acts).
    sample_rate_Hz, noise_x, noise_v : float
        Sampling and white noise of the displacement [m] and velocity [m/s].
    rest_before_s, duration_s : float
        Rest before the release and the length of the record after it [s].
    seed : int
        Seed of the noise.
    """
    omega = 2.0 * math.pi * frequency_Hz
    t_samples = np.arange(0.0, rest_before_s + duration_s, 1.0 / sample_rate_Hz)
    x = np.full(t_samples.shape, x0)
    v = np.zeros(t_samples.shape)
    t, state = 0.0, np.array([x0, 0.0])
    segments = []
    rest = None
    while t < duration_s:
        base = friction
        if friction_change is not None and t >= friction_change[0]:
            base = friction_change[1]
        here = base + friction_slope * abs(state[0])
        if state[1] == 0.0:
            if omega**2 * abs(state[0]) <= static_ratio * here:
                rest = (t, state[0])
                break
            direction = -math.copysign(1.0, state[0])
        else:
            direction = math.copysign(1.0, state[1])

        def rhs(_t: float, s: np.ndarray, d: float = direction, f: float = here) -> list[float]:
            return [s[1], -(omega**2) * s[0] - drag(s[1]) - f * d]

        def turning(_t: float, s: np.ndarray) -> float:
            return s[1]

        turning.terminal = True
        turning.direction = -direction
        sol = solve_ivp(
            rhs,
            (t, min(t + 2.0 * math.pi / omega, duration_s)),
            state,
            method="DOP853",
            rtol=1e-11,
            atol=1e-14,
            events=turning,
            dense_output=True,
        )
        segments.append(sol)
        if sol.t_events[0].size == 0:
            break
        t = float(sol.t_events[0][0])
        state = np.array([sol.y_events[0][0][0], 0.0])
    after = t_samples - rest_before_s
    for sol in segments:
        inside = (after >= sol.t[0]) & (after <= sol.t[-1])
        x[inside], v[inside] = sol.sol(after[inside])
    if rest is not None:
        stuck = after > rest[0]
        x[stuck], v[stuck] = rest[1], 0.0
    rng = np.random.default_rng(seed)
    metadata = {
        "natural_frequency_Hz": frequency_Hz,
        "mass_kg": mass_kg,
        "displacement_resolution_m": noise_x,
        "velocity_resolution_m_per_s": noise_v,
    }
    if load_N is not None:
        metadata["load_N"] = load_N
    return Run(
        t_samples,
        displacement=x + rng.normal(0.0, noise_x, x.shape),
        velocity=v + rng.normal(0.0, noise_v, v.shape),
        metadata=metadata,
    )


def swing_dissipation(
    drag: Callable[[float], float],
    amplitudes: np.ndarray,
    *,
    friction: float = 0.0,
    friction_slope: float = 0.0,
    frequency_Hz: float = 32.6,
    mass_kg: float = 0.035,
) -> np.ndarray:
    """Energy dissipated per cycle at each swing A [J]: ``k (a_s² - a_e²)``, twice the
    energy lost over the half cycle from rest at a_s to the turning point a_e with
    ``(a_s + a_e)/2 = A`` (solve_ivp through the half cycle, a_s by Brent's method)."""
    from scipy.optimize import brentq

    omega = 2.0 * math.pi * frequency_Hz

    def end(a: float) -> float:
        f = friction + friction_slope * a

        def rhs(_t: float, s: np.ndarray) -> list[float]:
            # moving towards -x the whole half cycle: a force discontinuous at v = 0
            # (friction) keeps its sign up to the turning point, where the event is
            return [s[1], -(omega**2) * s[0] - drag(min(s[1], -1e-300)) + f]

        def turning(_t: float, s: np.ndarray) -> float:
            return s[1]

        turning.terminal, turning.direction = True, 1.0
        sol = solve_ivp(
            rhs,
            (0.0, 2.0 * math.pi / omega),
            [a, 0.0],
            method="DOP853",
            rtol=1e-12,
            atol=1e-16 * a,
            events=turning,
        )
        if sol.y_events[0].size == 0:
            return math.nan  # the friction holds the pin at a: no half cycle starts
        return -float(sol.y_events[0][0][0])

    out = []
    for amp in np.atleast_1d(np.asarray(amplitudes, dtype=float)):
        low = amp
        while not math.isfinite(end(low)):  # the smallest start that moves
            low *= 1.001
        a_s = brentq(lambda a, amp=amp: 0.5 * (a + end(a)) - amp, low, 2.0 * amp, xtol=1e-15 * amp)
        out.append(mass_kg * omega**2 * (a_s**2 - end(a_s) ** 2))
    return np.array(out)
