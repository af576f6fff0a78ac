r"""The law-free answer of a fit: energy dissipated per cycle, ΔE(A), with its band.

Whatever the law, a fit answers "how much energy does the contact dissipate at each
amplitude". Over one cycle of the harmonic motion ``x = A cos Ωt`` a law dissipates

.. math::

    ΔE_h(A) = \oint F(\dot x)\,\dot x\,dt,

``π c Ω A²`` for viscous damping, ``4 μ_k N A`` for Coulomb friction,
``(8/3) c₂ Ω² A³`` for quadratic drag, ... (each term's
:meth:`~bayestribo.model.laws.Term.dissipation`). That integral is a first-order
quantity: laws that describe the same decay can differ in it by a relative O(ζ)
(viscous damping and a friction proportional to the amplitude, with the same decay:
1.5 % at ζ = 0.01, about 450 posterior standard deviations at ten times the
vibrometer's resolution in ``benchmarks/laws.py``). The reported ΔE(A) is therefore
the energy the law's own motion dissipates per cycle at the swing A
(:meth:`~bayestribo.model.laws.Law.swing_dissipation`): twice the energy lost over the
half cycle whose turning points ``a_s``, ``a_e`` have ``(a_s + a_e)/2 = A``,
``2A(a_s - a_e)``. It depends on the half-cycle map alone, which the decay measures,
so laws that describe the same decay give the same ΔE(A); it equals ``ΔE_h`` to first
order (exactly for Coulomb friction). ``ΔE_h`` is reported beside it
(``harmonic_mean``) and splits ΔE(A) between the law's terms (``by_term``).

ΔE(A) is given in joules where the stiffness is known (``k = mΩ²``: the run's mass and
frequency), otherwise as ΔE/k in the signal's unit squared, at swings spanning the
analysed motion (its largest and smallest half cycle included).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import scipy.special
from numpy.typing import NDArray

from bayestribo.inference.posterior import Posterior
from bayestribo.model.laws import PhysicalScale
from bayestribo.model.scaling import Scaling
from bayestribo.summary import check_prob

__all__ = [
    "DISSIPATION_AMPLITUDES",
    "FEWEST_HALF_CYCLES",
    "averaged_dissipation",
    "dissipation_amplitudes",
    "dissipation_band",
    "law_quantities",
    "physical_scale",
    "shape_agreement",
    "turning_point_dissipation",
]

#: Number of amplitudes at which ΔE(A) is reported.
DISSIPATION_AMPLITUDES = 12
#: At most this many posterior draws enter the band (the rest add Monte Carlo
#: precision far below the band's width); fewer for a law without a closed form, whose
#: ΔE(A) is integrated half cycle by half cycle (0.4 ms per draw for 12 swings).
_BAND_DRAWS = 4000
_BAND_DRAWS_INTEGRATED = 1000


def physical_scale(scaling: Scaling, metadata: Mapping[str, Any]) -> PhysicalScale:
    """What one dimensionless unit of length, time and energy is for a run.

    Parameters
    ----------
    scaling : Scaling
        The run's dimensionless scaling (ℓ and Ω).
    metadata : mapping
        The run's metadata: ``mass_kg`` (for k = mΩ² and energies in joules),
        ``load_N``, ``length_unit``; for a rotation (``length_unit`` ``"rad"``)
        ``inertia_kg_m2``, for the torsional stiffness κ = IΩ² [N m/rad] and energies
        in joules.

    Returns
    -------
    PhysicalScale
    """
    mass = metadata.get("mass_kg")
    mass = float(mass) if mass is not None and float(mass) > 0 else None
    load = metadata.get("load_N")
    load = float(load) if load is not None and float(load) > 0 else None
    unit = str(metadata.get("length_unit", "m") or "m")
    if unit == "arbitrary":
        unit = "signal unit"
    stiffness = mass * scaling.omega**2 if mass is not None and unit == "m" else None
    inertia = metadata.get("inertia_kg_m2")
    if unit == "rad" and inertia is not None and float(inertia) > 0:
        # a rotation: κ = IΩ² [N m/rad], energies in joules; no load, no mass
        stiffness, mass, load = float(inertia) * scaling.omega**2, None, None
    return PhysicalScale(
        length_scale=float(scaling.length_scale),
        omega=float(scaling.omega),
        length_unit=unit,
        stiffness=stiffness,
        mass=mass if unit == "m" else None,
        load=load,
    )


def dissipation_amplitudes(turning_points: NDArray, n: int = DISSIPATION_AMPLITUDES) -> NDArray:
    """Swings spanning the analysed motion: from its smallest half cycle to its largest.

    Parameters
    ----------
    turning_points : ndarray
        Turning points of the analysed window, in order, about the equilibrium (any
        unit; signs ignored).
    n : int
        Number of swings, log-spaced, both ends included.

    Returns
    -------
    ndarray
        Swings ``(|Y_n| + |Y_n+1|)/2`` in the unit of ``turning_points`` (the turning
        point itself with only one).
    """
    y = np.abs(np.asarray(turning_points, dtype=float))
    y = y[np.isfinite(y) & (y > 0)]
    if y.size == 0:
        raise ValueError("turning_points: no finite non-zero turning point")
    a = 0.5 * (y[1:] + y[:-1]) if y.size > 1 else y
    low, high = float(a.min()), float(a.max())
    if high <= low * (1 + 1e-12):
        return np.array([high])
    return np.geomspace(low, high, n)


def _gain_error(mean: NDArray, amplitudes: NDArray, gain_sd: float) -> NDArray:
    """Relative error of ΔE at fixed physical swings from a gain error of sd ``gain_sd``.

    With a gain g the recorded swing is gA and the energies g²: at a fixed reported
    swing, ln ΔE moves by (s - 2) ln g, s = d ln ΔE / d ln A the local log-log slope of
    the band (0 error for quadratic ΔE(A), viscous damping; σ_g for Coulomb, s = 1).
    """
    if gain_sd == 0.0 or mean.size == 0:
        return np.zeros_like(mean)
    if mean.size < 2 or not np.all(mean > 0):
        return np.full_like(mean, 2.0 * gain_sd)  # no slope to read: the energy's own
    slope = np.gradient(np.log(mean), np.log(np.asarray(amplitudes, dtype=float)))
    return np.abs(slope - 2.0) * gain_sd


def _band(
    total: NDArray,
    prob: float,
    frequency_sd: float,
    amplitudes: NDArray | None = None,
    gain_sd: float = 0.0,
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Mean, sd and equal-tailed interval of ΔE draws (n, n_A), with the frequency
    nuisance: the energies scale with k = mΩ², a relative error of twice it, added in
    quadrature to the sd and to each side of the interval."""
    tail = 0.5 * (1.0 - prob)
    lower, upper = np.quantile(total, [tail, 1.0 - tail], axis=0)
    mean = np.mean(total, axis=0)
    sd = np.std(total, axis=0, ddof=1) if total.shape[0] > 1 else np.zeros(total.shape[1])
    relative = 2.0 * float(frequency_sd) * np.ones_like(mean)
    if gain_sd > 0 and amplitudes is not None:
        relative = np.hypot(relative, _gain_error(mean, amplitudes, gain_sd))
    if np.any(relative > 0):
        extra = relative * np.abs(mean)
        z = float(scipy.special.ndtri(1.0 - tail))  # the normal quantile (norm.ppf)
        lower = mean - np.hypot(mean - lower, z * extra)
        upper = mean + np.hypot(upper - mean, z * extra)
        sd = np.hypot(sd, extra)
    return mean, sd, lower, upper


