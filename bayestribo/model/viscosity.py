"""Kinematic viscosity of glycerol-water solutions at 20 °C (Rigaud et al. 2010, Eq. 43).

The empirical law the paper takes from Shankar and Kumar (its reference [20])::

    (ln ν - ln ν_w) / (ln ν_g - ln ν_w) = x_g [1 + (1 - f_g)(a + b f_g + c f_g²)]   (Eq. 43)

with, at 20 °C, ν_g = 1160 mm²/s, ν_w = 1.01 mm²/s, a = -0.76728, b = 0.12153,
c = -1.41519, and f_g the mass fraction of glycerol.

Which fraction is x_g? The paper does not define x_g; the nomenclature defines only
f_g. Taking x_g = f_g (the glycerol *mass* fraction) reproduces the "Empirical
value" row of Table 1 to its printed digit (718.8, 625.5, 356.7, 252.5 and
214.2 mm²/s at 2.3, 3, 6, 8 and 9 % water); taking x_g as the glycerol *mole*
fraction gives 408 mm²/s at 2.3 % water instead of 718.8. So x_g = f_g here. In the
0.55 % column the table repeats the measured 1029 mm²/s (its relative error is
"-"): that column is where the water fraction was estimated from the measurement.
Eq. 43 gives 1031.3 mm²/s at 0.55 % water, and 1029 mm²/s at 0.56 % water.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "NU_GLYCEROL_MM2_PER_S",
    "NU_WATER_MM2_PER_S",
    "glycerol_water_viscosity",
    "water_fraction_for_viscosity",
]

#: Kinematic viscosity of glycerol at 20 °C, ν_g [mm²/s] (section 3.2).
NU_GLYCEROL_MM2_PER_S = 1160.0
#: Kinematic viscosity of water at 20 °C, ν_w [mm²/s] (section 3.2).
NU_WATER_MM2_PER_S = 1.01
_A, _B, _C = -0.76728, 0.12153, -1.41519


def _fraction(name: str, value: ArrayLike) -> NDArray:
    w = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(w)) or np.any((w < 0.0) | (w > 1.0)):
        raise ValueError(f"{name} must be a mass fraction in [0, 1], got {value!r}")
    return w


def glycerol_water_viscosity(water_mass_fraction: ArrayLike) -> NDArray:
    """Kinematic viscosity of a glycerol-water solution at 20 °C (Eq. 43).

    Parameters
    ----------
    water_mass_fraction : array_like
        Mass fraction of water 1 - f_g, in [0, 1] [-] (0.06 for 6 %).

    Returns
    -------
    ndarray
        Kinematic viscosity ν [mm²/s]; ν_g = 1160 at 0, ν_w = 1.01 at 1.

    Raises
    ------
    ValueError
        For a fraction outside [0, 1] or not finite.

    Examples
    --------
    >>> round(float(glycerol_water_viscosity(0.06)), 1)
    356.7
    """
    f_g = 1.0 - _fraction("water_mass_fraction", water_mass_fraction)
    ratio = f_g * (1.0 + (1.0 - f_g) * (_A + _B * f_g + _C * f_g**2))
    log_nu_w = np.log(NU_WATER_MM2_PER_S)
    return np.exp(log_nu_w + ratio * (np.log(NU_GLYCEROL_MM2_PER_S) - log_nu_w))


def water_fraction_for_viscosity(kinematic_viscosity_mm2_per_s: ArrayLike) -> NDArray:
    """Water mass fraction whose viscosity by Eq. 43 is the given one (the inverse).

    Eq. 43 decreases monotonically from ν_g (pure glycerol) to ν_w (pure water), so
    the inverse is unique; it is found by bisection to 1e-13 in the fraction.

    Parameters
    ----------
    kinematic_viscosity_mm2_per_s : array_like
        ν [mm²/s], within [ν_w, ν_g] = [1.01, 1160].

    Returns
    -------
    ndarray
        Mass fraction of water [-].

    Raises
    ------
    ValueError
        For a viscosity outside [ν_w, ν_g].
    """
    nu = np.asarray(kinematic_viscosity_mm2_per_s, dtype=float)
    if not np.all(np.isfinite(nu)) or np.any(
        (nu < NU_WATER_MM2_PER_S) | (nu > NU_GLYCEROL_MM2_PER_S)
    ):
        raise ValueError(
            f"kinematic_viscosity_mm2_per_s must be within [{NU_WATER_MM2_PER_S}, "
            f"{NU_GLYCEROL_MM2_PER_S}] mm²/s at 20 °C, got {kinematic_viscosity_mm2_per_s!r}"
        )
    low, high = np.zeros_like(nu), np.ones_like(nu)
    for _ in range(60):  # 2^-60 < 1e-13: bisection on a monotone decreasing function
        mid = 0.5 * (low + high)
        above = glycerol_water_viscosity(mid) > nu
        low, high = np.where(above, mid, low), np.where(above, high, mid)
    return 0.5 * (low + high)
