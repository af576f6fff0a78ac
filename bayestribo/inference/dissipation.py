r"""The law-free answer of a fit: energy dissipated per cycle, ΔE(A), with its band.

Whatever the law, a fit answers "how much energy does the contact dissipate at each
amplitude": over one cycle of the harmonic motion ``x = A cos Ωt``,

.. math::

    ΔE(A) = \oint F(\dot x)\,\dot x\,dt,

which is ``π c Ω A²`` for viscous damping, ``4 μ_k N A`` for Coulomb friction,
``(8/3) c₂ Ω² A³`` for quadratic drag, ... (each term's
:meth:`~bayestribo.model.laws.Term.dissipation`). Laws that describe the same decay
give nearly the same ΔE(A) over the amplitudes the record holds, even where their
parameters differ, which makes ΔE(A) the quantity to compare across laws, rigs and
lubricants. It is given in joules where the stiffness is known (``k = mΩ²``: the
run's mass and frequency), otherwise as ΔE/k in the signal's unit squared, at
amplitudes spanning the analysed motion (its largest and smallest swing included).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.posterior import Posterior
from bayestribo.model.laws import PhysicalScale
from bayestribo.model.scaling import Scaling
from bayestribo.summary import check_prob

__all__ = [
    "DISSIPATION_AMPLITUDES",
    "dissipation_amplitudes",
    "dissipation_band",
    "law_quantities",
    "physical_scale",
]

#: Number of amplitudes at which ΔE(A) is reported.
DISSIPATION_AMPLITUDES = 12
#: At most this many posterior draws enter the band (the rest add Monte Carlo
#: precision far below the band's width).
_BAND_DRAWS = 4000


def physical_scale(scaling: Scaling, metadata: Mapping[str, Any]) -> PhysicalScale:
    """What one dimensionless unit of length, time and energy is for a run.

    Parameters
    ----------
    scaling : Scaling
        The run's dimensionless scaling (ℓ and Ω).
    metadata : mapping
        The run's metadata: ``mass_kg`` (for k = mΩ² and energies in joules),
        ``load_N``, ``length_unit``.

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
    return PhysicalScale(
        length_scale=float(scaling.length_scale),
        omega=float(scaling.omega),
        length_unit=unit,
        stiffness=stiffness,
        mass=mass if unit == "m" else None,
        load=load,
    )


def dissipation_amplitudes(turning_points: NDArray, n: int = DISSIPATION_AMPLITUDES) -> NDArray:
    """Amplitudes spanning the analysed motion: from its smallest swing to its largest.

    Parameters
    ----------
    turning_points : ndarray
        Turning points of the analysed window (any unit; signs ignored).
    n : int
        Number of amplitudes, log-spaced, both ends included.

    Returns
    -------
    ndarray
        Amplitudes in the unit of ``turning_points``.
    """
    a = np.abs(np.asarray(turning_points, dtype=float))
    a = a[np.isfinite(a) & (a > 0)]
    if a.size == 0:
        raise ValueError("turning_points: no finite non-zero turning point")
    low, high = float(a.min()), float(a.max())
    if high <= low * (1 + 1e-12):
        return np.array([high])
    return np.geomspace(low, high, n)


def dissipation_band(
    posterior: Posterior,
    draws: NDArray,
    amplitudes: NDArray,
    scale: PhysicalScale,
    *,
    prob: float = 0.95,
) -> dict[str, Any]:
    """ΔE(A) over posterior draws: mean and equal-tailed interval at each amplitude.

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

    Returns
    -------
    dict
        ``law``; ``amplitude`` [``amplitude_unit``]; ``mean``, ``interval`` (lower,
        upper lists), ``sd`` [``unit``]; ``prob``; ``by_term``: each term's mean
        share; ``unit`` ("J" or the length unit squared, energy over stiffness).
    """
    prob = check_prob(prob)
    draws = np.atleast_2d(np.asarray(draws, dtype=float))
    if draws.shape[0] > _BAND_DRAWS:
        # evenly spaced over every chain (no random numbers: the fit's stream is kept)
        draws = draws[np.linspace(0, draws.shape[0] - 1, _BAND_DRAWS).astype(int)]
    values = posterior.law_draws(draws)
    ref = posterior.likelihood.reference_amplitude
    amps = np.asarray(amplitudes, dtype=float)
    parts = posterior.law.dissipation(amps, values, ref, by_term=True)
    factor = scale.energy_factor
    total = sum(parts.values()) * factor
    tail = 0.5 * (1.0 - prob)
    lower, upper = np.quantile(total, [tail, 1.0 - tail], axis=0)
    return {
        "law": posterior.law.name,
        "amplitude": (amps * scale.length_scale).tolist(),
        "amplitude_unit": scale.length_unit,
        "mean": np.mean(total, axis=0).tolist(),
        "sd": np.std(total, axis=0, ddof=1).tolist() if total.shape[0] > 1 else [0.0] * amps.size,
        "interval": [lower.tolist(), upper.tolist()],
        "prob": prob,
        "unit": scale.energy_unit,
        "by_term": {name: (np.mean(v, axis=0) * factor).tolist() for name, v in parts.items()},
    }


def law_quantities(
    posterior: Posterior, draws: NDArray, scale: PhysicalScale
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

    Returns
    -------
    values : dict of ndarray
    units : dict of str
    """
    values = posterior.law_draws(draws)
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
