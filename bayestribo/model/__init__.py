"""Forward models of the free decay: exact piecewise solution and averaged closed forms.

All functions are dimensionless (τ = Ωt, y = kx/N, Rigaud et al. 2010, Eq. 6) and
broadcast their array arguments with numpy rules. They are re-exported lazily, so that
importing a light module of the package (``model.restoring``'s registry, whose table the
command line reads) imports neither of them.
"""

from __future__ import annotations

from bayestribo._lazy import lazy_exports

_LAZY: dict[str, str] = {
    "averaged_amplitude": "bayestribo.model.averaged",
    "averaged_energy": "bayestribo.model.averaged",
    "averaged_pi": "bayestribo.model.averaged",
    "extinction_time": "bayestribo.model.averaged",
    "exact_energy": "bayestribo.model.exact",
    "exact_pi": "bayestribo.model.exact",
    "exact_response": "bayestribo.model.exact",
    "rest_position": "bayestribo.model.exact",
    "stop_time": "bayestribo.model.exact",
    "turning_points": "bayestribo.model.exact",
}

__all__ = sorted(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
