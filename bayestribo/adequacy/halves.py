r"""Split-half consistency: the first and second halves of the motion fitted apart.

If one constant (ζ, μ_k) describes the whole decay (Eq. 7), the two halves of the
motion fitted separately must give the same values within their uncertainty. The
decay is cut at the turning point in the middle of its half cycles, so each half
holds the same number of half cycles (the second one more when their number is odd),
hence about the same number of Π increments (a split *by τ*, not by
amplitude: the windowed fits and the constancy test already look along the
amplitude; a split by amplitude would leave the low-amplitude half with most of the
cycles of a viscous decay and the other with few). Each half is fitted by a window
fitter of :mod:`bayestribo.adequacy.windows`: least squares on its Π increments by
default (:class:`~bayestribo.adequacy.windows.LeastSquaresWindows`, covariance from
the curvature widened by the reduced χ² when above 1), or the Bayesian fit
(:class:`~bayestribo.adequacy.windows.BayesianWindows`, posterior covariance).

The test. With θ₁ and θ₂ the estimates of the halves and C₁, C₂ their covariances
(independent: the halves share no increment, and their noise is independent), the
difference d = θ₂ − θ₁ has covariance C₁ + C₂, and

.. math::  χ² = dᵀ (C_1 + C_2)^{-1} d \;\sim\; χ²_k

under the constant law (k = 2 for (ζ, μ), 1 when the friction is held). The halves
agree when the p-value is at least ``alpha`` (the false-alarm rate, 5 % by default;
measured on simulated runs by ``benchmarks/halves.py`` and tested in
``tests/test_adequacy_halves.py``). Measured at α = 5 %: least squares 1.3 % at the
vibrometer's resolution (conservative: the covariance is widened by a reduced χ²
near 1.6 there) and 6.2 % at 10× the noise (400 runs each); the Bayesian halves
15 % (6 of 40), because the Bayesian fit's own intervals are about 15 % too narrow
on these clean runs (each half's z against the truth has sd 1.1-1.2): the check
inherits the calibration of the fit it uses. The report gives, for each parameter, the
change from the first to the second half, relative to their mean and in standard
deviations of the difference: by how much the constant law fails.

Friction. As for the windows (``friction="auto"``): ζ and μ are both compared when
the whole-decay fit resolves the friction (μ above three standard errors) and
neither half's estimate sits on a bound; otherwise μ is held at the whole-decay
value in both halves and the *equivalent* damping ζ of the halves is compared
(1 degree of freedom).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import scipy.stats

from bayestribo.adequacy.segments import peak_positions, whole_decay_fit
from bayestribo.adequacy.windows import (
    LeastSquaresWindows,
    WindowContext,
    WindowEstimate,
    WindowFitter,
    _as_run,
    _estimate,
    analysed_decay,
    friction_symbol,
)
from bayestribo.errors import RecordingError
from bayestribo.signal.decay import EnergyDecay
from bayestribo.summary import interval_text

__all__ = ["MIN_HALF_OSCILLATIONS", "SplitHalves", "split_halves"]

#: Fewest oscillations in each half (least squares; the Bayesian fit needs 3).
MIN_HALF_OSCILLATIONS = 2


@dataclass(frozen=True)
class SplitHalves:
    """The two halves of a decay fitted apart, and whether they agree.

    Attributes
    ----------
    first, second : WindowEstimate
        The fits of the first and second halves (ζ, the friction, their covariance
        and 95 % intervals, the halves' time and amplitude ranges).
    parameters : tuple of str
        What is compared: ``("zeta", "mu")``, or ``("zeta",)`` when the friction is
        held at the whole-decay value (``friction_mode == "fixed"``).
    friction_name : str
        ``"mu_k"`` [-] or ``"friction_displacement"`` [signal length unit]: what
        ``"mu"`` is.
    friction_mode : str
        ``"fit"`` or ``"fixed"``.
    difference, difference_sd, z, relative : dict of str to float
        Per compared parameter: second minus first half, the sd of that difference
        (√ of the summed variances), their ratio, and the difference over the mean of
        the halves (None-free: NaN when the mean is 0).
    chi2 : float
        dᵀ(C₁+C₂)⁻¹d.
    dof : int
        Number of compared parameters.
    p_value : float
        P(χ²_dof ≥ chi2).
    alpha : float
        False-alarm rate: the halves disagree when ``p_value < alpha``.
    method : str
        ``"least_squares"`` or ``"bayes"``.
    interval_kind : str
        How the halves' intervals were obtained.
    length_unit : str
        ``"rad"`` for a rotation (its friction is the angle θ_c), else
        ``"signal unit"``.
    """

    first: WindowEstimate
    second: WindowEstimate
    parameters: tuple[str, ...]
    friction_name: str
    friction_mode: str
    difference: dict[str, float]
    difference_sd: dict[str, float]
    z: dict[str, float]
    relative: dict[str, float]
    chi2: float
    dof: int
    p_value: float
    alpha: float
    method: str
    interval_kind: str
    length_unit: str = "signal unit"

    @property
    def consistent(self) -> bool:
        """The halves agree within their uncertainty (p-value at least ``alpha``)."""
        return bool(self.p_value >= self.alpha)

    @property
    def max_abs_z(self) -> float:
        """Largest |difference|/sd over the compared parameters."""
        return max(abs(v) for v in self.z.values())

    def _label(self, name: str) -> str:
        if name == "zeta":
            return "ζ"
        return friction_symbol(self.friction_name, self.length_unit)

    @property
    def statement(self) -> str:
        """One plain sentence: agree or not, and by how much."""
        parts = []
        for name in self.parameters:
            rel = self.relative[name]
            percent = 100 * rel  # whole percent from 10 % on: "+200 %", not "+2e+02 %"
            rel_text = (
                ""
                if not math.isfinite(rel)
                else f"{percent:+.0f} %, "
                if abs(percent) >= 10
                else f"{percent:+.2g} %, "
            )
            shown = [  # each half in the digits its interval supports (a zero as zero)
                interval_text(getattr(h, name), *getattr(h, f"{name}_interval"))
                for h in (self.first, self.second)
            ]
            parts.append(
                f"{self._label(name)} {shown[0]} then {shown[1]} ({rel_text}{self.z[name]:+.1f} sd)"
            )
        held = "; friction held at the whole-decay value" if self.friction_mode == "fixed" else ""
        for label, half in (("first", self.first), ("second", self.second)):
            if half.at_bound:
                held += (
                    f"; the {label} half's {', '.join(half.at_bound)} on a bound (a one-sided "
                    "interval: the test is approximate)"
                )
            notes = [n for n in half.notes.split("; ") if n and not n.startswith("at a bound")]
            if notes:  # e.g. a Bayesian half whose sampler did not converge
                held += f"; the {label} half: {', '.join(notes)}"
        test = (
            f"χ² = {self.chi2:.3g} for {self.dof} dof, p = {self.p_value:.2g} "
            f"{'≥' if self.consistent else '<'} α = {self.alpha:.3g}"
        )
        if self.consistent:
            return f"the two halves agree ({', '.join(parts)}; {test}{held})"
        return (
            f"the two halves disagree by {self.max_abs_z:.1f} sd ({', '.join(parts)}; "
            f"{test}{held}): one constant law does not hold along this decay"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "consistent": self.consistent,
            "statement": self.statement,
            "parameters": list(self.parameters),
            "friction": self.friction_name,
            "friction_mode": self.friction_mode,
            "difference": dict(self.difference),
            "difference_sd": dict(self.difference_sd),
            "z": dict(self.z),
            "relative": {k: (v if math.isfinite(v) else None) for k, v in self.relative.items()},
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": self.p_value,
            "alpha": self.alpha,
            "method": self.method,
            "interval": self.interval_kind,
            "halves": [self.first.to_dict(), self.second.to_dict()],
        }


def _half_bounds(decay: EnergyDecay, min_oscillations: int) -> list[tuple[int, int, int, int]]:
    """(start, stop, first_peak, last_peak) of the two halves, cut at the middle turning point."""
    pos = peak_positions(decay)
    half_cycles = pos.size - 1
    middle = half_cycles // 2
    if middle < 2 * min_oscillations:
        raise RecordingError(
            f"the analysed decay holds {pos.size} turning points ({half_cycles / 2:g} "
            f"oscillations); the halves need {4 * min_oscillations + 1} (two halves of at "
            f"least {min_oscillations} oscillations each)"
        )
    return [
        (int(pos[0]), int(pos[middle]) + 1, 0, middle),
        (int(pos[middle]), decay.t.size, middle, half_cycles),
    ]


def _compare(
    first: WindowEstimate, second: WindowEstimate, names: tuple[str, ...]
) -> tuple[dict[str, float], dict[str, float], float]:
    idx = [("zeta", "mu").index(n) for n in names]
    d = np.array([getattr(second, n) - getattr(first, n) for n in names])
    cov = (first.covariance + second.covariance)[np.ix_(idx, idx)]
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    chi2 = float(d @ np.linalg.pinv(cov) @ d)
    return (
        dict(zip(names, d.tolist(), strict=True)),
        dict(zip(names, sd.tolist(), strict=True)),
        chi2,
    )


def split_halves(
    run: Any,
    *,
    fitter: WindowFitter | None = None,
    alpha: float = 0.05,
    skip_oscillations: int = 1,
    seed: int = 0,
    friction: Literal["auto", "fit", "fixed"] = "auto",
    progress: Callable[[str], None] | None = None,
) -> SplitHalves:
    """Fit the first and second halves of a decay apart and test that they agree.

    Parameters
    ----------
    run : Run, path or EnergyDecay
        The recording (an EnergyDecay only with the least-squares fitter).
    fitter : WindowFitter, optional
        :class:`~bayestribo.adequacy.windows.LeastSquaresWindows` (default) or
        :class:`~bayestribo.adequacy.windows.BayesianWindows`.
    alpha : float
        False-alarm rate of the test, in (0, 1).
    skip_oscillations : int
        Oscillations after the release left out.
    seed : int
        Seed of the noise propagation and of the Bayesian fits.
    friction : {"auto", "fit", "fixed"}
        Compare ζ and μ (``"fit"``), ζ with μ held at the whole-decay value
        (``"fixed"``), or choose (``"auto"``, see the module notes).
    progress : callable, optional
        Called with a one-line message before each half is fitted.

    Returns
    -------
    SplitHalves

    Raises
    ------
    RecordingError
        A bad ``alpha`` or ``friction``, a decay too short for two halves of
        :data:`MIN_HALF_OSCILLATIONS` oscillations (3 for the Bayesian fit), or a
        recording that cannot be analysed.
    """
    if not 0.0 < alpha < 1.0:
        raise RecordingError(f"alpha must be in (0, 1), got {alpha!r}")
    if friction not in ("auto", "fit", "fixed"):
        raise RecordingError(f"friction must be 'auto', 'fit' or 'fixed', got {friction!r}")
    fitter = LeastSquaresWindows() if fitter is None else fitter
    recording = None if isinstance(run, EnergyDecay) else _as_run(run)
    decay = analysed_decay(recording or run, skip_oscillations=skip_oscillations)
    loaded = decay.scaling.friction_defined
    ell = decay.scaling.length_scale
    context = WindowContext(decay=decay, run=recording, mu_scale=1.0 if loaded else ell, seed=seed)
    minimum = MIN_HALF_OSCILLATIONS if fitter.holds_friction else 3
    bounds = _half_bounds(decay, minimum)
    fitter.check(context, minimum)
    whole = whole_decay_fit(decay, seed=seed)
    resolved = "mu" not in whole.at_bound and whole.mu > 3.0 * whole.se("mu")
    mode = friction if friction != "auto" else ("fit" if resolved else "fixed")
    if not fitter.holds_friction:
        mode = "fit"

    def fit_halves(fixed_mu: float | None) -> list[WindowEstimate]:
        out = []
        for k, b in enumerate(bounds):
            if progress is not None:
                progress(f"split half {k + 1}/2 ({fitter.method})")
            out.append(_estimate(context, fitter, k, b, fixed_mu))
        return out

    halves = fit_halves(whole.mu if mode == "fixed" else None)
    if friction == "auto" and mode == "fit" and fitter.holds_friction:
        if any(not h.regular for h in halves):
            # ζ and μ cannot be told apart in a half: compare the equivalent damping.
            mode = "fixed"
            halves = fit_halves(whole.mu)
    names = ("zeta", "mu") if mode == "fit" else ("zeta",)
    first, second = halves
    diff, sd, chi2 = _compare(first, second, names)
    z = {n: (diff[n] / sd[n] if sd[n] > 0 else math.inf * np.sign(diff[n])) for n in names}
    relative = {}
    for n in names:
        mean = 0.5 * (getattr(first, n) + getattr(second, n))
        relative[n] = diff[n] / mean if mean != 0 else math.nan
    return SplitHalves(
        first=first,
        second=second,
        parameters=names,
        friction_name="mu_k" if loaded else "friction_displacement",
        friction_mode=mode,
        difference=diff,
        difference_sd=sd,
        z=z,
        relative=relative,
        chi2=chi2,
        dof=len(names),
        p_value=float(scipy.stats.chi2.sf(chi2, len(names))),
        alpha=alpha,
        method=fitter.method,
        interval_kind=fitter.interval_kind,
        length_unit="rad" if getattr(recording, "length_unit", None) == "rad" else "signal unit",
    )
