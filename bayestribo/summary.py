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

__all__ = ["ParameterSummary", "check_prob", "interval_text", "probability_text", "summarize"]


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
        (low, high): equal-tailed credible interval for posterior samples (a static
        friction whose lower quantile lies on the step of its posterior that starts at
        its prior's end: from that end, :func:`bayestribo.inference.flatness.
        end_interval`), or the normal-approximation confidence interval of a classical
        estimate.
    prob : float
        Probability of ``interval``.
    kind : {"posterior", "normal", "bound"}
        How the interval was made; ``"bound"``: the quantity is not constrained by the
        data (its posterior is its prior's up to a bound), and the interval runs from the
        prior's lower end to the one-sided ``prob`` bound
        (:func:`bayestribo.inference.flatness.bound_interval`).
    """

    mean: float
    sd: float
    median: float
    interval: tuple[float, float]
    prob: float
    kind: Literal["posterior", "normal", "bound"] = "posterior"

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


#: Largest |value| of an interval that reaches zero and is still shown as a number: below
#: it every end is a numerical zero ("4.83e-30"), shown as ``< 1e-9``.
NUMERICAL_ZERO = 1e-9

#: Digits added at most beyond those of the half width, so that an asymmetric interval's
#: end does not print as its centre ("0.024251 [0.024251, 0.024300]").
_EXTRA_DIGITS = 4


def _fixed(value: float, decimals: int) -> str:
    text = f"{value:.{decimals}f}"
    return "0" if float(text) == 0.0 else text  # no "-0.000", no "0.00000" at a bound


def interval_text(center: float, low: float, high: float) -> str:
    """``center [low, high]`` with the digits the interval supports: two significant
    digits of its half width, more (at most four) where an end of an asymmetric interval
    would print as its centre, so that no two of the three numbers collapse onto each
    other at the precision shown ("0.024251 [0.02425, 0.024251]").

    A value indistinguishable from zero says so: an interval that starts at zero from a
    positive support (its lower end is zero at the precision shown, or below 5 % of its
    upper end) and holds its centre
    in its lower half, or whose mean lies beyond it (a long tail), is
    ``0 (at the bound) [0, high]``; such an interval whose upper
    end is below :data:`NUMERICAL_ZERO` (a numerical zero, "4.83e-30") is ``< 1e-9``.

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
    >>> interval_text(0.024251, 0.0242509, 0.0243)
    '0.0242510 [0.0242509, 0.0243000]'
    >>> interval_text(1.2e-30, 0.0, 3e-29)
    '< 1e-9'
    >>> interval_text(1.1e-4, 2e-9, 3.1e-4)
    '0 (at the bound) [0, 0.00031]'
    >>> interval_text(2.5e-07, 6.9e-09, 9.0e-07)
    '0 (at the bound) [0, 9.0e-07]'
    >>> interval_text(1.5158e-07, 1.2e-07, 1.8e-07)
    '1.52e-07 [1.20e-07, 1.80e-07]'
    >>> interval_text(5.2e-27, -6.9e-04, 6.9e-04)
    '0 [-0.00069, 0.00069]'
    """
    center, low, high = float(center), float(low), float(high)
    if not all(math.isfinite(v) for v in (center, low, high)):
        return "–" if not math.isfinite(center) else f"{center:.3g}"
    half = 0.5 * (high - low)
    if not half > 0:
        return f"{center:.6g} [{low:.6g}, {high:.6g}]"
    decimals = 1 - math.floor(math.log10(half))  # two significant digits of the half width
    quantum = 10.0**-decimals
    # the lower end is zero at the precision shown, or within 5 % of the upper end (a
    # posterior spread over decades down to zero: ζ = 2.5e-07 [6.9e-09, 9.0e-07])
    reaches_zero = (
        -NUMERICAL_ZERO <= low and high > 0 and (low < 0.5 * quantum or low < 0.05 * high)
    )
    if reaches_zero and high < NUMERICAL_ZERO:
        return f"< {NUMERICAL_ZERO:.0e}".replace("e-0", "e-")
    if reaches_zero and low >= -1e-300 and (abs(center) < half or center > high):
        return f"0 (at the bound) [0, {_number(high, max(decimals, 0), high)}]"
    for extra in range(_EXTRA_DIGITS + 1):
        # one notation for the three, from the largest magnitude: a centre at a numerical
        # zero in an interval across zero is "0 [-0.00069, 0.00069]", not "5.2e-27 [...]"
        scale = max(abs(center), abs(low), abs(high))
        shown = [_number(v, decimals + extra, scale) for v in (center, low, high)]
        if shown[0] not in shown[1:] or low == center or high == center:
            break
    return f"{shown[0]} [{shown[1]}, {shown[2]}]"


def probability_text(p: float | None) -> str:
    """A probability in three decimals, ``< 0.001`` and ``> 0.999`` at its ends (a sign
    probability of 1 from a few thousand draws is not certainty: "P = 1.000" is not said).

    Examples
    --------
    >>> probability_text(1.0), probability_text(0.4567), probability_text(0.0)
    ('> 0.999', '0.457', '< 0.001')
    """
    if p is None or not math.isfinite(p):
        return "–"
    if p < 1e-3:
        return "< 0.001"
    if p > 0.999:
        return "> 0.999"
    return f"{p:.3f}"


def _number(value: float, decimals: int, scale: float) -> str:
    """``value`` to ``decimals`` decimals, in scientific notation (the exponent of
    ``scale``) for magnitudes of 1e5 and more or below 1e-4."""
    big = abs(scale) >= 1e5 or (0 < abs(scale) < 1e-4)
    if not big:
        return _fixed(value, max(decimals, 0))
    exponent = math.floor(math.log10(abs(scale)))
    digits = max(1, exponent + decimals)  # decimals of the mantissa
    return f"{value:.{digits}e}" if value != 0 else "0"
