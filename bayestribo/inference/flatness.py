"""Is a posterior only its prior? The flat-posterior test behind a bound.

Some quantities are not measured by a record: μ_s of a run that stops at a turning
point inside a wide band is bounded above by the stop, and its posterior is otherwise
the prior's shape. Quoting ``0.056 [0.030, 0.082]`` for it reads as a measurement. The
test here compares the draws of the sampled parameter that sets a quantity's spread
with that parameter's prior restricted to the range the draws cover (the data may rule
part of the prior out): a Kolmogorov–Smirnov distance of at most :data:`FLAT_KS` means
the data set a range, not a value; so does a static friction whose density at its
prior's lower end is at least half its highest (:func:`end_density`: a soft upper edge,
the lower side the prior's). The quantity is then shown as a bound by the fit's
table and the reports alike, and every machine-readable summary says the same
(:func:`bound_interval`: its interval runs from the lowest value the prior allows to the
one-sided bound, ``kind`` ``"bound"``), so that no central interval of a prior excludes a
truth at the prior's end (μ_s/μ_k = 1 of a record that never stops).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "END_DENSITY",
    "FLAT_KS",
    "SPREAD_OF",
    "bound_interval",
    "end_density",
    "end_interval",
    "is_bound",
    "is_flat",
    "prior_end",
    "prior_end_interval",
    "prior_flatness",
]

#: A posterior whose Kolmogorov–Smirnov distance to its prior, restricted to the range the
#: draws cover, is at most this is flat over its prior there: the data set only the range
#: (a bound), not a value. A normal posterior is about 0.2 from the uniform over its
#: draws' range; flat draws about 1/√(effective sample size).
FLAT_KS = 0.1

#: A static friction whose density at its prior's lower end (μ_s/μ_k = 1) is at least
#: this share of its highest is bounded by the data from above only (:func:`is_bound`):
#: a record that never sticks, where a turning point that did not stick bounds μ_s and
#: the last ones, too small to tell a stick from one more small half cycle, leave a soft
#: edge that is not flat (a torsion wheel's record: 0.67, μ_s/μ_k printed 2.8 [1.1, 4.4]
#: where only < 4.2 was measured).
END_DENSITY = 0.5
#: The static friction's lower quantile lies on the step that starts at its prior's end
#: (:func:`end_interval`) when the draws' density from that end to the quantile is at least
#: this share of their density over as wide a span just above the quantile: no rise at
#: the quantile, one flat step (a density rising from the end as (x - 1) gives 1/3).
SAME_STEP = 0.5

#: Bins of :func:`end_density`.
_END_BINS = 10

#: The draws reach the prior's lower end when their lowest is within this share of their
#: range from it: the interval of a bound then starts at the prior's end itself (μ_s/μ_k
#: at 1), not at the lowest draw above it.
_REACH = 0.05

#: Reported quantities whose spread is set by another sampled parameter: μ_s = (μ_s/μ_k)
#: μ_k, and the static friction's displacement and torque with it.
SPREAD_OF = {
    "mu_s": "mu_s_ratio",
    "static_friction_displacement": "mu_s_ratio",
    "static_friction_torque": "mu_s_ratio",
}


def prior_flatness(result: Any, name: str) -> float | None:
    """How far the posterior of ``name`` is from flat over its prior: the
    Kolmogorov–Smirnov distance between the draws of the sampled parameter that sets its
    spread (μ_s: μ_s/μ_k) and its prior restricted to the range the draws cover (the data
    may rule part of the prior out, as the stop of the motion bounds μ_s from above).
    None where the quantity has no prior of its own (a physical quantity derived from
    several).

    Parameters
    ----------
    result : FitResult
        A fit (its ``priors`` and ``samples``).
    name : str
        The quantity.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace as R
    >>> from bayestribo.inference.priors import PriorSet, Uniform
    >>> draws = np.random.default_rng(0).uniform(1.0, 2.9, 4000)  # flat up to 2.9
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda n: draws)
    >>> prior_flatness(fit, "mu_s") < FLAT_KS
    True
    """
    sampled = SPREAD_OF.get(name, name)
    try:
        prior = result.priors[sampled]
        draws = np.sort(np.asarray(result.samples(sampled), dtype=float).ravel())
    except (KeyError, ValueError, AttributeError):
        return None
    if draws.size < 2 or not draws[-1] > draws[0]:
        return None
    grid = np.linspace(draws[0], draws[-1], 1025)
    density = np.exp(np.asarray(prior.logpdf(grid), dtype=float))
    steps = 0.5 * (density[1:] + density[:-1]) * np.diff(grid)
    cdf = np.concatenate([[0.0], np.cumsum(steps)])
    if not cdf[-1] > 0:
        return None
    expected = np.interp(draws, grid, cdf / cdf[-1])
    ranks = np.arange(1, draws.size + 1) / draws.size
    return float(max(np.max(ranks - expected), np.max(expected - (ranks - 1 / draws.size))))


def is_flat(distance: float | None) -> bool:
    """Whether a :func:`prior_flatness` distance says the data set a range, not a value."""
    return distance is not None and distance <= FLAT_KS


def prior_end(result: Any, name: str) -> float | None:
    """The lower end of the prior of the parameter that sets the spread of ``name``
    (:data:`SPREAD_OF`), where that parameter's draws reach it (their lowest within
    :data:`_REACH` of their range from it); None where they do not (the data rule the
    prior's lower part out) or the prior has no finite lower end.

    Parameters
    ----------
    result : FitResult
        A fit (its ``priors`` and ``samples``).
    name : str
        The quantity.

    Returns
    -------
    float or None
        In the sampled parameter's unit.
    """
    sampled = SPREAD_OF.get(name, name)
    try:
        end = getattr(result.priors[sampled], "low", None)
        spread = np.asarray(result.samples(sampled), dtype=float).ravel()
    except (KeyError, ValueError, AttributeError):
        return None
    if end is None or not np.isfinite(end) or spread.size < 2:
        return None
    lowest = float(spread.min())
    return float(end) if lowest - end <= _REACH * float(spread.max() - lowest) else None


def is_bound(result: Any, name: str) -> bool:
    """Whether ``name`` is not constrained by the data: its posterior is flat over its
    prior (:func:`prior_flatness` at most :data:`FLAT_KS`) from the prior's lower end
    (:func:`prior_end`) up to a bound; for the static friction (μ_s/μ_k and what it
    sets), also where its density at the prior's lower end is at least
    :data:`END_DENSITY` of its highest (:func:`end_density`): the data bound it from
    above and leave its lower side to the prior. A posterior flat between two ends the
    data set (a stop that bounds μ_s/μ_k from both sides) is a range the data measured,
    not a bound."""
    if prior_end(result, name) is None:
        return False
    if is_flat(prior_flatness(result, name)):
        return True
    if SPREAD_OF.get(name, name) != "mu_s_ratio":
        return False
    share = end_density(result, name)
    return share is not None and share >= END_DENSITY


def end_density(result: Any, name: str) -> float | None:
    """The density of the draws of the parameter that sets ``name``'s spread at its
    prior's lower end, over their highest: the first of :data:`_END_BINS` equal bins
    from that end to the draws' 99th percentile against the fullest (None where the
    prior has no lower end the draws reach).

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace as R
    >>> from bayestribo.inference.priors import PriorSet, Uniform
    >>> rng = np.random.default_rng(0)
    >>> falling = 1.0 + 3.5 * np.sqrt(rng.uniform(0.0, 1.0, 4000))  # rising from the end
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda n: falling)
    >>> round(end_density(fit, "mu_s_ratio"), 1)
    0.1
    """
    start = prior_end(result, name)
    if start is None:
        return None
    sampled = SPREAD_OF.get(name, name)
    draws = np.asarray(result.samples(sampled), dtype=float).ravel()
    top = float(np.quantile(draws, 0.99))
    if not top > start:
        return None
    counts, _ = np.histogram(draws, bins=_END_BINS, range=(start, top))
    return float(counts[0] / counts.max()) if counts.max() > 0 else None


def bound_interval(
    result: Any, name: str, draws: ArrayLike, prob: float = 0.95
) -> tuple[float, float] | None:
    """The interval of probability ``prob`` of a quantity the data do not constrain
    (:func:`is_bound`), None for one they do.

    Such a posterior is its prior's up to a bound: the interval is one-sided, from the
    prior's lower end (:func:`prior_end`) to the ``prob`` quantile of the draws (the
    bound the fit's table prints, ``< high``); for a quantity that is the sampled
    parameter times another (μ_s = (μ_s/μ_k) μ_k, the static friction's displacement
    and torque), its lower end is the lower ``(1 - prob) / 2`` quantile of the other at
    the prior's end. A central interval would exclude the prior's end, where the truth
    of a record that never sticks lies (μ_s/μ_k = 1).

    Parameters
    ----------
    result : FitResult
        A fit (its ``priors`` and ``samples``).
    name : str
        The quantity.
    draws : array_like
        Its draws (any shape), in the order of the sampled parameter's.
    prob : float
        Probability of the interval.

    Returns
    -------
    (float, float) or None
        (low, high) in the quantity's unit.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace as R
    >>> from bayestribo.inference.priors import PriorSet, Uniform
    >>> draws = np.random.default_rng(0).uniform(1.0, 2.9, 4000)  # flat up to 2.9
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda n: draws)
    >>> low, high = bound_interval(fit, "mu_s_ratio", draws)
    >>> float(low), round(float(high), 1)
    (1.0, 2.8)
    >>> ranged = np.random.default_rng(0).uniform(18.5, 21.0, 4000)  # the data set both ends
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 40.0)}), samples=lambda n: ranged)
    >>> bound_interval(fit, "mu_s_ratio", ranged) is None
    True
    """
    if not is_bound(result, name):
        return None
    start = prior_end(result, name)
    assert start is not None  # is_bound
    x = np.asarray(draws, dtype=float).ravel()
    return _lower_end(result, name, x, start, (1 - prob) / 2), float(np.quantile(x, prob))


def _lower_end(result: Any, name: str, x: NDArray, start: float, tail: float) -> float:
    """The lower end of an interval from the prior's end ``start`` of the parameter that
    sets ``name``'s spread: ``start`` itself for that parameter; for a quantity it
    multiplies (μ_s = (μ_s/μ_k) μ_k), the lower ``tail`` quantile of the quantity at the
    prior's end, ``x`` its draws."""
    sampled = SPREAD_OF.get(name, name)
    if sampled == name:
        return start
    spread = np.asarray(result.samples(sampled), dtype=float).ravel()
    if spread.shape != x.shape or not np.all(spread > 0):
        return float(x.min())
    return float(np.quantile(x * (start / spread), tail))