def dissipation_band(
    posterior: Posterior,
    draws: NDArray,
    amplitudes: NDArray,
    scale: PhysicalScale,
    *,
    prob: float = 0.95,
    frequency_sd: float = 0.0,
    gain_sd: float = 0.0,
) -> dict[str, Any]:
    """ΔE(A) over posterior draws: mean and equal-tailed interval at each swing
    (:meth:`~bayestribo.model.laws.Law.swing_dissipation`, see the module notes).

    Parameters
    ----------
    posterior : Posterior
        The fitted posterior (its law and reference amplitude).
    draws : ndarray
        Flat draws of the sampled coordinates, shape (n, d).
    amplitudes : ndarray
        Amplitudes A [dimensionless, units of ℓ].
    scale : PhysicalScale
        Converts amplitudes and energies to physical units.
    prob : float
        Probability of the intervals.
    frequency_sd : float
        Relative standard deviation of the frequency nuisance
        (:func:`bayestribo.inference.pipeline.frequency_nuisance_sd`): the energies
        scale with k = mΩ², so ΔE(A) gets a relative error of twice it, added in
        quadrature to the band's sd and to each side of its interval.
    gain_sd : float
        Relative standard uncertainty of the sensor's gain
        (:mod:`bayestribo.signal.sensor`): at a fixed swing ΔE moves by (s - 2) times
        it, s the band's log-log slope; added in quadrature as ``frequency_sd`` is.

    Returns
    -------
    dict
        ``law``; ``amplitude`` [``amplitude_unit``], the swings; ``mean``,
        ``interval`` (lower, upper lists), ``sd`` [``unit``]; ``prob``;
        ``harmonic_mean``: the integral over the harmonic motion, ΔE_h(A);
        ``by_term``: each term's mean share of ΔE(A), in proportion to its share of
        ΔE_h; ``unit`` ("J" or the length unit squared, energy over stiffness);
        ``definition``.
    """
    prob = check_prob(prob)
    draws = np.atleast_2d(np.asarray(draws, dtype=float))
    most = _BAND_DRAWS if posterior.law.closed_form else _BAND_DRAWS_INTEGRATED
    if draws.shape[0] > most:
        # evenly spaced over every chain (no random numbers: the fit's stream is kept)
        draws = draws[np.linspace(0, draws.shape[0] - 1, most).astype(int)]
    values = posterior.law_draws(draws)
    ref = posterior.likelihood.reference_amplitude
    amps = np.asarray(amplitudes, dtype=float)
    parts = posterior.law.dissipation(amps, values, ref, by_term=True)
    harmonic = sum(parts.values())
    factor = scale.energy_factor
    exact = _swing_dissipation(posterior.law, amps, values, ref)
    parts = {k: np.broadcast_to(v, exact.shape) for k, v in parts.items()}
    harmonic = np.broadcast_to(harmonic, exact.shape)
    # a draw has no half cycle of a given swing when its friction would hold a motion
    # that small or its drag stop it: such draws are left out, and counted
    keep = np.all(np.isfinite(exact), axis=1)
    definition = "per cycle of the law's own motion at the swing A: 2A(a_s - a_e)"
    if posterior.law.restoring is not None:
        definition = (
            "per cycle of the law's own motion at the swing A on the "
            f"{posterior.law.restoring.name}'s restoring force: 2(V(a_s) - V(a_e))"
        )
    if not keep.any():
        exact, keep = harmonic, np.ones(keep.shape, bool)
        definition = "over one cycle of the harmonic motion (no draw has these swings)"
    exact, harmonic = exact[keep], harmonic[keep]
    parts = {k: v[keep] for k, v in parts.items()}
    total = exact * factor
    mean, sd, lower, upper = _band(total, prob, frequency_sd, amps * scale.length_scale, gain_sd)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = {k: np.where(harmonic != 0, v / harmonic, 0.0) for k, v in parts.items()}
    return {
        "law": posterior.law.name,
        "amplitude": (amps * scale.length_scale).tolist(),
        "amplitude_unit": scale.length_unit,
        "mean": mean.tolist(),
        "sd": sd.tolist(),
        "interval": [lower.tolist(), upper.tolist()],
        "prob": prob,
        "unit": scale.energy_unit,
        "harmonic_mean": (np.mean(harmonic, axis=0) * factor).tolist(),
        "by_term": {name: np.mean(share[name] * total, axis=0).tolist() for name in parts},
        "definition": definition,
        "draws_left_out": int(keep.size - keep.sum()),
        "frequency_nuisance_sd": float(frequency_sd),
        "gain_sd": float(gain_sd),
    }


