"""The autocorrelation time of a short chain: its known bias removed, and when it has settled.

emcee's windowed estimator (:func:`bayestribo.inference.sampling.autocorr_time`) on a
chain of L steps per walker is low by about k τ²/L, k = 2c + ½ for Sokal's window
constant c (5: k = 10.5). Each walker's own mean is taken out, which lowers every
autocorrelation by about τ/L (the variance of that mean over the walker's variance),
summed over the window's 2M ≈ 2cτ lags; the autocorrelation at lag t is taken over L
steps, not L − t, which lowers it by t/L of itself, about τ/(2L) of τ once summed for
a chain whose autocorrelation falls exponentially. So the estimate τ̂ ≈ τ (1 − kτ/L),
and :func:`debiased` gives τ̂ / (1 − kτ̂/L). On autoregressive chains of 32 walkers
with τ of 3, 8 and 15 steps, the raw estimate at L = 20-50 τ is 16-38 % low; the
debiased one is within 3 % of τ for L ≥ 15 τ (``tests/test_inference_tau_bias.py``
checks it at 2 and 10 standard errors).

A chain of a fast-mixing sampler meets the stopping rule's length (``autocorr_multiple``
τ and an effective sample size) while its raw τ still creeps up with L by this bias
alone: the rule that τ has *settled* (changed by less than 10 % since an earlier
check) then held the run for hundreds of steps more. Compared debiased, a chain in its
stationary distribution settles once the noise allows; a chain still on its way to
the posterior does not: its τ̂ grows in proportion to L (it spans the way, not the
posterior), and the debiasing multiplies two such estimates alike (kτ̂/L is the same
at both), so their ratio stays the ratio of the lengths. :func:`settle_span` sets how
far back the earlier estimate is taken: :data:`SETTLE_TAUS` autocorrelation times
(at least one check apart, at most the settings' ``settle_steps``), so a chain whose
τ̂ is a fixed share of its length is compared with one of at most half its length or
so, and a chain of a long τ keeps the 200 steps of the population's rule.

The sampler applies both where ``SamplerSettings.debias`` asks (the single-run fit)
and only while the independence move is in the mix
(:func:`bayestribo.inference.sampling.run_ensembles`): chains of the DE moves alone,
and the population's, are judged by the raw τ̂ settled over ``settle_steps``. Their
τ̂ at several hundred steps barely creeps, and on a ridge, where τ̂ is a large share of
the chain's length (kτ̂/L above :data:`MAX_SHARE`), the capped correction doubles an
estimate the rule already finds long and predicts a need past the step ceiling
(HarmOsc2's first half, ``benchmarks/README.md``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BIAS_FACTOR",
    "MAX_SHARE",
    "SETTLE_TAUS",
    "TauCheck",
    "debiased",
    "settle_span",
    "settled",
]

#: k of the estimator's bias τ̂ ≈ τ (1 − kτ/L): 2c + ½ with Sokal's window c = 5.
BIAS_FACTOR = 10.5
#: Largest kτ̂/L corrected: beyond it (a chain shorter than 2kτ̂ steps, fewer than
#: 21 τ̂) the correction is capped at a factor 2 and the estimate is not compared.
MAX_SHARE = 0.5
#: The span over which τ must have settled, in units of τ (see :func:`settle_span`).
SETTLE_TAUS = 30.0


def debiased(tau: NDArray, length: int) -> tuple[NDArray, bool]:
    """τ̂ corrected for the estimator's bias on a chain of ``length`` steps per walker.

    Parameters
    ----------
    tau : ndarray
        emcee's windowed estimates (c = 5) [steps].
    length : int
        Steps per walker of the chain they were estimated from.

    Returns
    -------
    tau : ndarray
        τ̂ / (1 − kτ̂/L) with k = :data:`BIAS_FACTOR` [steps]; the factor at most
        1 / (1 − :data:`MAX_SHARE`).
    comparable : bool
        Whether every kτ̂/L is below :data:`MAX_SHARE` (the chain long enough for the
        correction to hold: an estimate that is not is not used to judge settling).
    """
    tau = np.asarray(tau, dtype=float)
    share = BIAS_FACTOR * tau / max(int(length), 1)
    comparable = bool(np.all(share < MAX_SHARE))
    return tau / (1.0 - np.minimum(share, MAX_SHARE)), comparable


def settle_span(tau: NDArray, check_every: int, settle_steps: int) -> int:
    """Steps back to the estimate τ is compared with: :data:`SETTLE_TAUS` × the longest
    τ, at least ``check_every``, at most ``settle_steps``.

    Parameters
    ----------
    tau : ndarray
        The current (debiased) τ [steps].
    check_every, settle_steps : int
        The settings' steps between checks and longest span [steps].

    Returns
    -------
    int
        The span [steps].
    """
    return int(min(settle_steps, max(check_every, math.ceil(SETTLE_TAUS * np.max(tau)))))


@dataclass(frozen=True)
class TauCheck:
    """One check's estimate of τ.

    Attributes
    ----------
    steps : int
        Steps of the run at the check.
    raw : ndarray
        emcee's windowed estimate per parameter [steps].
    tau : ndarray
        The same debiased (:func:`debiased`) [steps].
    comparable : bool
        Whether the chain was long enough for the correction (:func:`debiased`).
    """

    steps: int
    raw: NDArray
    tau: NDArray
    comparable: bool


def settled(history: Sequence[TauCheck], now: TauCheck, span: int) -> bool:
    """Whether τ has settled since the last estimate ``span`` or more steps before: for
    every parameter, the raw estimate changed by less than 10 %, or the debiased one
    did (the raw one moved as its bias on a chain of that length says it does).

    A chain whose autocorrelation falls exponentially (a fast-mixing sampler's) shows
    the bias, and settles by the second rule; a chain of the package's DE moves at
    several hundred steps shows little of it (its raw τ̂ does not creep), and settles
    by the first. A chain on its way to the posterior settles by neither: its τ̂ grows
    with the length of the chain, raw and debiased alike.

    Parameters
    ----------
    history : sequence of TauCheck
        Earlier checks, oldest first.
    now : TauCheck
        This check.
    span : int
        :func:`settle_span` [steps].

    Returns
    -------
    bool
        False where no earlier estimate is far enough back, or where the one taken or
        this one is not comparable.
    """
    earlier = [c for c in history if c.steps <= now.steps - span]
    if not earlier or not earlier[-1].comparable or not now.comparable:
        return False
    then = earlier[-1]
    plain = np.abs(now.raw - then.raw) < 0.1 * now.raw
    biased = np.abs(now.tau - then.tau) < 0.1 * now.tau
    return bool(np.all(plain | biased))
