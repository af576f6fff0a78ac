"""Rig parameters and the dimensionless scaling of the free response.

Rigaud et al. (2010), Eq. 6 and 9-11::

    Ω² = k/m,   τ = Ω t,   y = k x / N,   y' = dy/dτ = k v / (N Ω),
    2ζ = (c₀ + N d_k)/√(k m),   ζ = ζ₀ + ζ_k,   2ζ_k = N d_k/√(k m).

The length that makes displacements dimensionless is ``ℓ = N/k`` [m]: a
displacement of one ℓ is the spring deflection that balances a friction force
equal to the load. Everything friction-related can be written with ℓ:
the friction displacement ``x_c = μ_k ℓ`` (the Coulomb force divided by the
stiffness) is the half-width of the band of ±x_c about which the oscillation is
centred (Eq. 16). When N or k is unknown (a recording from another rig, a test
without contact) ℓ is set to one unit of the signal: then y is the displacement in
the signal's unit, and the fitted "μ_k" *is* x_c in that unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Rig", "Scaling"]


def _positive_finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return value


@dataclass(frozen=True)
class Rig:
    """The oscillating system of a tribotest: mass, natural frequency and load.

    Parameters
    ----------
    natural_frequency_Hz : float
        Undamped natural frequency f [Hz]; Ω = 2πf (Eq. 6).
    mass_kg : float, optional
        Oscillating mass m [kg]. Needed for the stiffness k = mΩ² and for d_k.
    load_N : float, optional
        Normal load N [N]. ``0`` for a test without contact, ``None`` if unknown.
    frequency_measured : bool
        True when ``natural_frequency_Hz`` is not a nominal value but an estimate from
        the recording itself (:meth:`bayestribo.io.run.Run.rig` without
        ``natural_frequency_Hz`` in the metadata): the energy decay then has no nominal
        frequency to compare its measured one with (it scales with its own measurement
        either way, :func:`bayestribo.signal.decay.energy_decay`).

    Examples
    --------
    >>> rig = Rig(natural_frequency_Hz=32.6, mass_kg=0.035, load_N=0.31)
    >>> round(rig.stiffness_N_per_m, 1)
    1468.4
    """

    natural_frequency_Hz: float
    mass_kg: float | None = None
    load_N: float | None = None
    frequency_measured: bool = False

    def __post_init__(self) -> None:
        _positive_finite("natural_frequency_Hz", self.natural_frequency_Hz)
        if self.mass_kg is not None:
            _positive_finite("mass_kg", self.mass_kg)
        if self.load_N is not None:
            load = float(self.load_N)
            if not math.isfinite(load) or load < 0.0:
                raise ValueError(f"load_N must be a finite number >= 0, got {self.load_N!r}")

    @property
    def omega(self) -> float:
        """Circular natural frequency Ω = 2πf [rad/s] (Eq. 6)."""
        return 2.0 * math.pi * self.natural_frequency_Hz

    @property
    def stiffness_N_per_m(self) -> float | None:
        """Spring stiffness k = mΩ² [N/m] (Eq. 6), or ``None`` without a mass."""
        if self.mass_kg is None:
            return None
        return self.mass_kg * self.omega**2

    @property
    def has_contact(self) -> bool:
        """True when a positive load is known (μ_k is then defined)."""
        return self.load_N is not None and self.load_N > 0.0

    def scaling(self) -> Scaling:
        """The dimensionless scaling of this rig (see :class:`Scaling`)."""
        k = self.stiffness_N_per_m
        if self.has_contact and k is not None:
            return Scaling(omega=self.omega, length_scale=self.load_N / k, friction_defined=True)
        return Scaling(omega=self.omega, length_scale=1.0, friction_defined=False)

    def damping_split(self, zeta: ArrayLike, zeta0: ArrayLike) -> tuple[NDArray, NDArray]:
        """Split ζ into the contact part ζ_k = ζ - ζ₀ and the coefficient d_k.

        Parameters
        ----------
        zeta : array_like
            Equivalent viscous damping with contact, ζ (Eq. 6) [-].
        zeta0 : array_like
            Equivalent viscous damping of the rig without contact, ζ₀ (Eq. 10) [-].

        Returns
        -------
        zeta_k : ndarray
            ζ_k = ζ - ζ₀ (Eq. 9) [-].
        d_k : ndarray
            Velocity-dependent friction coefficient d_k = 2ζ_k√(km)/N (Eq. 11) [s/m].

        Raises
        ------
        ValueError
            Without a mass, or without a positive load (d_k is undefined there).
        """
        if self.mass_kg is None:
            raise ValueError("mass_kg is needed for d_k = 2 ζ_k sqrt(k m) / N (Eq. 11)")
        if not self.has_contact:
            raise ValueError(
                f"load_N must be > 0 for d_k = 2 ζ_k sqrt(k m) / N (Eq. 11), got {self.load_N!r}"
            )
        zeta_k = np.asarray(zeta, dtype=float) - np.asarray(zeta0, dtype=float)
        k = self.stiffness_N_per_m
        d_k = 2.0 * zeta_k * math.sqrt(k * self.mass_kg) / self.load_N
        return zeta_k, d_k


@dataclass(frozen=True)
class Scaling:
    """Conversion between physical signals and the paper's dimensionless ones.

    Parameters
    ----------
    omega : float
        Circular natural frequency Ω [rad/s].
    length_scale : float
        ℓ = N/k [signal length unit]; one dimensionless displacement unit.
    friction_defined : bool
        True when ℓ = N/k (a known load and stiffness), so the dimensionless
        friction is the friction coefficient μ_k. False when ℓ is one signal unit,
        in which case the dimensionless friction is the friction displacement.
    """

    omega: float
    length_scale: float = 1.0
    friction_defined: bool = False

    def __post_init__(self) -> None:
        _positive_finite("omega", self.omega)
        _positive_finite("length_scale", self.length_scale)

    def tau(self, t: ArrayLike) -> NDArray:
        """Dimensionless time τ = Ωt (Eq. 6)."""
        return self.omega * np.asarray(t, dtype=float)

    def time(self, tau: ArrayLike) -> NDArray:
        """Physical time t = τ/Ω [s]."""
        return np.asarray(tau, dtype=float) / self.omega

    def y(self, x: ArrayLike) -> NDArray:
        """Dimensionless displacement y = kx/N = x/ℓ (Eq. 6)."""
        return np.asarray(x, dtype=float) / self.length_scale

    def x(self, y: ArrayLike) -> NDArray:
        """Physical displacement x = yℓ [signal unit]."""
        return np.asarray(y, dtype=float) * self.length_scale

    def yp(self, v: ArrayLike) -> NDArray:
        """Dimensionless velocity y' = kv/(NΩ) = v/(ℓΩ)."""
        return np.asarray(v, dtype=float) / (self.length_scale * self.omega)

    def v(self, yp: ArrayLike) -> NDArray:
        """Physical velocity v = y'ℓΩ [signal unit/s]."""
        return np.asarray(yp, dtype=float) * (self.length_scale * self.omega)

    def friction_displacement(self, mu_k: ArrayLike) -> NDArray:
        """Friction displacement x_c = μ_k N/k = μ_k ℓ [signal unit]."""
        return np.asarray(mu_k, dtype=float) * self.length_scale

    def mu_k(self, friction_displacement: ArrayLike) -> NDArray:
        """Friction coefficient μ_k = x_c k/N from a friction displacement.

        Raises
        ------
        ValueError
            If the scaling has no load and stiffness (μ_k is then undefined).
        """
        if not self.friction_defined:
            raise ValueError(
                "μ_k needs a load N > 0 and a stiffness k: this scaling has neither; "
                "report the friction displacement instead"
            )
        return np.asarray(friction_displacement, dtype=float) / self.length_scale
