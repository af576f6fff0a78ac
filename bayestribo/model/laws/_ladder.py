"""The step counts of the compiled integrator and their node tables, compiled once.

The template :mod:`bayestribo.model.laws._core` is compiled once per law (its text in
a generated module of the law cache), but what is here depends on no law: the ladder
of step counts a half cycle may take, the nodes of the stretched angle for a number of
steps (:func:`nodes`) and the tables of every count of the ladder, computed once at
import. The template imports them, so that numba compiles :func:`nodes` and
:func:`ladder_tables` once, into the package's own cache, instead of once per law
(1.1-1.4 s of CPU per law with an empty law cache, and the first law of a process
5-6 s in all with the numba routines they pulled in; ``benchmarks/law_compile.py``);
the tables a law's functions read are the same arrays, and :func:`nodes` the same code.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws._core_shared import _FAST

__all__ = ["LADDER", "ladder_tables", "nodes"]

#: The step counts a half cycle may take (at most 25 % apart: the count chosen is never
#: far above the one the error asks for). Those below the template's ``_MIN_STEPS``
#: serve only the half cycles past the record, whose share of Π(0) is small.
LADDER = np.array(
    [8, 12, 16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96, 112, 128, 160, 192, 224, 256, 320, 384],
    dtype=np.int64,
)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def nodes(theta0: float, steps: int) -> NDArray:
    """sin θ, cos θ and dθ/dψ at ψ = i/(2 steps), i = 0 .. 2 steps, shape (3, 2 steps + 1).

    Parameters
    ----------
    theta0 : float
        The angle the half cycle starts at [rad], in [0, π).
    steps : int
        Runge-Kutta steps of the half cycle (two nodes a step, and the last).

    Returns
    -------
    ndarray
        Rows sin θ, cos θ [dimensionless] and dθ/dψ [rad], shape (3, 2 steps + 1).
    """
    span = math.pi - theta0
    two_pi = 2.0 * math.pi
    out = np.empty((3, 2 * steps + 1))
    for i in range(2 * steps + 1):
        psi = i / (2.0 * steps)
        th = theta0 + span * (psi - math.sin(two_pi * psi) / two_pi)
        out[0, i] = math.sin(th)
        out[1, i] = math.cos(th)
        out[2, i] = span * (1.0 - math.cos(two_pi * psi))
    return out


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def ladder_tables() -> tuple[NDArray, NDArray]:
    """The node tables of every step count of :data:`LADDER`, side by side, and
    where each starts.

    Returns
    -------
    tables : ndarray
        :func:`nodes` ``(0, n)`` for each n of :data:`LADDER`, side by side, shape
        (3, Σ (2n + 1)).
    offsets : ndarray
        The column where each count's table starts, shape (len(LADDER),).
    """
    offsets = np.empty(LADDER.size, dtype=np.int64)
    total = 0
    for i in range(LADDER.size):
        offsets[i] = total
        total += 2 * LADDER[i] + 1
    out = np.empty((3, total))
    for i in range(LADDER.size):
        out[:, offsets[i] : offsets[i] + 2 * LADDER[i] + 1] = nodes(0.0, LADDER[i])
    return out, offsets


# The node tables of the ladder depend on no parameter: computed once, at import, and
# frozen into the compiled functions of every law that read them.
TABLES, OFFSETS = ladder_tables()
