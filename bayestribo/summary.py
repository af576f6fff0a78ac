"""One summary vocabulary for every result: :class:`ParameterSummary`.

Every result type of the package (a single-run fit, a population, a trend, a
classical estimate, a window of an adequacy check) summarises a quantity with the same
fields: mean, standard deviation, median, an interval and the probability it holds.
Posterior summaries give an equal-tailed credible interval of the samples; classical
estimates give their normal-approximation confidence interval (mean ± z·sd, median =
mean), said in :attr:`ParameterSummary.kind`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from bayestribo.errors import BayestriboError

__all__ = ["ParameterSummary", "check_prob", "interval_text", "summarize"]


def check_prob(prob: float) -> float:
    """Check a credible-interval probability in (0, 1) and return it as a float.

    Raises
    ------
    BayestriboError
        If ``prob`` is not a real number strictly between 0 and 1.
    """
    if isinstance(prob, bool) or not (isinstance(prob, int | float) and 0 < prob < 1):
        raise BayestriboError(f"prob: expected a number in (0, 1), got {prob!r}")
    return float(prob)


@dataclass(frozen=True)
class ParameterSummary:
    """Summary of one quantity: mean, sd, median and an interval of probability ``prob``.

    Attributes
    ----------
    mean, sd, median : float
        In the quantity's own unit.
    interval : tuple of float
        (low, high): equal-tailed credible interval for posterior samples, or the
        normal-approximation confidence interval of a classical estimate.
    prob : float
        Probability of ``interval``.
    kind : {"posterior", "normal"}
        How the interval was made.
    """

    mean: float
    sd: float
    median: float
    interval: tuple[float, float]
    prob: float
    kind: Literal["posterior", "normal"] = "posterior"

    @classmethod
    def from_samples(cls, samples: ArrayLike, prob: float = 0.95) -> ParameterSummary:
        """Summarise posterior samples (any shape, flattened; NaN is an error).

        Raises
        ------
        BayestriboError
            If ``samples`` is empty or holds a non-finite value, or ``prob`` is not in (0, 1).
        """
        prob = check_prob(prob)
        x = np.asarray(samples, dtype=float).ravel()
        if x.size == 0:
            raise BayestriboError("samples: expected at least one sample, got none")
        if not np.all(np.isfinite(x)):
            raise BayestriboError(
                f"samples: expected finite values, got {int(np.sum(~np.isfinite(x)))} "
                "NaN or infinite"
            )
        lo, med, hi = np.quantile(x, [(1 - prob) / 2, 0.5, (1 + prob) / 2])
        sd = float(x.std(ddof=1)) if x.size > 1 else float("nan")
        return cls(float(x.mean()), sd, float(med), (float(lo), float(hi)), prob, "posterior")

    @classmethod
    def from_normal(cls, mean: float, sd: float, prob: float = 0.95) -> ParameterSummary:
        """Summarise a point estimate with a standard error (normal approximation).

        A NaN ``sd`` (no error available) gives a NaN interval.
        """
        prob = check_prob(prob)
        mean, sd = float(mean), float(sd)
        if not math.isnan(sd) and sd < 0:
            raise BayestriboError(f"sd: expected a non-negative standard error, got {sd!r}")
        import scipy.stats  # on first use: scipy.stats takes longer to import than a fit

        half = float(scipy.stats.norm.ppf(0.5 + prob / 2)) * sd
        return cls(mean, sd, mean, (mean - half, mean + half), prob, "normal")

    @property
    def low(self) -> float:
        """Lower end of :attr:`interval`."""
        return self.interval[0]

    @property
    def high(self) -> float:
        """Upper end of :attr:`interval`."""
        return self.interval[1]

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies inside the closed interval."""
        return self.interval[0] <= value <= self.interval[1]

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict: ``mean, sd, median, interval [low, high], prob, kind``."""
        d = asdict(self)
        d["interval"] = [float(v) for v in self.interval]
        return d

    def __str__(self) -> str:
        pct = f"{100 * self.prob:g} %"
        return (
            f"{self.mean:.6g} ± {self.sd:.3g}  [{self.interval[0]:.6g}, {self.interval[1]:.6g}]"
            f" ({pct})"
        )


def summarize(samples: ArrayLike, prob: float = 0.95) -> dict[str, Any]:
    """Plain-dict form of :meth:`ParameterSummary.from_samples` (JSON-ready).

    Returns
    -------
    dict
        ``{"mean", "sd", "median", "interval": [low, high], "prob", "kind"}``.
    """
    return ParameterSummary.from_samples(samples, prob).to_dict()


def interval_text(center: float, low: float, high: float) -> str:
    """``center [low, high]`` with the digits the interval supports: two significant
    digits of its half width, so that the ends never collapse onto each other at the
    precision shown ("0.024251 [0.02425, 0.024251]"); an interval that reaches zero
    from a positive support says so.

    Parameters
    ----------
    center, low, high : float
        A point value (mean or median) and the ends of its interval, in one unit.

    Returns
    -------
    str

    Examples
    --------
    >>> interval_text(0.0236012, 0.0236003, 0.0236021)
    '0.02360120 [0.02360030, 0.02360210]'
    >>> interval_text(1.2e-30, 0.0, 3e-29)
    '< 3e-29 (at zero)'
    """
    center, low, high = float(center), float(low), float(high)
    half = 0.5 * (high - low)
    if low <= 0.0 <= high and low >= -1e-300 and abs(center) < half:
        return f"< {high:.2g} (at zero)"
    if not (half > 0 and math.isfinite(half)):
        return f"{center:.6g} [{low:.6g}, {high:.6g}]"
    decimals = max(0, 1 - math.floor(math.log10(half)))
    if abs(center) >= 1e5 or (abs(center) < 1e-4 and center != 0):
        digits = max(2, math.floor(math.log10(abs(center))) - math.floor(math.log10(half)) + 2)
        return f"{center:.{digits}g} [{low:.{digits}g}, {high:.{digits}g}]"
    return f"{center:.{decimals}f} [{low:.{decimals}f}, {high:.{decimals}f}]"
