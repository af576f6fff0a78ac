"""Is a trend a straight line, or does it have a threshold?

Rigaud et al. (2010, Fig. 10) found μ_k constant with the lubricant's viscosity down to
about 357 mm²/s and rising below it: a threshold, which one slope against viscosity
summarises wrongly. :func:`threshold_test` fits the group means of a series against a
covariate twice by weighted least squares (weights from each mean's interval): a
straight line (2 parameters), and a *hinge*, constant on one side of a threshold and
linear on the other, continuous there (3 parameters: the level, the slope and the
threshold, scanned between the covariate's values). The two are compared by Akaike's
criterion AIC = χ² + 2k; the hinge is said to fit better where its AIC is lower by more
than :data:`AIC_MARGIN`. The straight line's own χ² says whether it fits at all.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["AIC_MARGIN", "MISFIT_P", "ThresholdFit", "threshold_test"]

#: Lower AIC by more than this and the hinge (a threshold) fits better than the line.
AIC_MARGIN = 2.0

#: Below this p-value of its χ² the straight line does not fit the group means.
MISFIT_P = 0.01


@dataclass(frozen=True)
class ThresholdFit:
    """The straight line and the best hinge fitted to group means.

    Attributes
    ----------
    n : int
        Number of group means.
    linear_chi2, hinge_chi2 : float
        Weighted residual sums of squares of the two fits.
    linear_p : float
        Probability of a χ² at least ``linear_chi2`` for ``n - 2`` degrees of freedom
        (NaN with two means or fewer).
    threshold : float
        The hinge's threshold [the covariate's unit].
    flat_above : bool
        True where the hinge is constant above the threshold, False below it.
    """

    n: int
    linear_chi2: float
    linear_p: float
    hinge_chi2: float
    threshold: float
    flat_above: bool

    @property
    def aic_difference(self) -> float:
        """AIC of the line minus the hinge's (positive: the hinge fits better)."""
        return (self.linear_chi2 + 4.0) - (self.hinge_chi2 + 6.0)

    @property
    def has_threshold(self) -> bool:
        """The hinge fits better than the line by more than :data:`AIC_MARGIN`."""
        return self.aic_difference > AIC_MARGIN

    @property
    def linear_fits(self) -> bool:
        """The line's χ² is within what the means' intervals allow (p ≥ :data:`MISFIT_P`)."""
        return not (self.linear_p < MISFIT_P)

    def text(self, unit: str = "") -> str:
        """The comparison in one phrase, with its numbers.

        Examples
        --------
        >>> ThresholdFit(6, 40.0, 1e-8, 2.0, 357.0, True).text("mm²/s")[:44]
        'a threshold: constant above 357 mm²/s, linea'
        """
        where = f"{self.threshold:.3g}" + (f" {unit}" if unit else "")
        line = f"χ² = {self.linear_chi2:.3g} for {self.n - 2} dof, p = {self.linear_p:.2g}"
        if self.has_threshold:
            side = "above" if self.flat_above else "below"
            return (
                f"a threshold: constant {side} {where}, linear beyond (the straight line: "
                f"{line}; AIC lower by {self.aic_difference:.3g} with the threshold)"
            )
        fits = "fits" if self.linear_fits else "does not fit, nor does a threshold"
        return f"the straight line {fits} ({line}; a threshold at {where} gains no more)"


def _wls(design: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    """χ² of the weighted least-squares fit of ``y`` on the columns of ``design``."""
    a = design * np.sqrt(w)[:, None]
    b = y * np.sqrt(w)
    coef, *_ = np.linalg.lstsq(a, b, rcond=None)
    return float(np.sum((b - a @ coef) ** 2))


def threshold_test(x: ArrayLike, y: ArrayLike, sd: ArrayLike) -> ThresholdFit:
    """Fit group means ``y`` ± ``sd`` against ``x`` by a line and by a hinge.

    Parameters
    ----------
    x : array_like
        The covariate of each group (a viscosity [mm²/s], a load [N]).
    y : array_like
        Each group's mean (a posterior median), in the quantity's unit.
    sd : array_like
        Each mean's standard error (its 95 % interval's half width over 1.96), > 0.

    Returns
    -------
    ThresholdFit

    Raises
    ------
    ValueError
        If the three do not have one length, hold a non-finite value, a ``sd`` is not
        positive, or ``x`` has fewer than four distinct values (a hinge needs two on
        each side).
    """
    x, y, sd = (np.asarray(v, dtype=float).ravel() for v in (x, y, sd))
    if not (x.size == y.size == sd.size):
        raise ValueError(f"x, y, sd: expected one length, got {x.size}, {y.size}, {sd.size}")
    if not all(np.all(np.isfinite(v)) for v in (x, y, sd)) or np.any(sd <= 0):
        raise ValueError("x, y, sd: expected finite values and sd > 0")
    levels = np.unique(x)
    if levels.size < 4:
        raise ValueError(f"x: expected at least 4 distinct values, got {levels.size}")
    w = 1.0 / sd**2
    ones = np.ones_like(x)
    linear = _wls(np.column_stack([ones, x]), y, w)
    best = (math.inf, float("nan"), True)
    # thresholds between the second and the second-to-last level: two groups each side
    for lo, hi in itertools.pairwise(levels[1:-1]):
        for t in np.linspace(lo, hi, 21):
            for flat_above in (True, False):
                arm = np.maximum(t - x, 0.0) if flat_above else np.maximum(x - t, 0.0)
                chi2 = _wls(np.column_stack([ones, arm]), y, w)
                if chi2 < best[0]:
                    best = (chi2, float(t), flat_above)
    from scipy.stats import chi2 as chi2_dist

    dof = x.size - 2
    p = float(chi2_dist.sf(linear, dof)) if dof > 0 else float("nan")
    return ThresholdFit(x.size, linear, p, best[0], best[1], best[2])
