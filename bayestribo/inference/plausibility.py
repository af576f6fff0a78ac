"""A friction coefficient no contact has: the run's load or mass in another unit.

μ_k comes from the friction displacement x_c and the run's metadata, μ_k = x_c k / N
with the stiffness k = m ω₀² (:func:`bayestribo.inference.assemble.derived_quantities`):
the record fixes x_c
and ω₀, the sidecar gives m (``mass_kg``) and N (``load_N``). A mass given in grams
under a key in kilograms makes μ_k 1000 times too large, a load in millinewtons under
a key in newtons as much again; the fit itself cannot see it (the record is fitted as
well as before) and would report the quantity with exit 0. Measured kinetic friction
coefficients lie below about 1.5 (clean metals in air up to ~1.5, rubber on dry glass
up to ~3 at the most); an interval of μ_k wholly above :data:`MU_K_LIMIT` is taken as
a unit error of the metadata, not a measurement, and said with the values used
(:class:`~bayestribo.errors.ImplausibleFrictionWarning`, exit 1).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._warnings import warn
from bayestribo.errors import ImplausibleFrictionWarning

__all__ = ["MU_K_LIMIT", "implausible_friction", "warn_implausible_friction"]

#: Kinetic friction coefficient [1] above which no contact's is taken as measured:
#: twice the largest commonly measured (clean metals, ~1.5) and above rubber on dry
#: glass (~3 at the most).
MU_K_LIMIT = 3.0


def implausible_friction(
    derived: Mapping[str, NDArray], metadata: Mapping[str, Any], prob: float = 0.95
) -> str | None:
    """The reason μ_k's draws are no contact's, or None.

    Parameters
    ----------
    derived : mapping of str to array
        The fit's derived quantities' draws; ``mu_k`` [1] where the load and the mass
        are known.
    metadata : mapping
        The run's metadata (``load_N`` [N], ``mass_kg`` [kg]).
    prob : float
        The central interval whose lower end is tested against :data:`MU_K_LIMIT`.

    Returns
    -------
    str or None
        A sentence with the interval and the load and mass it was computed from, where
        the interval's lower end exceeds :data:`MU_K_LIMIT`.
    """
    draws = derived.get("mu_k")
    if draws is None:
        return None
    values = np.asarray(draws, dtype=float).ravel()
    values = values[np.isfinite(values)]
    if values.size == 0:
        return None
    low, mid, high = np.quantile(values, [(1 - prob) / 2, 0.5, (1 + prob) / 2])
    if not low > MU_K_LIMIT:
        return None
    load, mass = metadata.get("load_N"), metadata.get("mass_kg")
    return (
        f"mu_k = {mid:.4g} [{low:.4g}, {high:.4g}] from load_N = {load} N and "
        f"mass_kg = {mass} kg: no contact's kinetic friction coefficient is above "
        f"{MU_K_LIMIT:g}, so the load or the mass is likely in another unit (a load in "
        "kgf is 9.81 N, one in mN 1e-3 N; a mass in g is 1e-3 kg). Give them in newtons "
        "and kilograms (sidecar load_N, mass_kg, or keys that name their unit: "
        "load_kgf, mass_g)"
    )


def warn_implausible_friction(
    name: str | None, derived: Mapping[str, NDArray], metadata: Mapping[str, Any]
) -> None:
    """Warn (:class:`~bayestribo.errors.ImplausibleFrictionWarning`) where
    :func:`implausible_friction` finds a reason."""
    reason = implausible_friction(derived, metadata)
    if reason is not None:
        warn(f"{name or 'the run'}: {reason}", ImplausibleFrictionWarning)
