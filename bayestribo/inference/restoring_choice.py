"""``restoring="auto"``: the restoring force chosen from how the half period changes.

Viscous damping and Coulomb friction leave a linear oscillator's half period constant
(Rigaud et al. 2010, Eq. 15); a nonlinear restoring force makes it change with the
swing, each force in its own way (``RestoringForce.half_period_ratio``, T(A)/T₀).
:func:`choose_restoring` reads the record's turning times and turning points and
chooses, in this order:

1. **linear** when the half period's change from the largest swing to the smallest,
   Δ ± σ (:func:`~bayestribo.signal.frequency.turning_point_trend`, the measurement a
   linear fit's :class:`~bayestribo.errors.FrequencyTrendWarning` reports), is within
   its noise: |Δ| ≤ ``FREQUENCY_TREND_CHANGE`` (2e-4) or |Δ| ≤ ``FREQUENCY_TREND_Z``
   (4) σ (:attr:`~bayestribo.signal.frequency.FrequencyTrend.significant`). The run is
   then prepared and fitted exactly as with ``restoring="linear"``;
2. **pendulum** when the run is in radians (``length_unit`` ``"rad"``, the angle itself,
   every turning point below π) and its change is the pendulum's own: the turning times
   less the unevenness the pendulum's half periods put in them (``t_n = t₀ + T₀ Σ_{m<n}
   T(A_m)/T₀``, T₀ by least squares) leave a change within the same noise, or at most
   :data:`FOLLOWED` of the change, as for the Duffing spring below: damping moves a
   nonlinear oscillator's turning points off its undamped half periods by a share that
   grows as ζ² (a pendulum released at 90° with ζ = 0.04 on the paper's rig: -0.1 % of
   a -7 % change, at 18 standard errors), which the pendulum, with no parameter to
   adjust, cannot take up and a Duffing spring's β would;
3. **duffing** otherwise, β measured from the turning times
   (:func:`~bayestribo.model.restoring.duffing.fit_beta`). Its half periods follow the
   change when what they leave is within the noise or at most :data:`FOLLOWED` of the
   change (the turning times' interpolation leaves a small, significant remainder on a
   true Duffing spring, some 1e-3 of its change; the fit's frequency check reports
   what remains beyond the law on the chosen force, and its nuisance carries it).

When no force follows the change (the Duffing spring leaves more than :data:`FOLLOWED`
of it, or β cannot be measured: a change that is not monotonic in the swing, a
frequency that drifts in time, a softening beyond what oscillates), the force whose half
periods leave the smallest change is kept and a
:class:`~bayestribo.errors.FrequencyTrendWarning` says so, with what each leaves. A run
not in radians whose change is the pendulum's is told that a pendulum is fitted in
radians. A record with too few turning points to measure the change (8) is taken as
linear, with a warning. Nothing is chosen silently: the choice and its numbers are the
result's ``restoring["auto"]`` (:meth:`RestoringChoice.to_dict`) and its text's
``restoring`` line (:meth:`RestoringChoice.describe`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from bayestribo._warnings import warn
from bayestribo.errors import FrequencyTrendWarning
from bayestribo.model.restoring import AUTO, get_restoring
from bayestribo.signal.frequency import (
    FOLLOWED,
    FrequencyTrend,
    follows,
    trend_beyond,
    turning_point_trend,
)
from bayestribo.signal.pendulum_arm import arm_advice, simple_pendulum_arm

__all__ = [
    "AUTO",
    "FOLLOWED",
    "RestoringChoice",
    "arm_advice",
    "choose_restoring",
    "simple_pendulum_arm",
    "trend_beyond",
]


@dataclass(frozen=True)
class RestoringChoice:
    """The restoring force ``restoring="auto"`` chose, and why.

    Attributes
    ----------
    name : str
        The force chosen (``linear``, ``pendulum`` or ``duffing``).
    trend : FrequencyTrend or None
        The half period's change from the largest swing to the smallest, measured
        (None: too few turning points).
    left : dict of str to FrequencyTrend or None
        The change each force examined leaves beyond its own half periods (the linear
        spring's is ``trend``), in the order examined.
    beta, beta_se : float or None
        The Duffing spring's β [1/unit²] and its standard error, where it was examined.
    warning : str or None
        What the choice warned about (no force follows the change, too few turning
        points, a pendulum's change in a unit that is not radians).
    followed : bool
        False when no force follows the change (the one that leaves the least of it
        was kept).
    """

    name: str
    trend: FrequencyTrend | None
    left: dict[str, FrequencyTrend | None] = field(default_factory=dict)
    beta: float | None = None
    beta_se: float | None = None
    warning: str | None = None
    followed: bool = True

    def describe(self) -> str:
        """One line for the output: ``auto → pendulum: ...``."""
        head = f"{AUTO} → {self.name}"
        trend = self.trend
        if trend is None:
            return f"{head}: too few turning points to measure the half period's change"
        measured = f"{_percent(trend.change)} ({trend.z:+.1f} SE)"
        if self.name == "linear" and not trend.significant:
            return f"{head}: the half period is constant within its noise, {measured}"
        left = self.left.get(self.name)
        if not self.followed:
            least = "" if self.name == "linear" or left is None else f", {_percent(left.change)}"
            return (
                f"{head}: the half period changes by {measured} and no force follows it; "
                f"the {_noun(self.name)} leaves the least of it{least} (warned)"
            )
        rest = "" if left is None else f"; {_percent(left.change)} left, {left.z:+.1f} SE"
        how = "as the pendulum's does" if self.name == "pendulum" else "as a Duffing spring's does"
        return f"{head}: the half period changes by {measured} {how}{rest}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the choice, the measured change and what each force leaves."""
        return {
            "chosen": self.name,
            "trend": None if self.trend is None else self.trend.to_dict(),
            "left": {k: None if v is None else v.to_dict() for k, v in self.left.items()},
            "beta": self.beta,
            "beta_se": self.beta_se,
            "warning": self.warning,
            "followed": self.followed,
        }


def _noun(name: str) -> str:
    """A force's name in a sentence."""
    return {"linear": "linear spring", "duffing": "Duffing spring"}.get(name, name)


def _percent(change: float) -> str:
    return f"{100 * change:+.3g} %"


def choose_restoring(
    times: ArrayLike | None,
    values: ArrayLike,
    *,
    length_unit: str,
    angle: bool = True,
    name: str | None = None,
    length_scale: float = 1.0,
) -> RestoringChoice:
    """The restoring force of a record, by the rule of the module notes.

    Parameters
    ----------
    times : array_like or None
        The record's turning times [s] (:attr:`~bayestribo.signal.decay.EnergyDecay.
        turning_times`; None when its analysis gives none).
    values : array_like
        The turning points about the equilibrium, in the run's unit.
    length_unit : str
        The run's length unit: the pendulum is examined for ``"rad"`` only.
    angle : bool
        False when the displacement analysed is not the angle itself (a rig's scale
        divides it): no pendulum then either.
    name : str, optional
        The run's name in the warnings.
    length_scale : float
        The run's unit per unit of ``values`` (a rig's scale N/k; 1 when they are in the
        run's unit): a record in metres is examined as a simple pendulum recorded as a
        length (:func:`simple_pendulum_arm`) in metres.

    Returns
    -------
    RestoringChoice

    Warns
    -----
    FrequencyTrendWarning
        When no force follows the change, when it cannot be measured, and when a record
        not in radians changes as a pendulum's would.
    """
    run = name or "the run"
    y = np.asarray(values, dtype=float)
    trend = None if times is None else turning_point_trend(times, y)
    if trend is None or not math.isfinite(trend.change):
        text = (
            f"restoring auto: {run} holds too few turning points ({y.size}; 8 or more) to "
            "measure how its half period changes with the swing: the linear spring is "
            "taken; name the force (--restoring, the sidecar's 'restoring') if it is another"
        )
        warn(text, FrequencyTrendWarning)
        return RestoringChoice("linear", None, {"linear": None}, warning=text)
    left: dict[str, FrequencyTrend | None] = {"linear": trend}
    if not trend.significant:
        return RestoringChoice("linear", trend, left)
    small = bool(np.all(np.abs(y) < math.pi))
    pendulum = (
        trend_beyond(times, y, get_restoring("pendulum").half_period_ratio) if small else None
    )
    if length_unit == "rad" and angle:
        left["pendulum"] = pendulum
        if follows(pendulum, trend):
            return RestoringChoice("pendulum", trend, left)
    beta = beta_se = None
    try:
        force, record = get_restoring("duffing").measure(times, y)  # type: ignore[misc]
        beta, beta_se = float(record["beta"]), float(record["beta_se"])
        left["duffing"] = trend_beyond(times, y, force.half_period_ratio)
    except ValueError:
        left["duffing"] = None
    followed = follows(left["duffing"], trend)
    # a record not in radians that changes as a pendulum's would were it an angle
    hint = (
        ""
        if not follows(pendulum, trend) or "pendulum" in left
        else f"it changes as a pendulum's would were the displacement an angle in radians "
        f"({_percent(pendulum.change)} left), but the run's unit is {length_unit!r}"
        + ("" if angle else " and its displacement is scaled by the rig")
        + ": a pendulum is fitted with the angle itself in radians (length_unit 'rad', "
        "--length-unit rad) and --restoring pendulum"
    )
    arm = simple_pendulum_arm(times, y * length_scale) if length_unit == "m" else None
    if arm is not None:
        hint = arm_advice(arm)
    if followed and not hint:
        return RestoringChoice("duffing", trend, left, beta, beta_se)
    if followed:
        text = f"restoring auto: the Duffing spring is taken for {run}; {hint}"
        warn(text, FrequencyTrendWarning)
        return RestoringChoice("duffing", trend, left, beta, beta_se, warning=text)
    # no force follows the change: keep the one that leaves the least of it
    found = {k: v for k, v in left.items() if v is not None}
    best = min(found, key=lambda k: abs(found[k].change))
    parts = ", ".join(
        f"the {_noun(k)}'s {_percent(v.change)}" for k, v in found.items() if k != "linear"
    )
    text = (
        f"restoring auto: the half period of {run} changes by {_percent(trend.change)} "
        f"({trend.z:+.0f} standard errors) from the largest swing to the smallest, and no "
        "restoring force follows it"
        + (f" (beyond their half periods, {parts} are left)" if parts else "")
        + (
            "; the linear spring is taken"
            if best == "linear"
            else f"; the {_noun(best)}, which leaves the least, is taken"
        )
        + ". A change the forms cannot follow is none of theirs (a frequency that drifts "
        "in time, a change that is not monotonic in the swing, a spring that stiffens or "
        "softens otherwise than as the cube of the swing): the fit carries it as a "
        "frequency nuisance" + (f"; {hint}" if hint else "")
    )
    warn(text, FrequencyTrendWarning)
    return RestoringChoice(best, trend, left, beta, beta_se, warning=text, followed=False)