#: Draws at which an interpolated ΔE(A) is checked against the integrator, and the
#: largest error allowed there, as a fraction of the band's standard deviation.
_SWING_CHECK_DRAWS = 32
_SWING_TOLERANCE = 1e-2


def _swing_dissipation(
    law: Any, amplitudes: NDArray, values: Mapping[str, NDArray], reference: float
) -> NDArray:
    """:meth:`~bayestribo.model.laws.Law.swing_dissipation` of every draw, interpolated
    for a law without a closed form.

    The integrator costs some 0.5 ms a draw; ΔE at each swing is a smooth function of
    the law's parameters over the posterior's spread, so it is interpolated by a
    quadratic in them through 1 + 2p + p(p-1)/2 integrated draws about the draws' mean
    (nodes two sd out along each parameter, and one per pair), as Π is for sampling
    (:mod:`bayestribo.inference.surrogate`). The interpolation is checked at
    :data:`_SWING_CHECK_DRAWS` draws evenly spaced and the :data:`_SWING_EXTREME_DRAWS`
    farthest from the draws' mean against the integrator, swing by swing: at a
    swing where it is off by more than :data:`_SWING_TOLERANCE` of the band's sd (or a
    value is not finite), every draw is integrated at that swing (the swings are
    independent half cycles), and kept at the others.
    """
    if law.closed_form:
        return law.swing_dissipation(amplitudes, values, reference)
    vals = {n: np.atleast_1d(np.asarray(values[n], dtype=float)) for n in law.parameter_names}
    size = max(v.size for v in vals.values())
    vals = {n: np.broadcast_to(v, (size,)) for n, v in vals.items()}
    names = [n for n in law.parameter_names if n != "mu_s_ratio" and np.std(vals[n]) > 0]
    p = len(names)
    if p == 0 or size <= 1 + 2 * p + p * (p - 1) // 2 + _SWING_CHECK_DRAWS + _SWING_EXTREME_DRAWS:
        return law.swing_dissipation(amplitudes, vals, reference)
    centre = np.array([np.mean(vals[n]) for n in names])
    scale = 2.0 * np.array([np.std(vals[n]) for n in names])
    sides = np.zeros(p)
    for a, name in enumerate(names):
        parameter = law.parameter(name)
        below = centre[a] - 2.0 * scale[a] >= parameter.low
        above = centre[a] + 2.0 * scale[a] <= parameter.high
        sides[a] = 0.0 if (below and above) else (1.0 if above else -1.0)
    rows = [np.zeros(p)]
    for a in range(p):
        for u in (-1.0, 1.0) if sides[a] == 0 else (sides[a], 2.0 * sides[a]):
            row = np.zeros(p)
            row[a] = u
            rows.append(row)
    first = np.where(sides == 0, 1.0, sides)
    for a in range(p):
        for b in range(a + 1, p):
            row = np.zeros(p)
            row[a], row[b] = first[a], first[b]
            rows.append(row)
    nodes = np.array(rows)

    def monomials(u: NDArray) -> NDArray:
        cols = [np.ones(u.shape[0]), *(u[:, a] for a in range(p))]
        cols += [u[:, a] * u[:, b] for a in range(p) for b in range(a, p)]
        return np.column_stack(cols)

    def at(u: NDArray) -> dict[str, NDArray]:
        out = {n: np.full(u.shape[0], float(np.mean(vals[n]))) for n in law.parameter_names}
        for a, name in enumerate(names):
            out[name] = centre[a] + u[:, a] * scale[a]
        return out

    known = law.swing_dissipation(amplitudes, at(nodes), reference)
    if not np.all(np.isfinite(known)):
        return law.swing_dissipation(amplitudes, vals, reference)
    table = np.linalg.solve(monomials(nodes), known)
    u = np.column_stack([(vals[n] - c) / s for n, c, s in zip(names, centre, scale, strict=True)])
    fitted = monomials(u) @ table
    # evenly spaced draws, and the draws farthest out, where a polynomial that holds
    # in the bulk misses first (a cubic of log ΔE that passed 32 evenly spaced draws
    # was off by 0.27 of the band's sd at a tail draw: benchmarks/band_log_amount.py)
    evenly = np.linspace(0, size - 1, _SWING_CHECK_DRAWS).astype(int)
    far = np.argsort(np.linalg.norm(u, axis=1))[::-1]
    picked = np.union1d(evenly, far[~np.isin(far, evenly)][:_SWING_EXTREME_DRAWS])
    checked = law.swing_dissipation(amplitudes, {n: vals[n][picked] for n in vals}, reference)
    held = _interpolation_held(fitted, checked, picked)
    if not np.all(held):
        # where the quadratic through the nodes missed (a posterior curved or
        # correlated across the nodes' axes: the AppStat HarmOsc1 record under
        # coulomb+power, α 2.56 ± 0.31 against its bound 3 and traded with ζ_α, missed
        # by 0.8-1.8 of the band's sd at 10 of 12 swings, every draw then integrated
        # there: 0.26 s of a 1.9 s fit), a cubic fitted by least squares at draws (1e-3
        # of the sd there), checked as the first at the same draws
        missed = np.flatnonzero(~held)
        refit, now = _refit_at_draws(
            law,
            np.asarray(amplitudes, dtype=float)[missed],
            vals,
            reference,
            _cubic_monomials(u),
            checked[:, missed],
            picked,
            _log_amount_basis(law, names, vals),
        )
        fitted[:, missed[now]] = refit[:, now]
        held[missed[now]] = True
    if not np.any(held):
        return law.swing_dissipation(amplitudes, vals, reference)
    if not np.all(held):
        # the swings where the interpolation missed are integrated at every draw
        fitted[:, ~held] = law.swing_dissipation(
            np.asarray(amplitudes, dtype=float)[~held], vals, reference
        )
    fitted[picked] = checked
    return fitted


