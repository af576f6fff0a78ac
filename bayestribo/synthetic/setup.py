"""What a simulated test is made of: the dissipation law, the release and the sensor.

:func:`bayestribo.synthetic.recording.simulate` takes one of each, with the rig
(:class:`bayestribo.model.scaling.Rig`): each object holds one part of the
experiment, checks its own fields (naming the field and what was expected), and has
the defaults of the paper's tribometer. The law is either :class:`DissipationLaw`
(viscous damping and Coulomb friction, constants or functions of the amplitude, on
the exact solution) or :class:`LawParameters` (any law of the registry,
:mod:`bayestribo.model.laws`, integrated by :mod:`bayestribo.synthetic.motion`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from bayestribo.model.scaling import Rig

__all__ = [
    "DISPLACEMENT_RESOLUTION_M",
    "PAPER_RIG",
    "VELOCITY_RESOLUTION_M_PER_S",
    "AmplitudeLaw",
    "DissipationLaw",
    "LawParameters",
    "Release",
    "Sensor",
]

#: Displacement resolution of the laser vibrometer of the paper, 0.15 µm (section 2.3).
DISPLACEMENT_RESOLUTION_M = 0.15e-6
#: Velocity resolution of the laser vibrometer of the paper, 0.015 µm/s (section 2.3).
VELOCITY_RESOLUTION_M_PER_S = 0.015e-6
#: The paper's rig: a 35 g pin on a blade at 32.6 Hz under 0.31 N (section 2).
PAPER_RIG = Rig(natural_frequency_Hz=32.6, mass_kg=0.035, load_N=0.31)

#: A parameter that depends on the oscillation amplitude: ``law(amplitude_m) -> value``.
AmplitudeLaw = Callable[[float], float]


def _number(name: str, value: float, *, low: float = 0.0, zero: bool = True) -> float:
    """``value`` as a finite float >= low (> low unless ``zero``), or a ValueError."""
    value = float(value)
    if not math.isfinite(value) or value < low or (value == low and not zero):
        bound = f">= {low:g}" if zero else f"> {low:g}"
        raise ValueError(f"{name} must be a finite number {bound}, got {value!r}")
    return value


@dataclass(frozen=True)
class DissipationLaw:
    """Viscous damping and Coulomb friction of the contact.

    Parameters
    ----------
    zeta : float or callable
        Equivalent viscous damping ζ [-] (Eq. 6), ``0 <= ζ < 1``, or ``zeta(amplitude_m)``
        (each half cycle uses the value at the amplitude of the turning point that
        starts it).
    mu_k : float or callable, optional
        Kinetic friction coefficient μ_k [-] (Eq. 3), or ``mu_k(amplitude_m)``. Default
        0.0294 on a rig with contact, 0 without.
    mu_s : float, optional
        Static friction coefficient μ_s >= μ_k [-] (Eq. 2, 5); default μ_k.
    """

    zeta: float | AmplitudeLaw = 0.0236
    mu_k: float | AmplitudeLaw | None = None
    mu_s: float | None = None

    def __post_init__(self) -> None:
        if not callable(self.zeta) and not 0.0 <= float(self.zeta) < 1.0:
            raise ValueError(f"zeta must satisfy 0 <= zeta < 1, got {self.zeta!r}")
        if self.mu_k is not None and not callable(self.mu_k):
            _number("mu_k", self.mu_k)
        if self.mu_s is not None:
            _number("mu_s", self.mu_s)
            if self.mu_k is not None and not callable(self.mu_k) and self.mu_s < self.mu_k:
                raise ValueError(
                    f"mu_s must be >= mu_k, got mu_s={self.mu_s!r} < mu_k={self.mu_k!r}"
                )

    @property
    def amplitude_dependent(self) -> bool:
        """True when ζ or μ_k depends on the amplitude."""
        return callable(self.zeta) or callable(self.mu_k)


def _describe(parameter: Any) -> str:
    """``name [unit] (symbol, label)`` of a law's parameter."""
    return f"{parameter.name} [{parameter.unit}] ({parameter.symbol}, {parameter.label})"


#: What the registry's units of a dimensionless parameter mean.
_UNITS_NOTE = "units: '-' none, 'y' one ℓ = N/k (1 m without contact), '1/y' per ℓ, '1/y²' per ℓ²"


