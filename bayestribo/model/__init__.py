"""Forward models of the free decay: exact piecewise solution and averaged closed forms.

All functions are dimensionless (τ = Ωt, y = kx/N, Rigaud et al. 2010, Eq. 6) and
broadcast their array arguments with numpy rules.
"""

from bayestribo.model.averaged import (
    averaged_amplitude,
    averaged_energy,
    averaged_pi,
    extinction_time,
)
from bayestribo.model.exact import (
    exact_energy,
    exact_pi,
    exact_response,
    rest_position,
    stop_time,
    turning_points,
)

__all__ = [
    "averaged_amplitude",
    "averaged_energy",
    "averaged_pi",
    "exact_energy",
    "exact_pi",
    "exact_response",
    "extinction_time",
    "rest_position",
    "stop_time",
    "turning_points",
]