def end_interval(
    result: Any, name: str, draws: ArrayLike, prob: float = 0.95
) -> tuple[float, float] | None:
    """The interval of probability at least ``prob`` of a static friction whose lower
    quantile lies on the step of its posterior that starts at its prior's lower end;
    None otherwise (and for every other quantity).

    The likelihood of μ_s/μ_k is a staircase: the model's motion, and so Π, changes with
    it only where it crosses the stop ratio |Y_n|/μ(|Y_n|) of a turning point, and is
    flat in between (:func:`bayestribo.inference.surrogate.stop_ratios`). Where the record
    cannot tell at which of its last small turning points the oscillator stuck, several
    steps hold posterior mass, the lowest one starting at the prior's end (μ_s/μ_k = 1);
    an equal-tailed interval then cuts that step at its lower quantile, and excludes
    values the data support as well as the quantile itself, the prior's end among them
    (a 20 Hz accelerometer record whose truth is 1: 3.3 [1.2, 6.0], its density at 1 a
    third of its highest). The step is found in the draws: their density from the prior's
    end to the lower quantile is at least :data:`SAME_STEP` of theirs over as wide a span
    above it (no rise between). The interval then runs from the prior's end (as
    :func:`bound_interval`'s lower end, for a quantity the sampled parameter sets) to the
    upper ``(1 + prob) / 2`` quantile: its probability is ``prob`` and the lower tail's.
    A quantity the data do not constrain at all (:func:`is_bound`) is
    :func:`bound_interval`'s.

    Parameters
    ----------
    result : FitResult
        A fit (its ``priors`` and ``samples``).
    name : str
        The quantity.
    draws : array_like
        Its draws (any shape), in the order of the sampled parameter's.
    prob : float
        Probability of the equal-tailed interval extended.

    Returns
    -------
    (float, float) or None
        (low, high) in the quantity's unit.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace as R
    >>> from bayestribo.inference.priors import PriorSet, Uniform
    >>> rng = np.random.default_rng(0)
    >>> steps = np.concatenate([rng.uniform(1.0, 2.0, 600), rng.uniform(2.0, 4.3, 3400)])
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda n: steps)
    >>> low, high = end_interval(fit, "mu_s_ratio", steps)
    >>> float(low), round(float(high), 1)
    (1.0, 4.2)
    >>> rising = 1.0 + 3.5 * np.sqrt(rng.uniform(0.0, 1.0, 4000))  # density grows from 1
    >>> fit = R(priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda n: rising)
    >>> end_interval(fit, "mu_s_ratio", rising) is None
    True
    """
    sampled = SPREAD_OF.get(name, name)
    if sampled != "mu_s_ratio" or is_bound(result, name):
        return None
    start = prior_end(result, name)
    if start is None:
        return None
    spread = np.asarray(result.samples(sampled), dtype=float).ravel()
    tail = (1.0 - prob) / 2.0
    low = float(np.quantile(spread, tail))
    width = low - start
    if not width > 0.0:
        return None
    below = np.count_nonzero(spread <= low)
    above = np.count_nonzero((spread > low) & (spread <= low + width))
    if below < SAME_STEP * above:
        return None
    x = np.asarray(draws, dtype=float).ravel()
    return _lower_end(result, name, x, start, tail), float(np.quantile(x, 1.0 - tail))


def prior_end_interval(
    result: Any, name: str, draws: ArrayLike, prob: float = 0.95
) -> tuple[tuple[float, float], str] | None:
    """The interval of ``name`` that runs from its prior's lower end, and its kind:
    :func:`bound_interval`'s (``"bound"``) for a quantity the data do not constrain,
    else :func:`end_interval`'s (``"posterior"``) for a static friction whose lowest step
    starts there; None where the equal-tailed interval stands."""
    bound = bound_interval(result, name, draws, prob)
    if bound is not None:
        return bound, "bound"
    reach = end_interval(result, name, draws, prob)
    return None if reach is None else (reach, "posterior")
