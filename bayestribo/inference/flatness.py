"""Is a posterior only its prior? The flat-posterior test behind a bound.

Some quantities are not measured by a record: μ_s of a run that stops at a turning
point inside a wide band is bounded above by the stop, and its posterior is otherwise
the prior's shape. Quoting ``0.056 [0.030, 0.082]`` for it reads as a measurement. The
test here compares the draws of the sampled parameter that sets a quantity's spread
with that parameter's prior restricted to the range the draws cover (the data may rule
part of the prior out): a Kolmogorov–Smirnov distance of at most :data:`FLAT_KS` means
the data set a range, not a value, and the quantity is shown as a bound by the fit's
table and the reports alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["FLAT_KS", "SPREAD_OF", "prior_flatness"]

#: A posterior whose Kolmogorov–Smirnov distance to its prior, restricted to the range the
#: draws cover, is at most this is flat over its prior there: the data set only the range
#: (a bound), not a value. A normal posterior is about 0.2 from the uniform over its
#: draws' range; flat draws about 1/√(effective sample size).
FLAT_KS = 0.1

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
