"""Ensemble MCMC with emcee: run length from the autocorrelation time, honest diagnostics.

* Several **independent ensembles** (default 2) run side by side, each with its own
  seed spawned from the user's seed (:class:`numpy.random.SeedSequence`), so that the
  Gelman-Rubin R-hat compares independent chains (R-hat over the walkers of one
  ensemble is not valid: they are coupled by the moves).
* Every ``check_every`` steps the integrated autocorrelation time τ of each parameter
  is estimated per ensemble (:func:`autocorr_time`, emcee's estimator) and, where
  ``SamplerSettings.debias`` asks and the independence move is in the mix (the
  single-run fit), corrected for that estimator's known bias on a chain of L steps,
  low by about 10.5 τ/L of itself (:func:`bayestribo.inference.tau_bias.debiased`);
  burn-in is 2τ;
  the run stops once every ensemble has at least ``autocorr_multiple`` × τ steps after
  burn-in and, where ``min_ess`` is given, an effective sample size of at least
  ``min_ess`` (:meth:`SamplerSettings.required_multiple`: the larger of the two in
  units of τ), τ has settled (changed by less than 10 % since the check
  ``settle_steps`` or more steps before; with the debiased τ, the raw or the debiased
  estimate since the check 30 τ, at most ``settle_steps``, before:
  :func:`bayestribo.inference.tau_bias.settled`, which says why a chain still on its
  way to the posterior does not settle) and the between-ensemble R-hat is below
  ``rhat_max`` for every parameter, or at ``max_steps``. Checking often (every 50
  steps by default) stops the run near the first step that meets the rule; with the
  debiased τ, the check a span before the earliest stop is never skipped. Past 2000
  steps (at the defaults) the checks come every 5 % of the steps so far
  (:func:`check_spacing`): a long run's checks cost in proportion to its length, not
  to its square.
  The single-run fit asks for an effective sample size of :data:`FIT_MIN_ESS` (1000)
  and at least :data:`FIT_AUTOCORR_MULTIPLE` (20) τ, keeps at most
  :data:`FIT_MAX_DRAWS` draws (``SamplerSettings.max_draws``,
  :mod:`bayestribo.inference.thinning`: the effective sample size reported is that of
  the draws kept) and mixes in the independence move (:data:`FIT_INDEPENDENCE`, taken
  out past :data:`FIT_INDEPENDENCE_LIMIT`, τ debiased while it is in); the settings'
  defaults (50 τ, no ESS target, every ⌈τ⌉-th step kept, τ raw) are the population's.
* Where R-hat fails at a check because the kept draws begin with the walkers' way
  from their start to the posterior (a transient the burn-in of 2τ did not cover:
  :func:`bayestribo.inference.modes.transient_steps`), the burn-in is extended past it
  and the run stops there when what is left still meets the rule.
* Samples are thinned by ⌈τ⌉ (more where ``max_draws`` asks); the effective sample
  size of a parameter is (steps after burn-in × walkers × ensembles)/τ, or the draws'
  own where they are thinned more (:func:`~bayestribo.inference.thinning.thinned_ess`).
* A run that does not meet the criteria is reported as not converged, never silently.

* A NaN log-probability is an error naming the parameters (a broken model or input),
  never a silent −inf (:class:`NaNLogProbabilityError`, a
  :class:`~bayestribo.errors.BayestriboError` and a ``FloatingPointError`` like the
  single-run posterior's own NaN error); −inf stays what it means: outside the support.

Moves (:func:`default_moves`): a mixture of differential-evolution moves (emcee's
``DEMove`` 80 %, the snooker move 20 %: ter Braak & Vrugt's, as
:class:`~bayestribo.inference.moves.DESnookerMove`, since emcee 3.1.6's is not a valid
Metropolis-Hastings move), which mix faster than the default stretch
move on the narrow, correlated posteriors of this problem (the single-run fit and
the population hyperparameters alike).

Two ways to run the ensembles (``SamplerSettings.moves``):

* ``"grouped"`` (the default where the walkers allow it: a multiple of 4 per
  ensemble): the ensembles are blocks of walkers of **one** emcee sampler, updated by
  the same DE and snooker moves restricted to each ensemble's own walkers
  (:mod:`bayestribo.inference.moves`); emcee's per-step work is paid once for all
  ensembles and the log-probability is evaluated for all their walkers in one call;
* ``"emcee"``: one :class:`emcee.EnsembleSampler` per ensemble with emcee's own
  moves, the reference the grouped moves are tested against.

Either way a step updates every walker of every ensemble once: the autocorrelation
time, the stopping rule and the effective sample size mean the same.

Where ``SamplerSettings.independence`` is above 0, the first ``adapt_steps`` steps
are an adaptation phase with the DE moves alone; at its end each ensemble's
independence proposal is fitted to its own walkers and held fixed, and the
independence Metropolis-Hastings move joins the mix with that weight (less where its
expected acceptance is low): :mod:`bayestribo.inference.independence`, which says
why the chain after the phase is valid and the ensembles independent. The phase is
never kept (the burn-in is at least ``adapt_steps``). The population's sampler
and the single-run fit use it (``benchmarks/README.md``).

Where ``SamplerSettings.independence_limit`` is given (the single-run fit's
:data:`FIT_INDEPENDENCE_LIMIT`), the move is **taken out** at the first check whose
longest raw τ is above that multiple of the τ the move's weight and expected
acceptance predict (:func:`~bayestribo.inference.independence.mixing_tau`): the
proposal, fitted to the adaptation phase's walkers, misses posterior mass they had
not reached (a ridge along a bound, a tail), where the move is rejected and the DE
moves, left a quarter of the steps, do the work alone. From that step on the DE
moves run alone with their own weights, and every step before it is discarded like
an adaptation phase (the burn-in is at least that step): the draws kept are all of
one fixed kernel, which leaves the posterior invariant, so the chain after the step
is valid however the step was chosen. The raw τ̂ (low on a short chain) is compared,
so a chain does not pass the limit by its estimator's bias. Where
``SamplerSettings.debias`` asks (the single-run fit), τ is debiased and its settling
judged over 30 τ while the move is in the mix; the DE moves alone (the move taken
out, never put in, or left out for its low acceptance), and the population's sampler,
are judged by the raw τ̂, settled over ``settle_steps``.

This module knows nothing of the models: :func:`run_ensembles` samples any vectorised
log-probability; the single-run fit and the population both use it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import emcee
import numpy as np
import scipy.fft
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.inference.independence import (
    GroupedIndependenceMove,
    expected_acceptance,
    mix_weight,
    mixing_tau,
)
from bayestribo.inference.modes import transient_steps
from bayestribo.inference.moves import DESnookerMove, grouped_moves
from bayestribo.inference.rhat import rhat
from bayestribo.inference.tau_bias import TauCheck, debiased, settle_span
from bayestribo.inference.tau_bias import settled as tau_settled
from bayestribo.inference.thinning import capped_thin, thinned_ess
from bayestribo.summary import ParameterSummary

__all__ = [
    "CHECK_GROWTH",
    "FIT_AUTOCORR_MULTIPLE",
    "FIT_INDEPENDENCE",
    "FIT_INDEPENDENCE_LIMIT",
    "FIT_MAX_DRAWS",
    "FIT_MIN_ESS",
    "MOVES",
    "NaNLogProbabilityError",
    "SamplerRun",
    "SamplerSettings",
    "autocorr_time",
    "check_spacing",
    "default_moves",
    "effective_sample_size",
    "rhat",
    "run_ensembles",
]


#: Checks are skipped while the steps are below this fraction of (2 + the required
#: multiple) τ (:meth:`SamplerSettings.required_multiple`).
_EARLY = 0.9
#: Ways to run the ensembles (:class:`SamplerSettings` ``moves``).
MOVES = ("grouped", "emcee")
#: The single-run fit's stopping rule (:meth:`bayestribo.inference.spec.FitSpec.sampler_settings`):
#: an effective sample size of 1000 (31.25 τ with its 2 × 16 walkers), and at least
#: 20 τ after burn-in however many walkers there are.
FIT_MIN_ESS = 1000.0
FIT_AUTOCORR_MULTIPLE = 20.0
#: The single-run fit's weight of the independence move (``SamplerSettings.independence``).
FIT_INDEPENDENCE = 0.75
#: The single-run fit's largest number of draws kept (``SamplerSettings.max_draws``).
FIT_MAX_DRAWS = 2000
#: The single-run fit's limit on τ with the independence move, in units of the τ its
#: expected acceptance predicts (``SamplerSettings.independence_limit``).
FIT_INDEPENDENCE_LIMIT = 4.0


class NaNLogProbabilityError(BayestriboError, FloatingPointError):
    """The sampled log-probability is NaN (a broken model or input); the message names
    the parameter values."""


def default_moves() -> list[tuple[emcee.moves.Move, float]]:
    """The move mix of every sampler in the package: DE 80 %, DE snooker 20 % (ter Braak
    & Vrugt's snooker, :class:`~bayestribo.inference.moves.DESnookerMove`: emcee 3.1.6's
    own does not sample the target)."""
    return [(emcee.moves.DEMove(), 0.8), (DESnookerMove(), 0.2)]


@dataclass(frozen=True)
class SamplerSettings:
    """Settings of :func:`run_ensembles`.

    Attributes
    ----------
    n_walkers : int
        Walkers per ensemble (at least twice the number of parameters).
    n_ensembles : int
        Independent ensembles (>= 2 for R-hat).
    autocorr_multiple : float
        Steps after burn-in required, in units of the autocorrelation time.
    min_ess : float or None
        Effective sample size required as well (over all ensembles' walkers, of the
        parameter with the longest τ); None: the rule is ``autocorr_multiple`` alone.
    check_every : int
        Steps between convergence checks.
    settle_steps : int
        τ has settled when it changed by less than 10 % since the check this many
        steps (or more) before.
    max_steps : int
        Ceiling on the steps per ensemble.
    rhat_max : float
        Largest acceptable R-hat.
    moves : {"grouped", "emcee"}
        All ensembles in one emcee sampler with the grouped DE moves (the default;
        used when ``n_walkers`` is a multiple of 4, else ``"emcee"``), or one sampler
        per ensemble with emcee's own moves (see the module notes).
    independence : float
        Weight in [0, 1) of the independence Metropolis-Hastings move in the mix after
        the adaptation phase (:mod:`bayestribo.inference.independence`; the DE moves
        share the rest, 80/20); 0 (the default): DE moves alone, no adaptation phase.
    adapt_steps : int
        Steps of the adaptation phase where ``independence`` > 0: DE moves alone,
        each ensemble's proposal then fitted to its walkers' second half of the phase
        and held fixed; the burn-in is at least this long.
    max_draws : int or None
        Largest number of draws kept (all walkers and ensembles): the thinning is
        coarser than ⌈τ⌉ where the run has more, and the effective sample size is
        that of the draws kept (:mod:`bayestribo.inference.thinning`); None: every
        ⌈τ⌉-th step's.
    independence_limit : float or None
        Where the independence move is in the mix: the longest raw τ at a check above
        this multiple of the τ the move's expected acceptance predicts
        (:func:`~bayestribo.inference.independence.mixing_tau`) takes the move out
        for the rest of the run, and every step before is discarded (see the module
        notes); None: the move stays in.
    debias : bool
        While the independence move is in the mix, τ corrected for its estimator's
        bias on short chains and its settling judged over 30 τ
        (:mod:`bayestribo.inference.tau_bias`; the single-run fit's rule); False (the
        default, the population's): the raw τ̂, settled over ``settle_steps``.
    """

    n_walkers: int = 32
    n_ensembles: int = 2
    autocorr_multiple: float = 50.0
    min_ess: float | None = None
    check_every: int = 50
    settle_steps: int = 200
    max_steps: int = 20_000
    rhat_max: float = 1.01
    moves: str = "grouped"
    independence: float = 0.0
    adapt_steps: int = 100
    max_draws: int | None = None
    independence_limit: float | None = None
    debias: bool = False

    def __post_init__(self) -> None:
        if self.moves not in MOVES:
            raise BayestriboError(f"moves: expected one of {MOVES}, got {self.moves!r}")
        if not 0.0 <= self.independence < 1.0:
            raise BayestriboError(
                f"independence: expected a weight in [0, 1), got {self.independence}"
            )
        if self.independence > 0 and not 2 <= self.adapt_steps < self.max_steps:
            raise BayestriboError(
                f"adapt_steps: expected 2 to max_steps - 1 = {self.max_steps - 1} steps "
                f"with the independence move, got {self.adapt_steps}"
            )
        if self.max_draws is not None and self.max_draws < self.n_walkers * self.n_ensembles:
            raise BayestriboError(
                "max_draws: expected at least one step's draws "
                f"({self.n_walkers * self.n_ensembles}), got {self.max_draws}"
            )
        if self.independence_limit is not None and not self.independence_limit > 1.0:
            raise BayestriboError(
                f"independence_limit: expected > 1 or None, got {self.independence_limit}"
            )
        if self.n_ensembles < 2:
            raise BayestriboError(f"n_ensembles: expected >= 2 for R-hat, got {self.n_ensembles}")
        if not self.autocorr_multiple > 0:
            raise BayestriboError(
                "autocorr_multiple: expected > 0 autocorrelation times, "
                f"got {self.autocorr_multiple}"
            )
        if self.min_ess is not None and not self.min_ess > 0:
            raise BayestriboError(f"min_ess: expected > 0 or None, got {self.min_ess}")
        if self.check_every < 10:
            raise BayestriboError(f"check_every: expected >= 10 steps, got {self.check_every}")
        if self.settle_steps < self.check_every:
            raise BayestriboError(
                f"settle_steps: expected at least check_every = {self.check_every} steps, "
                f"got {self.settle_steps}"
            )
        if self.max_steps < self.check_every:
            raise BayestriboError(
                f"max_steps: expected at least check_every = {self.check_every} steps, "
                f"got {self.max_steps}"
            )

    def required_multiple(self) -> float:
        """Steps after burn-in the rule requires, in units of the longest τ.

        ``autocorr_multiple``, or, where ``min_ess`` is given and asks for more, the
        steps whose effective sample size is ``min_ess``: ESS = steps × walkers ×
        ensembles / τ, so ``min_ess / (n_walkers × n_ensembles)`` τ.

        Returns
        -------
        float
            The multiple of τ [dimensionless].
        """
        multiple = float(self.autocorr_multiple)
        if self.min_ess is not None:
            multiple = max(multiple, float(self.min_ess) / (self.n_walkers * self.n_ensembles))
        return multiple


@dataclass
class SamplerRun:
    """Chains and diagnostics of a finished run.

    Attributes
    ----------
    chains : ndarray
        Thinned post-burn-in samples, shape (ensembles, draws, n_params); draws are
        step-major (all walkers of one step, then the next step).
    log_prob : ndarray
        Log posterior of each sample, shape (ensembles, draws).
    autocorr_time : ndarray
        Integrated autocorrelation time per parameter (max over ensembles) [steps].
    n_steps, burn, thin : int
        Steps per ensemble, discarded steps, thinning.
    acceptance_fraction : float
        Mean acceptance fraction over all walkers.
    ess : ndarray
        Effective sample size per parameter.
    rhat : ndarray
        Between-ensemble rank-normalised split R-hat per parameter.
    converged : bool
        All criteria met.
    reasons : list of str
        Why the run is not converged (empty if it is).
    names : tuple of str
        Parameter names, in the order of the last axis of ``chains``.
    walker_acceptance : ndarray or None
        emcee's acceptance fraction of each walker over the whole run, shape
        (ensembles, walkers); None where no sampler ran.
    ridge : bool
        Stopped before its ceiling on a ridge the record does not identify (the
        ``unidentified`` rule of :func:`run_ensembles`; its reasons say so).
    independence : float
        Weight of the independence move in the mix after the adaptation phase (0:
        not used; ``SamplerSettings.independence``).
    independence_acceptance : float
        The least of the ensembles' expected acceptances of that move at the end of
        the adaptation phase (NaN where there was none).
    independence_dropped : int or None
        The step at which the move was taken out (``SamplerSettings.independence_limit``:
        the draws kept are all after it, with the DE moves alone, and ``independence``
        is then 0); None where it was not.
    """

    chains: NDArray
    log_prob: NDArray
    autocorr_time: NDArray
    n_steps: int
    burn: int
    thin: int
    acceptance_fraction: float
    ess: NDArray
    rhat: NDArray
    converged: bool
    reasons: list[str] = field(default_factory=list)
    names: tuple[str, ...] = ()
    walker_acceptance: NDArray | None = None
    ridge: bool = False
    independence: float = 0.0
    independence_acceptance: float = float("nan")
    independence_dropped: int | None = None

    def summary(self, prob: float = 0.95) -> dict[str, ParameterSummary]:
        """Posterior summary of each parameter over all ensembles' thinned draws.

        Parameters
        ----------
        prob : float
            Probability of the equal-tailed credible interval, in (0, 1).

        Returns
        -------
        dict of str to ParameterSummary
            By parameter name (``theta[i]`` when the run was given no names), in the
            sampled parameter's own unit.
        """
        labels = _labels(self.names, self.chains.shape[-1])
        return {
            name: ParameterSummary.from_samples(self.chains[..., i], prob)
            for i, name in enumerate(labels)
        }


def _labels(names: Sequence[str], ndim: int) -> list[str]:
    """``names`` if there is one per parameter, else ``theta[0]``, ``theta[1]``, ..."""
    names = list(names)
    return names if len(names) == ndim else [f"theta[{i}]" for i in range(ndim)]


def _nan_checked(
    log_prob: Callable[[NDArray], NDArray], names: Sequence[str]
) -> Callable[[NDArray], NDArray]:
    """``log_prob`` that raises on NaN (the one rule of every sampler in the package)."""

    def checked(theta: NDArray) -> NDArray:
        lp = np.asarray(log_prob(theta), dtype=float)
        bad = np.isnan(lp)
        if np.any(bad):
            row = np.atleast_2d(theta)[int(np.argmax(bad))]
            named = ", ".join(f"{n}={float(v)!r}" for n, v in zip(names, row, strict=True))
            raise NaNLogProbabilityError(f"the log-probability is NaN at {named}")
        return lp

    # A compiled step of the grouped moves stops before any split with a NaN and
    # leaves it to this function (bayestribo.inference.moves).
    checked.grouped_step = getattr(log_prob, "grouped_step", None)  # type: ignore[attr-defined]
    checked.independence_step = getattr(log_prob, "independence_step", None)  # type: ignore[attr-defined]
    return checked


def autocorr_time(chain: NDArray, c: float = 5.0) -> NDArray:
    """Integrated autocorrelation time τ per parameter [steps].

    emcee's estimator (:func:`emcee.autocorr.integrated_time` with ``tol=0``): the
    autocorrelation function of each walker by FFT, averaged over the walkers,
    τ(M) = 1 + 2 Σ_{t=1}^{M} ρ(t) with Sokal's window, the smallest M >= c τ(M) (the
    last lag if there is none). Computed for all walkers and parameters in one
    batched real FFT of a fast length; it agrees with emcee's to rounding (tests).

    Parameters
    ----------
    chain : ndarray
        One ensemble's chain, shape (steps, walkers, params) (or (steps, walkers) and
        (steps,) for one parameter, as emcee takes them).
    c : float
        Window constant of Sokal's rule.

    Returns
    -------
    ndarray
        τ per parameter (NaN for a chain that does not move).
    """
    x = np.asarray(chain, dtype=float)
    x = x.reshape(x.shape + (1,) * (3 - x.ndim))
    return _autocorr_times(x[None], c)[0]


def _autocorr_times(chains: NDArray, c: float = 5.0) -> NDArray:
    """:func:`autocorr_time` of each ensemble's chain, (ensembles, steps, walkers,
    params) -> (ensembles, params).

    Sokal's window M is the first lag with M >= c τ(M), and τ(M) needs the
    autocorrelation up to M alone: it is computed for the first quarter of the lags
    (:data:`_FIRST_LAGS` at least), where a chain long enough to be judged has its
    window (M ≈ cτ: a tenth of the steps at 50 τ, a sixth at the fit's 31 τ), and for
    all of them for an ensemble with a parameter whose window is not there
    (:func:`_windowed_taus`; an ensemble's τ is the same whether it is transformed
    alone or with others).
    """
    n_t = chains.shape[1]
    lags = min(n_t, max(_FIRST_LAGS, n_t // 4))
    taus, inside = _windowed_taus(chains, c, lags)
    out = _at_window(taus, inside)
    # an ensemble with a parameter whose window is not among the first lags: all of them
    longer = ~np.all(np.any(~inside, axis=-1), axis=-1)
    if lags < n_t and longer.any():
        out[longer] = _at_window(*_windowed_taus(chains[longer], c, n_t))
    return out


def _at_window(taus: NDArray, inside: NDArray) -> NDArray:
    """τ at Sokal's window by emcee's rule: the first lag M >= c τ(M) (``inside`` is
    M < c τ(M)); the last lag where none is below c τ (a NaN τ)."""
    window = np.where(inside.any(axis=-1), np.argmin(inside, axis=-1), taus.shape[-1] - 1)
    return np.take_along_axis(taus, window[..., None], axis=-1)[..., 0]


#: Lags of the autocorrelation computed first (:func:`_autocorr_times`), at least.
_FIRST_LAGS = 64


def _windowed_taus(chains: NDArray, c: float, lags: int) -> tuple[NDArray, NDArray]:
    """τ(M) = 1 + 2 Σ_{t=1}^{M} ρ(t) for the lags M < ``lags``, (ensembles, params,
    lags), and whether M < c τ(M) at each.

    Zero padding to n + lags - 1 or more gives the linear (not circular)
    autocorrelation exactly at those lags; emcee pads to twice the next power of two,
    a fast length is quicker, and so are transforms along contiguous rows. Each
    walker's autocorrelation is taken over its value at lag 0 (its sum of squares) and
    averaged over the walkers; the transform being linear, the average is taken of
    the normalised power spectra, transformed back once per parameter. The walkers of
    one ensemble and parameter are transformed together, in one reused padded buffer:
    a few hundred kB at a time, where the whole at once (megabytes, allocated afresh
    at every check) costs more in fresh memory pages than in arithmetic.
    """
    n_ens, n_t, n_walkers, n_params = chains.shape
    size = scipy.fft.next_fast_len(max(n_t + lags - 1, 1), real=True)
    rows = np.zeros((n_walkers, size))
    kept = rows[:, :n_t]
    power = np.empty((n_ens, n_params, size // 2 + 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        for e in range(n_ens):
            for p in range(n_params):
                kept[...] = chains[e, :, :, p].T
                kept -= kept.mean(axis=-1, keepdims=True)
                spectrum = scipy.fft.rfft(rows, axis=-1)
                walkers = spectrum.real**2 + spectrum.imag**2
                walkers /= np.einsum("ij,ij->i", kept, kept)[:, None]
                walkers.mean(axis=0, out=power[e, p])
        acf = scipy.fft.irfft(power, n=size, axis=-1)[..., :lags]
        taus = 2.0 * np.cumsum(acf, axis=-1) - 1.0  # (ensembles, params, lags)
        inside = np.arange(lags) < c * taus
    return taus, inside


def effective_sample_size(chain: NDArray) -> NDArray:
    """Effective sample size per parameter of one ensemble's chain.

    ESS = steps × walkers / τ, with τ from :func:`autocorr_time` (the number of
    independent draws worth as much as the chain for estimating a mean).

    Parameters
    ----------
    chain : ndarray
        Shape (steps, walkers, params).

    Returns
    -------
    ndarray
        ESS per parameter (NaN for a chain that does not move).

    Raises
    ------
    BayestriboError
        If ``chain`` is not three-dimensional.
    """
    chain = np.asarray(chain, dtype=float)
    if chain.ndim != 3:
        raise BayestriboError(f"chain: expected shape (steps, walkers, params), got {chain.shape}")
    return chain.shape[0] * chain.shape[1] / autocorr_time(chain)


#: From ``2 check_every / CHECK_GROWTH`` steps (2000 at the defaults; the default fit
#: stops before, the population's sampler at about 1500), the checks come every
#: ``CHECK_GROWTH`` of the steps run so far, in whole ``check_every``
#: (:func:`check_spacing`).
CHECK_GROWTH = 0.05


def check_spacing(steps: int, check_every: int) -> int:
    """Steps to run before the next check of the stopping rule, at ``steps`` so far.

    A check costs in proportion to the chain's length (the autocorrelation's
    transforms of every walker and parameter): checked every ``check_every`` steps, a
    run of n steps spends ∝ n² on its checks (a ridge walked for 16,000 steps: a third
    of its time). Every :data:`CHECK_GROWTH` of the steps so far, in whole
    ``check_every``, they cost ∝ n in all, and a run stops at most that share of its
    length after the check that would have stopped it; below 2 ``check_every /
    CHECK_GROWTH`` steps (2000 at the defaults) the checks are as before.

    Parameters
    ----------
    steps : int
        Steps run so far.
    check_every : int
        The settings' steps between checks (:class:`SamplerSettings`).

    Returns
    -------
    int
        A multiple of ``check_every``, at least one.
    """
    return check_every * max(1, int(CHECK_GROWTH * steps) // check_every)


def run_ensembles(
    log_prob: Callable[[NDArray], NDArray],
    initial: NDArray,
    settings: SamplerSettings,
    seed: int | None,
    progress: bool = False,
    names: Sequence[str] | None = None,
    unidentified: Callable[[NDArray], list[str]] | None = None,
) -> SamplerRun:
    """Run ``settings.n_ensembles`` independent emcee ensembles to convergence.

    Parameters
    ----------
    log_prob : callable
        Vectorised log posterior: rows (n, d) -> (n,).
    initial : ndarray
        Starting positions, shape (n_ensembles, n_walkers, d), all with finite log_prob.
    settings : SamplerSettings
    seed : int or None
        Seed of the whole run.
    progress : bool
        Show a progress bar (tqdm).
    names : sequence of str, optional
        Parameter names, for messages (default ``names`` of ``log_prob`` if it has
        them, else ``theta[i]``).
    unidentified : callable, optional
        ``unidentified(draws) -> reasons``: why the draws (n, d) show a posterior that
        the record does not identify (a ridge, not a mode; empty when they do not:
        :func:`bayestribo.inference.identifiability.unidentified_reasons`). Where it
        gives reasons at a check at which the rule needs more steps than the ceiling
        even at the τ measured so far (which short chains underestimate), or would at
        the ceiling where τ grows in proportion to the chain (:func:`_ridge_growth`), or
        where the ensembles' disagreement has not shrunk over a doubling of the steps
        since the rule was met (:func:`_rhat_stalled`), the run stops there, not
        converged, instead of walking the ridge to the ceiling.

    Returns
    -------
    SamplerRun
        Not converged (with reasons) when the criteria are not met by ``max_steps``.

    Raises
    ------
    NaNLogProbabilityError
        If ``log_prob`` returns NaN; the message names the parameter values (a
        ``FloatingPointError`` too).
    BayestriboError
        If ``initial`` is not of shape (n_ensembles, n_walkers, d) as ``settings`` say.
    """
    initial = np.asarray(initial, dtype=float)
    if initial.ndim != 3 or initial.shape[:2] != (settings.n_ensembles, settings.n_walkers):
        raise BayestriboError(
            f"initial: expected shape ({settings.n_ensembles}, {settings.n_walkers}, d), "
            f"got {initial.shape}"
        )
    n_ens, n_walkers, ndim = initial.shape
    labels = _labels(names if names is not None else getattr(log_prob, "names", []), ndim)
    if n_walkers < 2 * ndim:
        # emcee's moves need two walkers a coordinate (an ensemble of fewer does not
        # span the posterior; emcee itself refuses with a RuntimeError)
        raise BayestriboError(
            f"n_walkers (--walkers): expected at least twice the {ndim} sampled parameters "
            f"({', '.join(labels)}), {2 * ndim} walkers per ensemble, got {n_walkers}"
        )
    checked = _nan_checked(log_prob, labels)
    if settings.moves == "grouped" and n_walkers % 4 == 0 and n_walkers >= 2 * ndim:
        ensembles: _Ensembles = _Grouped(checked, initial, seed)
    else:
        ensembles = _Separate(checked, initial, seed)

    multiple = settings.required_multiple()
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=settings.max_steps, desc="sampling", unit="step", leave=False)
    history: list[TauCheck] = []  # the checks since τ was defined
    last_rhat: tuple[int, int, int, NDArray] | None = None  # steps, burn, thin, R-hat
    tau = np.full(ndim, np.inf)
    steps = 0
    enough = settled = False
    span = settings.settle_steps  # the span τ is judged settled over
    extended: int | None = None  # a burn-in extended past a transient
    hopeless: list[str] = []  # why a run on a ridge was stopped before its ceiling
    # the first check at which the rule was met and the ensembles disagreed
    stalled_from: tuple[int, int, int, NDArray] | None = None
    skip = 0  # the end of a transient found at the start of the draws (steps)
    floor = 0  # the adaptation phase, never kept (inference/independence.py)
    independence = (0.0, float("nan"))  # the move's weight and expected acceptance
    dropped: int | None = None  # the step at which the move was taken out
    try:
        if settings.independence > 0:
            floor = settings.adapt_steps
            ensembles.run(floor)
            steps = floor
            if bar is not None:
                bar.update(floor)
            independence = _adapted(ensembles, checked, floor, settings.independence, seed)
        while steps < settings.max_steps:
            mixing = independence[0] > 0  # the move in the mix
            debias = mixing and settings.debias  # τ debiased, settled over 30 τ
            chunk = check_spacing(steps, settings.check_every)
            if np.all(np.isfinite(tau)):
                # The rule cannot be met this early with the last τ (which short chains
                # underestimate): the checks before this many steps are skipped, and
                # the steps up to the next check run in one call of the sampler.
                longest = np.max(tau)
                early = _EARLY * max((2.0 + multiple) * longest, floor + multiple * longest)
                if debias:
                    # a check is left a span before it, for the rule that τ settle
                    early -= settle_span(tau, settings.check_every, settings.settle_steps)
                skipped = math.ceil((early - steps) / settings.check_every)
                chunk = max(chunk, settings.check_every * skipped)
            chunk = min(chunk, settings.max_steps - steps)
            ensembles.run(chunk)
            steps += chunk
            if bar is not None:
                bar.update(chunk)
            burn = min(int(2 * np.max(tau)) if np.all(np.isfinite(tau)) else steps // 3, steps // 2)
            burn = max(burn, min(skip, steps // 2), floor)
            raw = np.max(_autocorr_times(ensembles.chains(burn)), axis=0)
            # With the move, τ̂ of a short chain is low by its known bias
            # (inference/tau_bias.py); with the DE moves alone it is the rule as is.
            tau, comparable = debiased(raw, steps - burn) if debias else (raw, True)
            if not np.all(np.isfinite(tau)):
                # A stuck chain (no move accepted): τ is undefined; keep sampling.
                history, enough, settled = [], False, False
                continue
            limit = settings.independence_limit if steps < settings.max_steps else None
            if mixing and _move_fails(raw, independence, limit):
                # the proposal misses posterior mass (a ridge, a tail, a bound): the
                # move is taken out and the run starts again from here with the DE
                # moves alone, every step before discarded (the kept draws are all
                # of one kernel); not at the ceiling, where no step would be left
                ensembles.drop_independence()
                independence = (0.0, independence[1])
                dropped = floor = steps
                history, enough, settled, skip, last_rhat = [], False, False, 0, None
                stalled_from = None
                tau = np.full(ndim, np.inf)
                continue
            burn = math.ceil(2 * np.max(tau))
            if history and np.max(tau) < 0.5 * np.max(history[-1].tau):
                # τ fell by half: the draws the last estimate kept may begin with the
                # walkers' way in from their start (a transient, which lengthens τ
                # while it is kept): the burn-in is extended past it from now on
                skip = max(skip, _transient_end(ensembles, burn, tau, settings, labels))
            burn = max(burn, skip, floor)
            span = (
                settle_span(tau, settings.check_every, settings.settle_steps)
                if debias
                else settings.settle_steps
            )
            now = TauCheck(steps, raw, tau, comparable)
            settled = tau_settled(history, now, span)
            history.append(now)
            enough = steps - burn >= multiple * np.max(tau)
            need = burn + multiple * np.max(tau)
            why = None
            if unidentified is not None and not enough:
                if need > settings.max_steps:
                    why = (
                        f"stopped at {steps} steps: the rule needs at least {need:.0f} "
                        f"(burn-in and {multiple:g} autocorrelation times "
                        f"of {np.max(tau):.0f} steps), beyond the ceiling of "
                        f"{settings.max_steps}"
                    )
                else:
                    why = _ridge_growth(history, multiple, settings.max_steps)
            elif unidentified is not None and stalled_from is not None:
                why = _rhat_stalled(stalled_from, last_rhat, labels)
            if why is not None:
                # the rule cannot be met by the ceiling: where the draws show why (a
                # ridge the record does not identify), the run stops here
                kept = ensembles.flat(min(burn, steps - 1), 1)[0]
                unseen = unidentified(kept.reshape(-1, ndim)) if unidentified else []
                if unseen:
                    hopeless = [why, *unseen]
                    break
            if bar is not None:
                need = int(burn + multiple * np.max(tau))
                bar.set_postfix(tau=f"{np.max(tau):.0f}", need=need)
            if enough and settled:
                # Independent ensembles must also agree; otherwise keep sampling.
                burn_now = min(burn, steps - 1)
                thin_now = max(1, math.ceil(np.max(tau)))
                last_rhat = (steps, burn_now, thin_now, rhat(ensembles.flat(burn_now, thin_now)[0]))
                if np.all(last_rhat[3] < settings.rhat_max):
                    break
                # the walkers' way from their start to the posterior, left after the
                # burn-in of 2τ, makes the ensembles disagree: the burn-in extended past
                # it where what is left meets the rule (inference/modes.py)
                past = _past_transient(ensembles, steps, burn_now, thin_now, tau, settings, labels)
                if past is not None:
                    last_rhat = past
                    extended = past[1]
                    break
                if stalled_from is None:
                    stalled_from = last_rhat
    finally:
        if bar is not None:
            bar.close()

    defined = bool(np.all(np.isfinite(tau)))
    burn = min(max(math.ceil(2 * np.max(tau)), skip, floor), steps - 1) if defined else steps // 2
    if not defined:
        burn = max(burn, min(floor, steps - 1))
    if extended is not None:
        burn = extended
    thin = max(1, math.ceil(np.max(tau))) if defined else 1
    step_thin = thin
    if defined and settings.max_draws is not None:
        # at most max_draws draws kept, their own ESS reported (inference/thinning.py)
        thin = max(thin, capped_thin(steps - burn, n_walkers * n_ens, settings.max_draws))
    chains, lps = ensembles.flat(burn, thin)
    acceptance = ensembles.acceptance()
    ess = (steps - burn) * n_walkers * n_ens / tau
    if thin > step_thin:
        ess = np.minimum(ess, thinned_ess(chains.shape[0] * chains.shape[1], tau, thin))
    reuse = last_rhat is not None and last_rhat[:3] == (steps, burn, thin)
    r_hat = last_rhat[3] if reuse else rhat(chains)

    reasons = list(hopeless)
    if not defined:
        reasons.append("the autocorrelation time is undefined (a chain did not move)")
    elif not enough:
        reasons.append(
            f"only {steps - burn} steps after burn-in, fewer than "
            f"{multiple:g} autocorrelation times ({np.max(tau):.1f})"
        )
    elif not settled:
        reasons.append(
            "the autocorrelation time has not settled (changed by 10 % or more over the "
            f"last {span} steps, its estimator's bias on short chains removed)"
        )
    if not np.all(r_hat < settings.rhat_max):
        worst = int(np.argmax(r_hat))
        reasons.append(f"R-hat {r_hat[worst]:.4f} >= {settings.rhat_max} for {labels[worst]}")
    if not 0.05 < acceptance < 0.95:
        reasons.append(f"acceptance fraction {acceptance:.3f} outside (0.05, 0.95)")
    return SamplerRun(
        chains=chains,
        log_prob=lps,
        autocorr_time=tau,
        n_steps=steps,
        burn=burn,
        thin=thin,
        acceptance_fraction=acceptance,
        ess=ess,
        rhat=r_hat,
        converged=not reasons,
        reasons=reasons,
        names=tuple(labels),
        walker_acceptance=ensembles.walker_acceptance(),
        ridge=bool(hopeless),
        independence=independence[0],
        independence_acceptance=independence[1],
        independence_dropped=dropped,
    )


#: τ grows in proportion to the chain (a ridge's random walk) when it grew as the steps
#: to at least this power over their last doubling (:func:`_ridge_growth`); a posterior
#: settling to its τ grows slower (a real ridge that converged: 0.6-0.75 at its worst).
RIDGE_POWER = 0.8
#: ... and only from this many steps on (a start's transient grows τ faster, early).
RIDGE_MIN_STEPS = 2000
#: The ensembles' disagreement has stalled when max(R-hat - 1) is still at least this
#: share of its value where the rule was first met, twice the steps on (:func:`_rhat_stalled`).
RHAT_STALLED = 0.8


def _ridge_growth(history: Sequence[TauCheck], multiple: float, ceiling: int) -> str | None:
    """Why the rule cannot be met by ``ceiling`` where τ grows with the chain, or None.

    On a ridge the record does not identify the walkers' random walk has no τ of its
    own: the estimate grows with the chain, and at the ceiling's length the rule (burn-in
    of 2τ and ``multiple`` τ) needs more than the ceiling whenever τ is more than a
    ``1 / (2 + multiple)`` share of the chain. Where the last check's τ grew as the steps
    to at least :data:`RIDGE_POWER` since the check at half its steps or fewer (from
    :data:`RIDGE_MIN_STEPS` on), τ is carried to the ceiling at that power; None where
    the rule would still be met there (or τ settles)."""
    if len(history) < 2 or history[-1].steps < RIDGE_MIN_STEPS:
        return None
    now = history[-1]
    earlier = [h for h in history[:-1] if h.steps <= now.steps / 2]
    if not earlier:
        return None
    then = earlier[-1]
    t_now, t_then = float(np.max(now.tau)), float(np.max(then.tau))
    if not (t_then > 0.0 and t_now > t_then):
        return None
    power = math.log(t_now / t_then) / math.log(now.steps / then.steps)
    if power < RIDGE_POWER:
        return None
    at_ceiling = t_now * (ceiling / now.steps) ** min(power, 1.0)
    need = (2.0 + multiple) * at_ceiling
    if need <= ceiling:
        return None
    return (
        f"stopped at {now.steps} steps: the autocorrelation time grows with the chain "
        f"({t_then:.0f} steps at {then.steps}, {t_now:.0f} at {now.steps}), as on a "
        f"ridge; at that rate the rule (burn-in and {multiple:g} autocorrelation times) "
        f"would need {need:.0f} steps at the ceiling of {ceiling}"
    )


def _rhat_stalled(
    first: tuple[int, int, int, NDArray],
    last: tuple[int, int, int, NDArray] | None,
    labels: Sequence[str],
) -> str | None:
    """Why the ensembles will not agree by the ceiling, or None: at twice the steps
    at which the rule was first met with R-hat over its bound (``first``), the largest
    R-hat - 1 (``last``) still at least :data:`RHAT_STALLED` of what it was there."""
    if last is None or last[0] < 2 * first[0]:
        return None
    was, now = float(np.max(first[3]) - 1.0), float(np.max(last[3]) - 1.0)
    if not (was > 0.0 and now >= RHAT_STALLED * was):
        return None
    worst = labels[int(np.argmax(last[3]))]
    return (
        f"stopped at {last[0]} steps: the ensembles still disagree (R-hat of {worst} "
        f"{1.0 + now:.3f}, {1.0 + was:.3f} at {first[0]} steps, where the autocorrelation "
        "rule was first met), as on a ridge"
    )


def _move_fails(raw: NDArray, independence: tuple[float, float], limit: float | None) -> bool:
    """Whether the longest raw τ is above ``limit`` × the τ the move's weight and
    expected acceptance ``independence`` predict
    (:func:`~bayestribo.inference.independence.mixing_tau`); False where ``limit`` is
    None. The raw τ̂ (low on a short chain) is compared: a chain does not pass the
    limit by its estimator's bias."""
    if limit is None:
        return False
    weight, acceptance = independence
    return bool(np.max(raw) > limit * mixing_tau(acceptance, weight))


