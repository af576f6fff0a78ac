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
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.signal.decay import EnergyDecay

__all__ = [
    "LAW",
    "LINEAR_SPRING",
    "chains",
    "chosen_run",
    "first_turn",
    "force_text",
    "hermite",
    "law_frame_frequency",
    "rest_grid",
    "restoring_decay",
    "segment_law",
]

#: The law the checks judge: constant ζ and friction.
LAW = "viscous+coulomb"

#: The linear spring's force and potential, V'(y) = y and V(y) = y²/2, as a kernel's.
LINEAR_SPRING = SimpleNamespace(spring=lambda y: y, potential=lambda y: 0.5 * y * y)

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
        length_scale=decay.scaling.length_scale,
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


def restoring_decay(run: Any, *, skip_oscillations: int = 1, seed: int = 0) -> EnergyDecay:
    """The decay of a run on its nonlinear restoring force, as the fit prepares it (time
    in the small swings' ω₀, the energy ½y'² + V(y), a Duffing spring's β measured from
    the record), then again in the frame of the law's own turning times
    (:func:`law_frame_frequency`), as the fit samples it; :attr:`EnergyDecay.restoring`
    holds the force.

    The small swings' ω₀ is measured from the turning times with the undamped half
    periods at each swing, which friction and damping change a little on a nonlinear
    force (about 0.3 % over a pendulum's decay from 75° with a friction angle of
    0.012 rad): left as it is, the predicted end of motion, a sum of every half period,
    is off by as much, far beyond its interval.
    """
    from bayestribo.inference.preparation import prepare, reframe

    prepared = prepare(run, skip_oscillations=skip_oscillations)
    frequency = law_frame_frequency(prepared.decay, seed=seed)
    return prepared.decay if frequency is None else reframe(prepared, frequency).decay


def law_frame_frequency(decay: EnergyDecay, *, seed: int = 0) -> float | None:
    """The natural frequency [Hz] at which the turning times of the law of constant ζ
    and friction on the decay's restoring force, fitted to the whole decay
    (:func:`~bayestribo.adequacy.segments.whole_decay_fit`), keep step with the
    record's: the slope of the record's turning times against the law's, weighted by
    |Y_n| (as :func:`bayestribo.inference.preparation.law_frequency` finds it for a
    fit). None when fewer than 90 % of them (and 4) have a turning point of the law
    within a quarter period.
    """
    from bayestribo.adequacy.segments import whole_decay_fit
    from bayestribo.inference.preparation import match_turning_times

    times = decay.turning_times
    if decay.restoring is None or times is None or np.size(times) < 4:
        return None
    whole = whole_decay_fit(decay, seed=seed)
    sign = 1.0 if decay.y[0] >= 0.0 else -1.0
    tau_law, _ = segment_law(decay.restoring).turning_points(
        _values(whole.zeta, whole.mu, whole.mu),
        sign * whole.y0,
        float(decay.yp[0]),
        tau_max=float(decay.tau[-1] - decay.tau[0]) + 2.0 * math.pi,
    )
    matched = match_turning_times(tau_law, decay)
    if matched is None:
        return None
    tau_meas, tau_matched, close = matched
    weight = np.abs(np.asarray(decay.peaks.value, dtype=float))[close]
    if weight.size != tau_matched.size or not np.any(weight > 0.0):
        weight = np.ones(tau_matched.size)
    slope = float(np.polyfit(tau_matched, tau_meas, 1, w=np.sqrt(weight))[0])
    if not (math.isfinite(slope) and slope > 0.0):
        return None
    return decay.scaling.omega / slope / (2.0 * math.pi)


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


def first_turn(decay: EnergyDecay, draws: Any) -> tuple[Any, NDArray]:
    """The draws from the first turning point: its amplitude [-] in place of ``y0``,
    and how long before the decay's first sample it was [-] (negative when it comes
    after it), per draw.

    On the linear spring (``decay.restoring`` None) the potential is y²/2.

    The least-squares and Bayesian fits start the model at the decay's first sample,
    at ``y0`` with the recorded velocity there (``decay.yp[0]``: the sample nearest the
    turning point is not on it); the turning point before it is that of the undamped
    motion through that state, V(A) = ½y'² + V(y₀) (the loss over the part of a sample
    period between them is of the order of ζ and μ times the distance, far below the
    noise), reached |y'|/(|V'(A)| - μ) earlier (the acceleration there held).
    """
    import dataclasses

    kernel = decay.restoring or LINEAR_SPRING
    yp0 = float(decay.yp[0])
    y0 = np.abs(np.asarray(draws.y0, dtype=float))
    energy = 0.5 * yp0 * yp0 + np.asarray(kernel.potential(y0), dtype=float)
    amp = np.sqrt(2.0 * energy)
    for _ in range(40):  # Newton on V(A) = E from the linear spring's amplitude
        step = (np.asarray(kernel.potential(amp), dtype=float) - energy) / np.asarray(
            kernel.spring(amp), dtype=float
        )
        amp = amp - step
        if np.all(np.abs(step) <= 1e-14 * amp):
            break
    pull = np.maximum(np.abs(np.asarray(kernel.spring(amp), dtype=float)) - draws.mu, 1e-12)
    # moving away from the equilibrium: the turning point is still ahead
    ahead = yp0 * float(decay.y[0]) > 0.0
    return dataclasses.replace(draws, y0=amp), (-1.0 if ahead else 1.0) * abs(yp0) / pull


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
