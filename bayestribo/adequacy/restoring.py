"""The run's restoring force in the adequacy checks: its decay, its law and its motion.

The checks judge the law of constant ζ and friction (viscous damping and Coulomb
friction, Eq. 7) on the oscillator's own restoring force (docs/restoring.md): a run
whose ``restoring`` (its metadata, or the ``restoring=`` option of
:func:`bayestribo.adequacy.check_adequacy`) names a force with compiled kernels (a
pendulum, a Duffing spring) is analysed as the fit analyses it
(:func:`bayestribo.inference.preparation.prepare`: time in the small swings' ω₀, the
energy ½y'² + V(y)), and the checks take that force's motion, y'' = -V'(y) - 2ζy' -
μ sgn y', in place of the linear spring's closed forms. ``restoring: auto`` is chosen
once on the whole run (:func:`bayestribo.inference.restoring_choice.choose_restoring`).

The motion of the parameter draws: the turning points from the law's compiled
integrator (:meth:`bayestribo.model.laws.Law.turning_points` with
:meth:`~bayestribo.model.laws.Law.with_restoring`), and the motion near them (to
sample a peak as the record samples it) by classical Runge-Kutta from rest on a grid
(:func:`rest_grid`) and cubic Hermite interpolation in it (:func:`hermite`), vectorised
over draws and peaks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.signal.decay import EnergyDecay

__all__ = [
    "LAW",
    "chains",
    "chosen_run",
    "force_text",
    "hermite",
    "rest_grid",
    "restoring_decay",
    "segment_law",
]

#: The law the checks judge: constant ζ and friction.
LAW = "viscous+coulomb"

#: Runge-Kutta steps per π of τ of :func:`rest_grid` (as the law's integrator takes).
STEPS_PER_PI = 40


def chosen_run(run: Any, restoring: str | None = None, *, skip_oscillations: int = 1) -> Any:
    """The run (a Run, or a path read) with its restoring force named: ``restoring``
    when given, else the run's own; ``"auto"`` chosen once, on the whole run's linear
    analysis (:func:`~bayestribo.inference.restoring_choice.choose_restoring`), so that
    every window and half takes the same force.

    Raises
    ------
    RecordingError
        For a ``restoring`` that names no registered force (nor ``"auto"``).
    """
    from bayestribo.adequacy.windows import _as_run, analysed_decay
    from bayestribo.errors import RecordingError
    from bayestribo.model.restoring import AUTO, get_restoring, restoring_choices

    run = _as_run(run)
    if restoring is not None:
        if restoring != AUTO:
            try:
                get_restoring(restoring)
            except ValueError:
                raise RecordingError(
                    f"restoring must be one of {restoring_choices()}, got {restoring!r}"
                ) from None
        run = run.with_metadata(restoring=restoring)
    if run.metadata.get("restoring") != AUTO:
        return run
    from bayestribo.inference.restoring_choice import choose_restoring

    decay = analysed_decay(run, skip_oscillations=skip_oscillations)  # the linear analysis
    choice = choose_restoring(
        decay.turning_times,
        decay.peaks.value / decay.scaling.length_scale,
        length_unit=run.length_unit,
        angle=decay.scaling.length_scale == 1.0,
        name=str(run.source or run.metadata.get("run_id") or "") or None,
    )
    return run.with_metadata(restoring=choice.name)


def nonlinear(run: Any) -> bool:
    """True when the run (not an EnergyDecay) names a restoring force with compiled
    kernels (the checks then take its motion)."""
    from bayestribo.model.restoring import AUTO, get_restoring

    if isinstance(run, EnergyDecay):
        return False
    name = dict(getattr(run, "metadata", {})).get("restoring")
    if name is None or name == AUTO:
        return False
    return get_restoring(name).kernels is not None


def restoring_decay(run: Any, *, skip_oscillations: int = 1) -> EnergyDecay:
    """The decay of a run on its nonlinear restoring force, as the fit prepares it (time
    in the small swings' ω₀, the energy ½y'² + V(y), a Duffing spring's β measured from
    the record); :attr:`EnergyDecay.restoring` holds the force."""
    from bayestribo.inference.preparation import prepare

    return prepare(run, skip_oscillations=skip_oscillations).decay


def force_text(kernel: Any) -> str:
    """The restoring force in words: ``"the pendulum's restoring force"``, or with its
    measured coefficients (``"the duffing's restoring force (0.6)"``)."""
    return f"the {kernel.name}'s restoring force" + (
        f" (β = {kernel.coefficients[0]:.4g})" if kernel.coefficients else ""
    )


def segment_law(kernel: Any) -> Any:
    """The law of constant ζ and friction on the restoring force ``kernel``."""
    from bayestribo.model.laws import get_law

    return get_law(LAW).with_restoring(kernel)


def _values(zeta: float, mu: float, mu_s: float) -> dict[str, float]:
    return {"zeta": zeta, "mu_k": mu, "mu_s_ratio": mu_s / mu if mu > 0.0 else 1.0}


def chains(
    kernel: Any, draws: Any, sign0: float, tau_max: float, max_count: int
) -> list[tuple[NDArray, NDArray, bool]]:
    """Each draw's turning times τ_n and points Y_n from its first analysed turning point
    (signed ``sign0``), until it stops, passes ``tau_max`` or holds ``max_count``;
    and whether it stopped (its last turning point inside the static friction band
    |V'(Y)| <= μ_s).

    Parameters
    ----------
    kernel : RestoringKernel
        The restoring force.
    draws : ParameterDraws
        ζ, μ, μ_s and Y_0 per draw (dimensionless).
    sign0 : float
        Sign of the first turning point.
    tau_max : float
        Last time [-].
    max_count : int
        At most this many turning points.
    """
    law = segment_law(kernel)
    out = []
    for z, m, ms, y0 in zip(draws.zeta, draws.mu, draws.mu_s, draws.y0, strict=True):
        ms = max(float(ms), float(m))
        tn, yn = law.turning_points(
            _values(float(z), float(m), ms),
            sign0 * float(y0),
            0.0,
            tau_max=tau_max,
            max_count=max_count,
        )
        force = abs(float(kernel.spring(yn[-1]))) if yn.size else 0.0
        out.append((tn, yn, bool(yn.size and force <= ms)))
    return out


def rest_grid(
    spring: Any,
    start: NDArray,
    direction: NDArray,
    zeta: NDArray,
    mu: NDArray,
    span: float,
) -> tuple[float, NDArray, NDArray, NDArray]:
    """The motion from rest at ``start``, moving in ``direction`` (±1, held: y'' = -V'(y)
    - 2ζy' - direction·μ), on the grid s_j = j·h up to ``span`` [-] (either sign; a
    negative span integrates back to the motion that arrived at ``start``, whose
    direction is the opposite of the next half cycle's), by classical Runge-Kutta with
    the step h = ±π/:data:`STEPS_PER_PI`.

    Returns
    -------
    h : float
        The step [-], of the sign of ``span``.
    y, yp, ypp : ndarray
        y, y' and y'' at the grid points, shape (G, *B), B the broadcast shape of the
        arguments; G - 1 steps reach past ``span``.
    """
    h = math.copysign(math.pi / STEPS_PER_PI, span if span != 0.0 else 1.0)
    count = math.ceil(abs(span) / abs(h)) + 2
    shape = np.broadcast_shapes(np.shape(start), np.shape(direction), np.shape(zeta), np.shape(mu))
    friction = np.asarray(direction, dtype=float) * np.asarray(mu, dtype=float)
    two_zeta = 2.0 * np.asarray(zeta, dtype=float)

    def acc(y: NDArray, v: NDArray) -> NDArray:
        return -np.asarray(spring(y), dtype=float) - two_zeta * v - friction

    ys, vs, accs = np.empty((3, count, *shape))
    y = np.broadcast_to(np.asarray(start, dtype=float), shape).copy()
    v = np.zeros(shape)
    for j in range(count):
        a1 = acc(y, v)
        ys[j], vs[j], accs[j] = y, v, a1
        if j + 1 == count:
            break
        y2, v2 = y + 0.5 * h * v, v + 0.5 * h * a1
        a2 = acc(y2, v2)
        y3, v3 = y + 0.5 * h * v2, v + 0.5 * h * a2
        a3 = acc(y3, v3)
        y4, v4 = y + h * v3, v + h * a3
        a4 = acc(y4, v4)
        y = y + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
        v = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    return h, ys, vs, accs


def hermite(h: float, f: NDArray, df: NDArray, s: NDArray, column: NDArray) -> NDArray:
    """Cubic Hermite interpolation of ``f`` (values at s_j = j·h, its derivative ``df``,
    both (G, M)) at the times ``s`` [-] of the columns ``column`` (same shapes); a time
    outside the grid takes its nearest end."""
    x = np.asarray(s, dtype=float) / h
    j = np.clip(np.floor(x).astype(np.int64), 0, f.shape[0] - 2)
    u = np.clip(x - j, 0.0, 1.0)
    f0, f1 = f[j, column], f[j + 1, column]
    d0, d1 = df[j, column] * h, df[j + 1, column] * h
    u2 = u * u
    u3 = u2 * u
    return (
        (2.0 * u3 - 3.0 * u2 + 1.0) * f0
        + (u3 - 2.0 * u2 + u) * d0
        + (-2.0 * u3 + 3.0 * u2) * f1
        + (u3 - u2) * d1
    )