def _adapted(
    ensembles: _Ensembles,
    log_prob: Callable[[NDArray], NDArray],
    steps: int,
    weight: float,
    seed: int | None,
) -> tuple[float, float]:
    """The end of the adaptation phase (:mod:`bayestribo.inference.independence`):
    each ensemble's proposal fitted to its own walkers over the phase's second half,
    its expected acceptance estimated from those draws and one proposal per walker
    (evaluated here, not part of any chain), and the move put in the mix with its
    weight (:func:`~bayestribo.inference.independence.mix_weight` of the least
    expected acceptance; none where that is 0). Returns (weight, least acceptance)."""
    move = GroupedIndependenceMove.fitted(ensembles.chains(steps // 2))
    draws, lps = ensembles.flat(steps // 2, 1)
    n_ens, _, ndim = draws.shape
    per = ensembles.walker_acceptance().shape[1]
    child = np.random.SeedSequence(seed).spawn(2)[1]  # not the sampler's stream
    random = np.random.RandomState(child.generate_state(1)[0])
    proposed = np.stack([p.draw(random, per) for p in move.proposals])
    proposed_lp = np.asarray(log_prob(proposed.reshape(-1, ndim)), dtype=float)
    acceptance = expected_acceptance(
        move.proposals, draws, lps, proposed, proposed_lp.reshape(n_ens, per)
    )
    used = mix_weight(float(np.min(acceptance)), weight)
    if used > 0:
        ensembles.use_independence(move, used)
    return used, float(np.min(acceptance))


def _transient_end(
    ensembles: _Ensembles,
    burn: int,
    tau: NDArray,
    settings: SamplerSettings,
    labels: Sequence[str],
) -> int:
    """The step at which a transient at the start of the draws after ``burn`` ends
    (:func:`bayestribo.inference.modes.transient_steps`, the draws thinned by ⌈τ⌉), or
    0 when there is none."""
    thin = max(1, math.ceil(np.max(tau)))
    chains, lps = ensembles.flat(burn, thin)
    cut = transient_steps(chains, lps, labels, settings.n_walkers)
    return burn + cut * thin if cut else 0


def _past_transient(
    ensembles: _Ensembles,
    steps: int,
    burn: int,
    thin: int,
    tau: NDArray,
    settings: SamplerSettings,
    labels: Sequence[str],
) -> tuple[int, int, int, NDArray] | None:
    """``(steps, burn, thin, R-hat)`` with the burn-in extended past a transient of the
    draws kept (:func:`bayestribo.inference.modes.transient_steps`) when what is left
    holds the required multiple of τ after it (:meth:`SamplerSettings.required_multiple`)
    and R-hat below ``rhat_max``; else None."""
    chains, lps = ensembles.flat(burn, thin)
    cut = transient_steps(chains, lps, labels, settings.n_walkers)
    if cut == 0:
        return None
    longer = burn + cut * thin
    if not steps - longer >= settings.required_multiple() * np.max(tau):
        return None
    r_hat = rhat(ensembles.flat(longer, thin)[0])
    if not np.all(r_hat < settings.rhat_max):
        return None
    return steps, longer, thin, r_hat


class _Ensembles:
    """Independent ensembles advanced together (see the module notes)."""

    def run(self, steps: int) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def chains(self, discard: int) -> NDArray:  # pragma: no cover - interface
        """Every ensemble's chain after ``discard`` steps, (ensembles, steps, walkers, d)."""
        raise NotImplementedError

    def flat(self, discard: int, thin: int) -> tuple[NDArray, NDArray]:
        """Thinned draws (ensembles, draws, d) and their log-probabilities, step-major."""
        raise NotImplementedError  # pragma: no cover - interface

    def acceptance(self) -> float:  # pragma: no cover - interface
        raise NotImplementedError

    def walker_acceptance(self) -> NDArray:  # pragma: no cover - interface
        """Acceptance fraction of each walker, (ensembles, walkers)."""
        raise NotImplementedError

    def use_independence(self, move: GroupedIndependenceMove, weight: float) -> None:
        """From the next step on, ``move`` (one fixed proposal per ensemble) with
        ``weight`` in the mix, the DE moves sharing the rest as before."""
        raise NotImplementedError  # pragma: no cover - interface

    def drop_independence(self) -> None:
        """From the next step on, the DE moves alone, with their weights before
        :meth:`use_independence`."""
        raise NotImplementedError  # pragma: no cover - interface


def _with_independence(sampler: emcee.EnsembleSampler, move, weight: float) -> None:
    """Set ``sampler``'s move mix to its moves so far at ``1 - weight`` of their
    weights and ``move`` at ``weight``, as emcee's constructor stores a mix (a tuple
    of moves, normalised float weights), which its ``sample`` draws from at every
    step."""
    weights = np.append(np.asarray(sampler._weights, dtype=float) * (1.0 - weight), weight)
    sampler._plain_moves = (sampler._moves, sampler._weights)
    sampler._moves = (*sampler._moves, move)
    sampler._weights = weights / np.sum(weights)


def _without_independence(sampler: emcee.EnsembleSampler) -> None:
    """Restore ``sampler``'s move mix from before :func:`_with_independence`."""
    sampler._moves, sampler._weights = sampler._plain_moves


class _Separate(_Ensembles):
    """One emcee sampler per ensemble, with emcee's own moves (the reference)."""

    def __init__(self, log_prob: Callable[[NDArray], NDArray], initial: NDArray, seed: int | None):
        n_ens, n_walkers, ndim = initial.shape
        children = np.random.SeedSequence(seed).spawn(n_ens)
        self.samplers = []
        for e in range(n_ens):
            sampler = emcee.EnsembleSampler(
                n_walkers, ndim, log_prob, moves=default_moves(), vectorize=True
            )
            state = np.random.RandomState(children[e].generate_state(1)[0]).get_state()
            sampler.random_state = state
            self.samplers.append(sampler)
        self.states: list = list(initial)

    def run(self, steps: int) -> None:
        for e, sampler in enumerate(self.samplers):
            self.states[e] = sampler.run_mcmc(self.states[e], steps, progress=False)

    def chains(self, discard: int) -> NDArray:
        return np.stack([s.get_chain(discard=discard) for s in self.samplers])

    def flat(self, discard: int, thin: int) -> tuple[NDArray, NDArray]:
        chains = np.stack(
            [s.get_chain(discard=discard, thin=thin, flat=True) for s in self.samplers]
        )
        lps = np.stack(
            [s.get_log_prob(discard=discard, thin=thin, flat=True) for s in self.samplers]
        )
        return chains, lps

    def acceptance(self) -> float:
        return float(np.mean([s.acceptance_fraction for s in self.samplers]))

    def walker_acceptance(self) -> NDArray:
        return np.stack([np.asarray(s.acceptance_fraction, dtype=float) for s in self.samplers])

    def use_independence(self, move: GroupedIndependenceMove, weight: float) -> None:
        for sampler, proposal in zip(self.samplers, move.proposals, strict=True):
            _with_independence(sampler, GroupedIndependenceMove([proposal]), weight)

    def drop_independence(self) -> None:
        for sampler in self.samplers:
            _without_independence(sampler)


class _MoveChoice(np.random.RandomState):
    """A Mersenne-Twister generator whose ``choice`` with probabilities ``p`` and no
    ``size`` (emcee's choice of the move at every step) costs one uniform draw.

    numpy's ``choice`` checks ``p`` and sums it anew at each call, several microseconds
    where the draw is a fraction of one. Here the cumulative sum of the last ``p``
    seen is kept, computed and checked as numpy does, and the index is the first
    whose cumulative probability exceeds one ``random_sample()``: numpy's draw and
    rule (``searchsorted(..., side="right")``), so the moves chosen and the stream
    after them are those of numpy's ``choice`` (tests). Any other call is numpy's.
    """

    _cdf: tuple[tuple[float, ...], list[float]] | None = None

    def choice(self, a, size=None, replace=True, p=None):  # type: ignore[override]
        """numpy's ``RandomState.choice``; one uniform draw for ``size=None`` with
        ``p`` (see the class notes)."""
        if size is not None or p is None or not isinstance(a, list | tuple):
            return super().choice(a, size=size, replace=replace, p=p)
        key = tuple(p)
        if self._cdf is None or self._cdf[0] != key:
            weights = np.asarray(p, dtype=float)
            if (
                weights.ndim != 1
                or weights.size != len(a)
                or np.any(weights < 0)
                or abs(math.fsum(weights) - 1.0) > math.sqrt(np.finfo(float).eps)
            ):
                return super().choice(a, size=size, replace=replace, p=p)
            cdf = weights.cumsum()
            cdf /= cdf[-1]
            self._cdf = (key, cdf.tolist())
        return a[bisect.bisect_right(self._cdf[1], self.random_sample())]


class _ResumingSampler(emcee.EnsembleSampler):
    """emcee's sampler without a copy of its generator's state in every step, and
    with a cheaper choice of the move.

    emcee's ``sample`` stores ``random_state`` (a copy of the Mersenne-Twister state,
    2.5 kB, about a fifth of a grouped step's time) in each step's ``State`` only so
    that a run resumed from that ``State`` restores the generator. :func:`run_ensembles`
    always resumes from the last state of the same sampler, whose generator is
    already in that state: here the getter gives None, which emcee's setter, by its
    documented rule ("fail silently if it doesn't work"), leaves the generator alone
    for. Seeding through the setter works as in emcee. The generator is a
    :class:`_MoveChoice`, whose ``choice`` of the move draws what numpy's does at a
    tenth of its cost. The chains are identical to emcee's own sampler's (tests).
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        generator = _MoveChoice()
        generator.set_state(self._random.get_state())
        self._random = generator

    @property
    def random_state(self) -> None:
        """None: the state is not copied (see the class notes)."""
        return None

    @random_state.setter
    def random_state(self, state: object) -> None:
        emcee.EnsembleSampler.random_state.fset(self, state)  # type: ignore[attr-defined]


class _Grouped(_Ensembles):
    """All ensembles as blocks of walkers of one emcee sampler, grouped moves."""

    sampler_class: type[emcee.EnsembleSampler] = _ResumingSampler

    def __init__(self, log_prob: Callable[[NDArray], NDArray], initial: NDArray, seed: int | None):
        n_ens, self.n_walkers, ndim = initial.shape
        self.n_ens = n_ens
        self.sampler = self.sampler_class(
            n_ens * self.n_walkers, ndim, log_prob, moves=grouped_moves(n_ens), vectorize=True
        )
        child = np.random.SeedSequence(seed).spawn(1)[0]
        self.sampler.random_state = np.random.RandomState(child.generate_state(1)[0]).get_state()
        self.state = initial.reshape(n_ens * self.n_walkers, ndim)

    def _split(self, values: NDArray) -> NDArray:
        """(steps, E·W, ...) -> (E, steps, W, ...)."""
        steps = values.shape[0]
        shaped = values.reshape(steps, self.n_ens, self.n_walkers, *values.shape[2:])
        return np.moveaxis(shaped, 1, 0)

    def run(self, steps: int) -> None:
        # emcee checks that the starting walkers are linearly independent; a run
        # resumed from the sampler's own last state was checked when it began
        resumed = self.sampler.iteration > 0
        self.state = self.sampler.run_mcmc(
            self.state, steps, progress=False, skip_initial_state_check=resumed
        )

    def chains(self, discard: int) -> NDArray:
        return self._split(self.sampler.get_chain(discard=discard))

    def flat(self, discard: int, thin: int) -> tuple[NDArray, NDArray]:
        chains = self._split(self.sampler.get_chain(discard=discard, thin=thin))
        lps = self._split(self.sampler.get_log_prob(discard=discard, thin=thin))
        n_ens, steps, walkers = lps.shape
        return (
            chains.reshape(n_ens, steps * walkers, -1),
            lps.reshape(n_ens, steps * walkers),
        )

    def acceptance(self) -> float:
        return float(np.mean(self.sampler.acceptance_fraction))

    def walker_acceptance(self) -> NDArray:
        fractions = np.asarray(self.sampler.acceptance_fraction, dtype=float)
        return fractions.reshape(self.n_ens, self.n_walkers)

    def use_independence(self, move: GroupedIndependenceMove, weight: float) -> None:
        _with_independence(self.sampler, move, weight)

    def drop_independence(self) -> None:
        _without_independence(self.sampler)
