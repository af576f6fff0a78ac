"""Ensemble MCMC with emcee: run length from the autocorrelation time, honest diagnostics.

* Several **independent ensembles** (default 2) run side by side, each with its own
  seed spawned from the user's seed (:class:`numpy.random.SeedSequence`), so that the
  Gelman-Rubin R-hat compares independent chains (R-hat over the walkers of one
  ensemble is not valid: they are coupled by the moves).
* Every ``check_every`` steps the integrated autocorrelation time τ of each parameter
  is estimated per ensemble (:func:`emcee.autocorr.integrated_time`); burn-in is 2τ;
  the run stops once every ensemble has at least ``autocorr_multiple`` × τ steps after
  burn-in, τ has settled (changed by less than 10 % since the last check) and the
  between-ensemble R-hat is below ``rhat_max`` for every parameter, or at
  ``max_steps``.
* Samples are thinned by ⌈τ⌉; the effective sample size of a parameter is
  (steps after burn-in × walkers × ensembles)/τ.
* A run that does not meet the criteria is reported as not converged, never silently.

Moves: a mixture of differential-evolution moves (emcee's ``DEMove`` 80 %,
``DESnookerMove`` 20 %), which mix faster than the default stretch move on the
narrow, correlated posteriors of this problem.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import emcee
import numpy as np
from numpy.typing import NDArray

__all__ = ["SamplerRun", "SamplerSettings", "run_ensembles"]


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
    check_every : int
        Steps between convergence checks.
    max_steps : int
        Ceiling on the steps per ensemble.
    rhat_max : float
        Largest acceptable R-hat.
    """

    n_walkers: int = 32
    n_ensembles: int = 2
    autocorr_multiple: float = 50.0
    check_every: int = 200
    max_steps: int = 20_000
    rhat_max: float = 1.01

    def __post_init__(self) -> None:
        if self.n_ensembles < 2:
            raise ValueError(f"n_ensembles must be >= 2 for R-hat, got {self.n_ensembles}")
        if self.check_every < 10 or self.max_steps < self.check_every:
            raise ValueError("check_every must be >= 10 and max_steps >= check_every")


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


def _autocorr(chain: NDArray) -> NDArray:
    """τ per parameter of one ensemble's chain (steps, walkers, params), no tolerance check."""
    return emcee.autocorr.integrated_time(chain, tol=0, quiet=True)


def _rhat(chains: NDArray) -> NDArray:
    """Rank-normalised split R-hat per parameter over the ensembles (ArviZ)."""
    import arviz as az

    return np.array(
        [float(az.rhat(np.ascontiguousarray(chains[..., i]))) for i in range(chains.shape[-1])]
    )


def run_ensembles(
    log_prob: Callable[[NDArray], NDArray],
    initial: NDArray,
    settings: SamplerSettings,
    seed: int | None,
    progress: bool = False,
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
    """
    n_ens, n_walkers, ndim = initial.shape
    children = np.random.SeedSequence(seed).spawn(n_ens)
    moves = [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    samplers = []
    states = []
    for e in range(n_ens):
        sampler = emcee.EnsembleSampler(n_walkers, ndim, log_prob, moves=moves, vectorize=True)
        sampler.random_state = np.random.RandomState(children[e].generate_state(1)[0]).get_state()
        samplers.append(sampler)
        states.append(initial[e])

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=settings.max_steps, desc="sampling", unit="step", leave=False)
    previous_tau = None
    tau = np.full(ndim, np.inf)
    steps = 0
    enough = False
    try:
        while steps < settings.max_steps:
            chunk = min(settings.check_every, settings.max_steps - steps)
            for e, sampler in enumerate(samplers):
                states[e] = sampler.run_mcmc(states[e], chunk, progress=False)
            steps += chunk
            if bar is not None:
                bar.update(chunk)
            taus = []
            for sampler in samplers:
                chain = sampler.get_chain()
                burn = min(
                    int(2 * np.max(tau)) if np.all(np.isfinite(tau)) else steps // 3, steps // 2
                )
                taus.append(_autocorr(chain[burn:]))
            tau = np.max(taus, axis=0)
            burn = math.ceil(2 * np.max(tau))
            settled = previous_tau is not None and np.all(np.abs(tau - previous_tau) < 0.1 * tau)
            previous_tau = tau
            enough = steps - burn >= settings.autocorr_multiple * np.max(tau)
            if bar is not None:
                need = int(burn + settings.autocorr_multiple * np.max(tau))
                bar.set_postfix(tau=f"{np.max(tau):.0f}", need=need)
            if enough and settled:
                # Independent ensembles must also agree; otherwise keep sampling.
                burn_now = min(burn, steps - 1)
                thin_now = max(1, math.ceil(np.max(tau)))
                current = np.stack(
                    [s.get_chain(discard=burn_now, thin=thin_now, flat=True) for s in samplers]
                )
                if np.all(_rhat(current) < settings.rhat_max):
                    break
    finally:
        if bar is not None:
            bar.close()

    burn = min(math.ceil(2 * np.max(tau)), steps - 1)
    thin = max(1, math.ceil(np.max(tau)))
    chains = np.stack([s.get_chain(discard=burn, thin=thin, flat=True) for s in samplers])
    lps = np.stack([s.get_log_prob(discard=burn, thin=thin, flat=True) for s in samplers])
    acceptance = float(np.mean([s.acceptance_fraction for s in samplers]))
    ess = (steps - burn) * n_walkers * n_ens / tau
    rhat = _rhat(chains)

    reasons = []
    if not enough:
        reasons.append(
            f"only {steps - burn} steps after burn-in, fewer than "
            f"{settings.autocorr_multiple:g} autocorrelation times ({np.max(tau):.1f})"
        )
    if not np.all(rhat < settings.rhat_max):
        worst = int(np.argmax(rhat))
        reasons.append(f"R-hat {rhat[worst]:.4f} >= {settings.rhat_max} for parameter {worst}")
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
        rhat=rhat,
        converged=not reasons,
        reasons=reasons,
    )