@dataclass(frozen=True)
class LawParameters:
    """Any dissipation law of the registry with the values of its parameters.

    Parameters
    ----------
    law : str or Law
        The law's name, registered terms joined with ``+`` (``"viscous+quadratic"``),
        or a :class:`~bayestribo.model.laws.Law` (whose terms need not be registered).
    values : mapping of str to float
        Parameter values by name, in the registry's units (``bayestribo laws``): the
        dimensionless ones of Rigaud et al. (2010), Eq. 6-7, where ``y`` is one length
        scale ℓ = N/k (μ_k [y], quadratic drag γ = c₂ℓ/m [1/y], ...). A parameter
        not given takes its typical value (:attr:`Parameter.typical
        <bayestribo.model.laws.Parameter>`: ζ 0.0236, μ_k 0.0294, μ_s/μ_k 1); one
        without a typical value must be given. Terms parametrised at a reference
        amplitude (power-law drag's ζ_α) are at the release displacement x₀/ℓ.

    Raises
    ------
    ValueError
        For an unknown law, a name that is not one of the law's parameters, a value
        outside the parameter's support, or a parameter without a typical value that
        is not given (each message names the parameter with its unit).

    Examples
    --------
    >>> law = LawParameters("viscous+quadratic", {"zeta": 0.01, "c2": 0.005})
    >>> law.name, law.values["zeta"]
    ('viscous+quadratic', 0.01)
    """

    law: Any
    values: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from bayestribo.model.laws import get_law

        law = get_law(self.law)
        if not isinstance(self.values, Mapping):
            raise ValueError(
                f"values must be a mapping of parameter names to numbers, got {self.values!r}"
            )
        known = {p.name: p for p in law.parameters}
        for name in self.values:
            if name not in known:
                raise ValueError(
                    f"law {law.name} has no parameter {name!r}; its parameters: "
                    + "; ".join(_describe(p) for p in law.parameters)
                )
        values: dict[str, float] = {}
        for p in law.parameters:
            if p.name not in self.values:
                if p.typical is None:
                    raise ValueError(
                        f"law {law.name} needs a value of {_describe(p)}, in "
                        f"[{p.low:g}, {p.high:g}] ({_UNITS_NOTE}); it has no typical value"
                    )
                values[p.name] = float(p.typical)
                continue
            raw = self.values[p.name]
            try:
                value = float(raw)
            except (TypeError, ValueError):
                value = math.nan
            if not (math.isfinite(value) and p.low <= value <= p.high):
                raise ValueError(
                    f"parameter {_describe(p)} of law {law.name} must be a finite number in "
                    f"[{p.low:g}, {p.high:g}], got {raw!r}"
                )
            values[p.name] = value
        object.__setattr__(self, "law", law)
        object.__setattr__(self, "values", MappingProxyType(values))

    def __repr__(self) -> str:
        return f"LawParameters({self.name!r}, {dict(self.values)!r})"

    @property
    def name(self) -> str:
        """The law's name."""
        return str(self.law.name)

    @property
    def friction(self) -> bool:
        """True when the law has a friction term (it needs a load)."""
        return bool(self.law.friction)


@dataclass(frozen=True)
class Release:
    """How the test starts and how long it is recorded.

    Parameters
    ----------
    initial_displacement_m : float
        Initial displacement x₀ > 0 where the magnet holds the pin [m].
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
    """

    initial_displacement_m: float = 1.5e-3
    rest_before_s: float = 0.05
    motion_duration_s: float | None = None
    rest_after_s: float = 0.1
    magnet_fade_s: float | None = None
    offset_m: float = 0.0
    time_origin_s: float = 0.0

    def __post_init__(self) -> None:
        _number("initial_displacement_m", self.initial_displacement_m, zero=False)
        _number("rest_before_s", self.rest_before_s)
        _number("rest_after_s", self.rest_after_s)
        if self.motion_duration_s is not None:
            _number("motion_duration_s", self.motion_duration_s, zero=False)
        if self.magnet_fade_s is not None:
            _number("magnet_fade_s", self.magnet_fade_s)
        for name in ("offset_m", "time_origin_s"):
            if not math.isfinite(float(getattr(self, name))):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")

    def fade_s(self, rig: Rig) -> float:
        """The magnet fade [s]: as given, or a quarter of the rig's natural period."""
        if self.magnet_fade_s is None:
            return 0.25 * (1.0 / rig.natural_frequency_Hz)
        return float(self.magnet_fade_s)


@dataclass(frozen=True)
class Sensor:
    """What the vibrometer records and how.

    Parameters
    ----------
    sample_rate_Hz : float
        Sample rate [Hz].
    displacement_noise_m, velocity_noise_m_per_s : float, optional
        Standard deviation of the white noise on each channel [m], [m/s]; default the
        resolution; 0 for none.
    displacement_resolution_m, velocity_resolution_m_per_s : float
        Resolution [m], [m/s] (default: the paper's vibrometer), recorded in the
        metadata and used for quantisation.
    quantise : bool
        Round each channel to multiples of its resolution.
    displacement_range_m, velocity_range_m_per_s : float, optional
        Range [m], [m/s]: samples beyond are saturated at ±range (a clipped, invalid
        recording), and the range is recorded in the metadata.
    channels : tuple of str
        Which of ``"displacement"`` and ``"velocity"`` to record.
    """

    sample_rate_Hz: float = 10_000.0
    displacement_noise_m: float | None = None
    velocity_noise_m_per_s: float | None = None
    displacement_resolution_m: float = DISPLACEMENT_RESOLUTION_M
    velocity_resolution_m_per_s: float = VELOCITY_RESOLUTION_M_PER_S
    quantise: bool = False
    displacement_range_m: float | None = None
    velocity_range_m_per_s: float | None = None
    channels: tuple[str, ...] = ("displacement", "velocity")

    def __post_init__(self) -> None:
        _number("sample_rate_Hz", self.sample_rate_Hz, zero=False)
        _number("displacement_resolution_m", self.displacement_resolution_m, zero=False)
        _number("velocity_resolution_m_per_s", self.velocity_resolution_m_per_s, zero=False)
        for name in ("displacement_noise_m", "velocity_noise_m_per_s"):
            if getattr(self, name) is not None:
                _number(name, getattr(self, name))
        for name in ("displacement_range_m", "velocity_range_m_per_s"):
            if getattr(self, name) is not None:
                _number(name, getattr(self, name), zero=False)
        channels = tuple(self.channels)
        if not channels or set(channels) - {"displacement", "velocity"}:
            raise ValueError(
                f"channels must be some of ('displacement', 'velocity'), got {self.channels!r}"
            )
        object.__setattr__(self, "channels", channels)

    @property
    def noise(self) -> tuple[float, float]:
        """Noise standard deviations (displacement [m], velocity [m/s]) in use."""
        sx = self.displacement_resolution_m
        sv = self.velocity_resolution_m_per_s
        return (
            sx if self.displacement_noise_m is None else float(self.displacement_noise_m),
            sv if self.velocity_noise_m_per_s is None else float(self.velocity_noise_m_per_s),
        )