#: Draws farthest out at which a cubic of log ΔE in the amounts' logarithms is checked
#: besides the evenly spaced ones (:func:`_refit_at_draws`).
_SWING_EXTREME_DRAWS = 8
#: Draws at which ΔE is integrated to fit its cubic by least squares where the quadratic
#: through the nodes missed, per coefficient of the cubic.
_SWING_FIT_PER_COEFFICIENT = 3


def _cubic_monomials(u: NDArray) -> NDArray:
    """The monomials of rows ``u`` (n, p) up to degree 3: 1, u_a, u_a u_b (a <= b),
    u_a u_b u_c (a <= b <= c); shape (n, (p + 1)(p + 2)(p + 3)/6)."""
    p = u.shape[1]
    cols = [np.ones(u.shape[0]), *(u[:, a] for a in range(p))]
    cols += [u[:, a] * u[:, b] for a in range(p) for b in range(a, p)]
    cols += [
        u[:, a] * u[:, b] * u[:, c] for a in range(p) for b in range(a, p) for c in range(b, p)
    ]
    return np.column_stack(cols)


def _log_amount_basis(law: Any, names: list[str], vals: Mapping[str, NDArray]) -> NDArray | None:
    """The cubic monomials of the draws in coordinates where each term's amount
    (:attr:`~bayestribo.model.laws.base.Term.amount`: ζ, c₂, ζ_α, η, μ_k), positive at
    every draw, is taken as its logarithm, each coordinate centred and scaled by two
    sds; None where no amount is positive throughout.

    ΔE at a swing is close to proportional to a term's amount and to a power of the
    swing whose exponent is sampled: in these coordinates log ΔE is nearly linear, and
    a cubic follows it into a posterior's far tail where one on the plain coordinates
    does not (power-law drag on a seismometer's five increments, ζ_α to 5 sd above its
    mean; ``tests/test_inference_dissipation_log_amount.py``)."""
    amounts = {t.amount for t in law.terms if t.amount is not None}
    logged = [n in amounts and bool(np.all(vals[n] > 0.0)) for n in names]
    if not any(logged):
        return None
    x = np.column_stack(
        [
            np.log(vals[n]) if take else np.asarray(vals[n], dtype=float)
            for n, take in zip(names, logged, strict=True)
        ]
    )
    sd = x.std(axis=0)
    if not np.all(sd > 0.0):
        return None
    return _cubic_monomials((x - x.mean(axis=0)) / (2.0 * sd))


