"""The averaged model's Π as numpy ufuncs, for :func:`bayestribo.model.averaged.averaged_pi`.

The scalar forms are :mod:`bayestribo.model._averaged_kernel`'s. The ufuncs are built
with their signatures, that is compiled (or loaded from the cache) when this module is
imported: they live apart from the scalar forms so that the fused log posterior, which
imports those, does not build them (0.1-0.15 s of every fitting process's start).
"""

from __future__ import annotations

import numba

from bayestribo.model._averaged_kernel import _CONTRACT, averaged_amplitude, pi_of_amplitude

__all__ = ["averaged_pi_ufunc", "averaged_pi_until"]


@numba.vectorize(["float64(float64, float64, float64, float64)"], cache=True, fastmath=_CONTRACT)
def averaged_pi_ufunc(t: float, a0: float, z: float, mk: float) -> float:  # pragma: no cover
    """Π_app(τ) to the end of motion (a numpy ufunc: broadcasts its arguments)."""
    return pi_of_amplitude(averaged_amplitude(t, a0, z, mk), z, mk)


@numba.vectorize(
    ["float64(float64, float64, float64, float64, float64)"], cache=True, fastmath=_CONTRACT
)
def averaged_pi_until(
    t: float, t_end: float, a0: float, z: float, mk: float
) -> float:  # pragma: no cover
    """Π_app(τ) to min(T_f, τ_end): 0 from τ_end on (a numpy ufunc)."""
    if not t < t_end:
        return 0.0
    pi = pi_of_amplitude(averaged_amplitude(t, a0, z, mk), z, mk)
    return pi - pi_of_amplitude(averaged_amplitude(t_end, a0, z, mk), z, mk)
