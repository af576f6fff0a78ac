"""A fit's answer against the truth, as the coverage benchmarks record it."""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np


def flags_of(caught: Iterable[warnings.WarningMessage], flags: Iterable[str]) -> list[str]:
    """Names of the caught warnings that are one of ``flags`` or a subclass of one
    (``ShortAnalysisWarning`` and ``CoarseSignalWarning`` are ``MisfitWarning``s: the
    command's exit status is 1)."""
    names = set(flags)
    return sorted(
        {
            w.category.__name__
            for w in caught
            if any(c.__name__ in names for c in w.category.__mro__)
        }
    )


def against_truth(result: Any, truth: Mapping[str, float]) -> dict[str, dict[str, Any]]:
    """Per quantity: the posterior mean and sd, z = (mean − truth)/sd, and whether the
    95 % interval holds the truth."""
    out: dict[str, dict[str, Any]] = {}
    for name, value in truth.items():
        draws = result.samples(name)
        lo, hi = result.interval(name, 0.95)
        sd = float(np.std(draws, ddof=1))
        out[name] = {
            "mean": float(np.mean(draws)),
            "sd": sd,
            "z": float((np.mean(draws) - value) / sd),
            "covered": bool(lo <= value <= hi),
        }
    return out