def _refit_at_draws(
    law: Any,
    amplitudes: NDArray,
    vals: Mapping[str, NDArray],
    reference: float,
    basis: NDArray,
    checked: NDArray,
    picked: NDArray,
    log_basis: NDArray | None = None,
) -> tuple[NDArray, NDArray]:
    """ΔE at every draw from a polynomial in the law's parameters fitted by least
    squares to the integrated ΔE at draws evenly spaced apart from those ``picked``
    for the check (:data:`_SWING_FIT_PER_COEFFICIENT` per coefficient); per swing the
    first that holds against ``checked`` (:func:`_interpolation_held`) of: ΔE on
    ``basis``, log ΔE on ``basis`` (a power of the swing whose exponent is sampled is
    linear in it there), and log ΔE on ``log_basis`` (the monomials with the terms'
    amounts as logarithms, :func:`_log_amount_basis`, where ΔE is nearly linear),
    which is also checked at the :data:`_SWING_EXTREME_DRAWS` draws farthest out in
    those coordinates (an exponential of a cubic that the evenly spaced draws pass can
    still run away in the tail).

    ``basis`` and ``log_basis``: the draws' monomials, (n, R). Returns the values (n,
    S) and the mask (S,)."""
    n, r = basis.shape
    count = min(_SWING_FIT_PER_COEFFICIENT * r, n)
    at = np.linspace(0, n - 1, count + 1)[:-1].astype(int) + (n // (2 * count) if count else 0)
    at = np.setdiff1d(np.minimum(at, n - 1), picked)  # the check's draws kept apart
    known = law.swing_dissipation(amplitudes, {k: v[at] for k, v in vals.items()}, reference)
    out = np.full((n, amplitudes.size), np.nan)
    held = np.zeros(amplitudes.size, dtype=bool)
    finite = np.all(np.isfinite(known), axis=0)
    if at.size < r or not np.any(finite):
        return out, held
    positive = finite & np.all(known > 0.0, axis=0)
    attempts = [(basis, False, finite), (basis, True, positive)]
    if log_basis is not None:
        attempts.append((log_basis, True, positive))
    for monomials, logged, allowed in attempts:
        todo = np.flatnonzero(allowed & ~held)
        if not todo.size:
            continue
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            target = np.log(known[:, todo]) if logged else known[:, todo]
            table = np.linalg.lstsq(monomials[at], target, rcond=None)[0]
            fitted = np.exp(monomials @ table) if logged else monomials @ table
        now = _interpolation_held(fitted, checked[:, todo], picked)
        if monomials is log_basis and np.any(now):
            # the draws farthest out (the linear monomials' norm) checked too
            p = _linear_count(r)
            far = np.argsort(np.linalg.norm(monomials[:, 1 : 1 + p], axis=1))[::-1]
            far = far[~np.isin(far, picked)][:_SWING_EXTREME_DRAWS]
            ends = law.swing_dissipation(
                amplitudes[todo[now]], {k: v[far] for k, v in vals.items()}, reference
            )
            with np.errstate(invalid="ignore"):
                spread = np.std(fitted[:, now], axis=0)
                close = np.all(np.isfinite(ends), axis=0) & np.all(
                    np.abs(fitted[far][:, now] - ends) <= _SWING_TOLERANCE * spread, axis=0
                )
            now[np.flatnonzero(now)[~close]] = False
        out[:, todo[now]] = fitted[:, now]
        held[todo[now]] = True
    return out, held


def _linear_count(r: int) -> int:
    """p, the parameters of a cubic in p variables with r monomials
    (r = (p + 1)(p + 2)(p + 3)/6)."""
    p = 0
    while (p + 1) * (p + 2) * (p + 3) // 6 < r:
        p += 1
    return p


def _interpolation_held(fitted: NDArray, checked: NDArray, picked: NDArray) -> NDArray:
    """Per swing (column), whether the interpolated ΔE of every draw (``fitted``, (n, S))
    is within :data:`_SWING_TOLERANCE` of its spread over the draws of the integrated
    one at the draws ``picked`` (``checked``, (len(picked), S), all finite)."""
    spread = np.std(fitted, axis=0)
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(checked), axis=0) & np.all(
            np.abs(fitted[picked] - checked) <= _SWING_TOLERANCE * spread, axis=0
        )


