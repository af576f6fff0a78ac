"""Posterior summaries of sample arrays: mean, sd, median, equal-tailed interval."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from bayestribo.errors import BayestriboError

__all__ = ["check_prob", "summarize"]


def check_prob(prob: float) -> float:
    """Check a credible-interval probability in (0, 1)."""
    if not (isinstance(prob, int | float) and 0 < prob < 1):
        raise BayestriboError(f"prob: expected a number in (0, 1), got {prob!r}")
    return float(prob)


def summarize(samples: ArrayLike, prob: float = 0.95) -> dict[str, Any]:
    """Mean, sd, median and the equal-tailed ``prob`` interval of 1-D samples.

    Returns
    -------
    dict
        ``{"mean", "sd", "median", "interval": [low, high], "prob"}`` (plain floats).
    """
    prob = check_prob(prob)
    x = np.asarray(samples, dtype=float).ravel()
    lo, med, hi = np.quantile(x, [(1 - prob) / 2, 0.5, (1 + prob) / 2])
    return {
        "mean": float(x.mean()),
        "sd": float(x.std(ddof=1)),
        "median": float(med),
        "interval": [float(lo), float(hi)],
        "prob": prob,
    }