def law_quantities(
    posterior: Posterior, draws: NDArray, scale: PhysicalScale, gain: NDArray | None = None
) -> tuple[dict[str, NDArray], dict[str, str]]:
    """The draws of a law's own parameters and physical quantities, by name, and their
    units, for terms other than viscous damping and Coulomb friction (whose ζ, μ_k,
    μ_s and x_c :func:`bayestribo.inference.assemble.derived_quantities` reports).

    Parameters
    ----------
    posterior : Posterior
    draws : ndarray
        Flat draws of the sampled coordinates, shape (n, d).
    scale : PhysicalScale
    gain : ndarray, optional
        Draws of the signal chain's gain, one per draw: the length of one unit of y is
        ℓ/g in each (:mod:`bayestribo.signal.sensor`). None: exactly 1.

    Returns
    -------
    values : dict of ndarray
    units : dict of str
    """
    values = posterior.law_draws(draws)
    if gain is not None:
        scale = dataclasses.replace(scale, length_scale=scale.length_scale / np.asarray(gain))
    sampled_or_fixed = set(posterior.names) | set(posterior.fixed)
    out: dict[str, NDArray] = {}
    units: dict[str, str] = {}
    ref = posterior.likelihood.reference_amplitude
    for term in posterior.law.terms:
        if term.name in ("viscous", "coulomb"):
            continue
        if not any(p.name in sampled_or_fixed for p in term.parameters):
            continue
        for p in term.parameters:
            out[p.name] = np.asarray(values[p.name], dtype=float)
            units[p.name] = "1" if p.unit == "-" else p.unit
        for name, (v, unit, _symbol, _label) in term.physical(values, ref, scale).items():
            arr = np.broadcast_to(np.asarray(v, dtype=float), (np.atleast_2d(draws).shape[0],))
            if np.all(np.isfinite(arr)):
                out[name] = np.array(arr)
                units[name] = unit
    return out, units


#: Fewest half cycles a local fit of :func:`turning_point_dissipation` uses.
_MIN_LOCAL_CYCLES = 8
#: Fewest half cycles that give a law-free ΔE(A) at all (a constant ΔE/A, two degrees of
#: freedom for its interval).
FEWEST_HALF_CYCLES = 3


def turning_point_dissipation(
    turning_points: NDArray,
    amplitudes: NDArray,
    scale: PhysicalScale,
    *,
    prob: float = 0.95,
    gain_sd: float = 0.0,
    restoring: Any = None,
    energy_sd: float = 0.0,
) -> dict[str, Any] | None:
    """ΔE(A) from the turning points alone: the law-free answer.

    Each half cycle from the turning point ``Y_n`` to ``Y_{n+1}`` loses
    ``(Y_n² - Y_{n+1}²)/2`` (times kℓ²) at its swing ``(|Y_n| + |Y_{n+1}|)/2``:
    whatever dissipates the energy, this is what the motion lost, and twice it is ΔE(A)
    as :meth:`~bayestribo.model.laws.Law.swing_dissipation` defines it for a law. An
    error δ of the equilibrium moves each half cycle's loss by ±2δA, alternately, which
    the local fit averages out. At each reported swing the ratio ΔE/A of the half
    cycles within a quarter decade of it (at least eight) is fitted as a parabola in A
    by least squares (a straight line leaves up to 8 standard errors of curvature bias
    under quadratic drag, whose ratio grows as A²), and the interval is the Student-t
    interval from the residual scatter: the noise is the recording's as it is, not a
    model of it (neighbouring half cycles share a turning point, whose error enters
    them with opposite signs: the scatter then overstates the error of their mean).
    Much wider than a law's band (every half cycle is its own measurement), it holds
    whatever the law. A record of fewer than eight half cycles (a seismometer's few
    swings, a torsion pendulum recorded for two seconds) fits all of them at every swing,
    with a polynomial of degree ``min(2, n - 3)`` so that two degrees of freedom remain
    for the interval: wide, but an answer; with fewer than three half cycles there is
    none. A fit passes a coarse displacement's turning points as its staircase places
    them (:func:`bayestribo.inference.law_free.law_free_turning_points`): on its levels
    they are up to half a step off, and the band is not calibrated.

    Parameters
    ----------
    turning_points : ndarray
        Turning points of the analysed window in order, about the equilibrium,
        dimensionless (units of ℓ).
    amplitudes : ndarray
        Swings at which to report ΔE(A) [dimensionless].
    scale : PhysicalScale
        Converts amplitudes and energies to physical units.
    prob : float
        Probability of the intervals.
    gain_sd : float
        Relative standard uncertainty of the sensor's gain, added in quadrature as in
        :func:`dissipation_band` (the scatter of the turning points does not hold it).
    restoring : str or RestoringForce, optional
        The oscillator's restoring force (:mod:`bayestribo.model.restoring`): each half
        cycle loses ``V(Y_n) - V(Y_n+1)`` of its potential V; default linear,
        ``V = y²/2``. A pendulum's turning points must be angles in radians.
    energy_sd : float
        Relative standard uncertainty of the energy unit (a pendulum's κ = Iω₀², whose
        ω₀ is known from the measured frequency only as well as the swing's effect on
        the period is), added in quadrature.

    Returns
    -------
    dict or None
        ``amplitude`` [``amplitude_unit``]; ``mean``, ``sd``, ``interval``
        [``unit``]; ``prob``; ``cycles`` (half cycles in each local fit); ``unit``;
        ``definition``. None with fewer than three half cycles.
    """
    prob = check_prob(prob)
    y = np.asarray(turning_points, dtype=float)
    a = np.abs(y)
    n = a.size - 1
    if n < FEWEST_HALF_CYCLES:
        return None
    degree = min(2, n - 3)  # two degrees of freedom at least for the interval
    from bayestribo.model.restoring import get_restoring

    potential = get_restoring(restoring).potential
    loss = 2.0 * (potential(y[:-1]) - potential(y[1:]))  # per cycle: twice the half cycle's
    swing = 0.5 * (a[:-1] + a[1:])
    ratio = loss / swing
    log_swing = np.log(swing)
    amps = np.asarray(amplitudes, dtype=float)
    mean = np.full(amps.size, np.nan)
    sd = np.full(amps.size, np.nan)
    lower = np.full(amps.size, np.nan)
    upper = np.full(amps.size, np.nan)
    used = np.zeros(amps.size, dtype=int)
    for j, amp in enumerate(amps):
        distance = np.abs(log_swing - math.log(amp))
        near = distance <= 0.25 * math.log(10.0)
        if near.sum() < _MIN_LOCAL_CYCLES:
            near = np.zeros(n, bool)
            near[np.argsort(distance)[:_MIN_LOCAL_CYCLES]] = True
        x = (swing[near] - amp) / amp
        design = np.column_stack([x**power for power in range(degree + 1)])
        coef, *_ = np.linalg.lstsq(design, ratio[near], rcond=None)
        dof = x.size - degree - 1
        resid = ratio[near] - design @ coef
        s2 = float(resid @ resid) / dof
        try:
            cov = s2 * np.linalg.inv(design.T @ design)
        except np.linalg.LinAlgError:
            # swings that repeat exactly (the turning points of a coarse digitiser sit
            # on its levels): the curvature terms are not determined, the mean is
            cov = s2 * np.linalg.pinv(design.T @ design)
        se = math.sqrt(max(cov[0, 0], 0.0))
        # Student's t quantile: what scipy.stats.t.ppf computes, without its per-call
        # argument handling (~100 µs a call, a swing each)
        q = float(scipy.special.stdtrit(dof, 0.5 * (1.0 + prob)))
        mean[j] = amp * coef[0]
        sd[j] = amp * se
        lower[j] = amp * (coef[0] - q * se)
        upper[j] = amp * (coef[0] + q * se)
        used[j] = int(near.sum())
    if gain_sd > 0 or energy_sd > 0:
        extra = np.hypot(_gain_error(mean, amps, gain_sd), energy_sd) * np.abs(mean)
        z = float(scipy.special.ndtri(0.5 * (1.0 + prob)))
        lower = mean - np.hypot(mean - lower, z * extra)
        upper = mean + np.hypot(upper - mean, z * extra)
        sd = np.hypot(sd, extra)
    factor = scale.energy_factor
    return {
        "amplitude": (amps * scale.length_scale).tolist(),
        "amplitude_unit": scale.length_unit,
        "mean": (mean * factor).tolist(),
        "sd": (sd * factor).tolist(),
        "interval": [(lower * factor).tolist(), (upper * factor).tolist()],
        "prob": prob,
        "cycles": used.tolist(),
        "unit": scale.energy_unit,
        "definition": "from the turning points: twice V(Y_n) - V(Y_n+1) per half cycle "
        f"({get_restoring(restoring).name} restoring force), local fit",
    }


def averaged_dissipation(
    members: list[tuple[str, Posterior, NDArray, PhysicalScale]],
    amplitude: NDArray,
    *,
    prob: float = 0.95,
    frequency_sd: float = 0.0,
) -> dict[str, Any]:
    """ΔE(A) averaged over laws the data do not tell apart, with equal weights.

    A decay often fits several laws equally well (PSIS-LOO differences within their
    noise): viscous damping and a friction that grows with the amplitude, or a law and
    the one that nests it with an extra term near zero. Their ΔE(A) agree to first
    order, not within the band of any one of them: at ten times the vibrometer's
    resolution a viscous fit of an amplitude-proportional friction put the true ΔE(A)
    1.8 to 2.7 of its standard deviations off (``benchmarks/laws.py``). The answer of a
    comparison therefore mixes their posteriors, the same number of draws from each:
    the laws as good as the best are one hypothesis the data cannot split.

    Parameters
    ----------
    members : list of (name, Posterior, draws, PhysicalScale)
        Each law's name, posterior, flat draws (n, d) and the physical scale of the
        preparation it was fitted on.
    amplitude : ndarray
        Swings A in the physical length unit of the scales.
    prob, frequency_sd
        As in :func:`dissipation_band`.

    Returns
    -------
    dict
        As :func:`dissipation_band` (without ``by_term`` and ``harmonic_mean``), with
        ``law`` the laws joined by " | " and ``laws`` their list.
    """
    prob = check_prob(prob)
    per = max(_BAND_DRAWS_INTEGRATED, _BAND_DRAWS // max(len(members), 1))
    amps = np.asarray(amplitude, dtype=float)
    stacks = []
    for _, posterior, draws, scale in members:
        draws = np.atleast_2d(np.asarray(draws, dtype=float))
        pick = draws[np.linspace(0, draws.shape[0] - 1, min(per, draws.shape[0])).astype(int)]
        values = posterior.law_draws(pick)
        energy = _swing_dissipation(
            posterior.law,
            amps / scale.length_scale,
            values,
            posterior.likelihood.reference_amplitude,
        )
        energy = energy[np.all(np.isfinite(energy), axis=1)]
        if energy.shape[0]:
            # the same number of draws from each law: equal weights
            take = np.linspace(0, energy.shape[0] - 1, per).astype(int)
            stacks.append(energy[take] * scale.energy_factor)
    if not stacks:
        raise ValueError("members: no law has a half cycle at these swings")
    mean, sd, lower, upper = _band(np.concatenate(stacks), prob, frequency_sd)
    names = [member[0] for member in members]
    scale = members[0][3]
    return {
        "law": " | ".join(names),
        "laws": names,
        "amplitude": amps.tolist(),
        "amplitude_unit": scale.length_unit,
        "mean": mean.tolist(),
        "sd": sd.tolist(),
        "interval": [lower.tolist(), upper.tolist()],
        "prob": prob,
        "unit": scale.energy_unit,
        "definition": "per cycle of each law's own motion at the swing A, averaged over the "
        "laws as good as the verdict (equal weights)",
        "frequency_nuisance_sd": float(frequency_sd),
    }


#: Largest difference of log-log slopes between a law's ΔE(A) and the turning points'
#: that still counts as the same shape (A¹ friction against A² drag differ by 1).
SHAPE_SLOPE_TOLERANCE = 0.5


def _log_slope(amplitude: NDArray, mean: NDArray, sd: NDArray | None) -> tuple[float, float]:
    """Least-squares slope of ln ΔE against ln A over the swings, and its standard
    error from the sds at the two ends (0 without sds)."""
    a, e = np.asarray(amplitude, dtype=float), np.asarray(mean, dtype=float)
    ok = np.isfinite(a) & np.isfinite(e) & (a > 0) & (e > 0)
    if sd is not None:
        s = np.asarray(sd, dtype=float)
        ok &= np.isfinite(s) & (s > 0)
    if ok.sum() < 2 or np.ptp(np.log(a[ok])) < 1e-9:
        return math.nan, math.inf
    x, y = np.log(a[ok]), np.log(e[ok])
    xm = float(np.mean(x))
    slope = float(np.sum((x - xm) * y) / np.sum((x - xm) ** 2))
    if sd is None:
        return slope, 0.0
    # neighbouring swings share half cycles (the local fits overlap), so the slope is
    # known no better than from its two ends: their relative errors over the span
    rel = np.asarray(sd, dtype=float)[ok] / e[ok]
    se = float(math.hypot(rel[0], rel[-1]) / (x[-1] - x[0]))
    return slope, abs(se)


def shape_agreement(band: Mapping[str, Any], measured: Mapping[str, Any] | None) -> dict | None:
    """How close a law's ΔE(A) comes to the turning points' (the law-free answer).

    Parameters
    ----------
    band : mapping
        A law's ΔE(A) (:func:`dissipation_band`).
    measured : mapping or None
        The turning points' ΔE(A) at the same swings (:func:`turning_point_dissipation`).

    Returns
    -------
    dict or None
        ``max_percent`` and ``rms_percent``: the law's departure from the turning
        points' mean over the swings, in percent of it; ``max_z``: the largest
        departure in the turning points' sd; ``law_slope`` and ``measured_slope``
        (± ``measured_slope_se``): log-log slopes of ΔE(A) (1 for friction, 2 for
        viscous damping, 3 for quadratic drag); ``same_shape``: False when the slopes
        differ by more than :data:`SHAPE_SLOPE_TOLERANCE` and by more than three
        standard errors. None without a turning-point answer.
    """
    if not measured or not measured.get("amplitude") or not band or not band.get("amplitude"):
        return None
    amp = np.asarray(band["amplitude"], dtype=float)
    law = np.asarray(band["mean"], dtype=float)
    tp = np.asarray(measured["mean"], dtype=float)
    tp_sd = np.asarray(measured["sd"], dtype=float)
    if amp.shape != tp.shape or not np.allclose(amp, measured["amplitude"], rtol=1e-9):
        raise ValueError("band and measured: expected ΔE(A) at the same swings")
    ok = np.isfinite(law) & np.isfinite(tp) & (tp > 0)
    if not ok.any():
        return None
    rel = (law[ok] - tp[ok]) / tp[ok]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(tp_sd[ok] > 0, (law[ok] - tp[ok]) / tp_sd[ok], np.nan)
    law_slope, _ = _log_slope(amp, law, None)
    tp_slope, tp_se = _log_slope(amp, tp, tp_sd)
    differ = abs(law_slope - tp_slope)
    same = not (math.isfinite(differ) and differ > SHAPE_SLOPE_TOLERANCE and differ > 3.0 * tp_se)
    return {
        "max_percent": float(100.0 * np.max(np.abs(rel))),
        "rms_percent": float(100.0 * math.sqrt(float(np.mean(rel * rel)))),
        "max_z": float(np.nanmax(np.abs(z))) if np.isfinite(z).any() else None,
        "law_slope": law_slope,
        "measured_slope": tp_slope,
        "measured_slope_se": tp_se,
        "same_shape": bool(same),
    }
