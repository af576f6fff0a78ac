"""Which dissipation law does a run support: viscous only, Coulomb only, or both?

Each run is fitted three times with the single-run model of :mod:`bayestribo.inference`
(the same Π increments, noise model, likelihood and sampler):

* ``"viscous"``: ζ free, no friction (μ_k = μ_s = 0);
* ``"coulomb"``: friction free (μ_k, μ_s/μ_k), ζ = 0;
* ``"both"``: ζ and friction free (the default fit of a run with contact).

The laws are compared by their expected log pointwise predictive density estimated
with Pareto-smoothed importance-sampling leave-one-out cross-validation (PSIS-LOO,
Vehtari, Gelman & Gabry 2017) over the Π increments, through
:func:`arviz.compare`.

Verdict. The law with the highest ``elpd_loo`` is the best. A law is *as good* as
the best when its difference is below 4 or below two standard errors of the
difference (Sivula, Magnusson & Vehtari 2020: smaller differences are not reliably
resolved). Among the laws as good as the best, the verdict is the simplest (one
mechanism before two); a Pareto k above 0.7 is reported, since the estimate is then
unreliable for that law.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bayestribo import DEFAULT_SEED
from bayestribo.errors import BayestriboError
from bayestribo.inference.assemble import pointwise_log_likelihood
from bayestribo.inference.pipeline import PreparedRun, Sampled, build_posterior, prepare, sample
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.io.run import Run
from bayestribo.signal.increments import PiData

__all__ = ["LAWS", "LawComparison", "compare_dissipation_laws"]

#: Dissipation laws and the number of mechanisms each has.
LAWS: Mapping[str, int] = {"viscous": 1, "coulomb": 1, "both": 2}
#: elpd difference below which two laws are not told apart.
SMALL_ELPD_DIFFERENCE = 4.0
#: Pareto k above which PSIS-LOO is unreliable.
PARETO_K_LIMIT = 0.7


@dataclass(frozen=True)
class LawComparison:
    """PSIS-LOO comparison of the dissipation laws of one run.

    Attributes
    ----------
    run_name : str
        The run.
    table : dict
        Law -> ``elpd_loo``, ``se``, ``p_loo``, ``elpd_diff``, ``dse``, ``weight``,
        ``rank``, ``pareto_k_max``, ``converged``, and the posterior medians.
    best : str
        Law with the highest elpd_loo.
    verdict : str
        Simplest law as good as the best (see the module notes).
    as_good : list of str
        Laws as good as the best (the best included).
    warnings : list of str
        Unreliable estimates (Pareto k) and unconverged fits.
    """

    run_name: str
    table: dict[str, dict[str, Any]]
    best: str
    verdict: str
    as_good: list[str]
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "run_name": self.run_name,
            "best": self.best,
            "verdict": self.verdict,
            "as_good": list(self.as_good),
            "table": self.table,
            "warnings": list(self.warnings),
        }


def _posterior(law: str, data: PiData, model: str, discrepancy: bool) -> Posterior:
    """The posterior of one law: viscous has no friction, Coulomb has ζ fixed at 0."""
    return build_posterior(
        data,
        model=model,
        friction=law != "viscous",
        discrepancy=discrepancy,
        fixed={"zeta": 0.0} if law == "coulomb" else None,
    )


def _loo(idata: Any) -> float:
    """Largest Pareto k of the PSIS-LOO of one law (a high k is reported, not warned)."""
    import arviz as az

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        loo = az.loo(idata, pointwise=True)
    return float(np.max(np.asarray(loo.pareto_k)))


def _fit_law(
    law: str,
    prepared: PreparedRun,
    settings: SamplerSettings,
    rng: np.random.Generator,
    model: str,
    discrepancy: bool,
    nested_start: Mapping[str, float] | None,
) -> tuple[Sampled, Any]:
    """Sample one law's posterior; its InferenceData holds the pointwise log-likelihood."""
    import arviz as az

    posterior = _posterior(law, prepared.data, model, discrepancy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sampled = sample(
            posterior, prepared.decay, settings=settings, seed=rng, also_start_at=nested_start
        )
    chains = sampled.run.chains
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        idata = az.from_dict(
            posterior={name: chains[..., i] for i, name in enumerate(posterior.names)},
            log_likelihood={"pi": pointwise_log_likelihood(posterior, chains)},
        )
    return sampled, idata


def _verdict(
    laws: Sequence[str], table: dict[str, dict[str, Any]], frame: Any
) -> tuple[str, list[str], str]:
    """Best law, the laws as good as the best, and the simplest of those."""
    best = str(frame.index[0])
    as_good = [
        law
        for law in laws
        if law == best
        or table[law]["elpd_diff"] < max(SMALL_ELPD_DIFFERENCE, 2.0 * table[law]["dse"])
    ]
    verdict = min(as_good, key=lambda law: (LAWS[law], table[law]["rank"]))
    return best, as_good, verdict


def compare_dissipation_laws(
    run: Run | str | os.PathLike[str],
    *,
    laws: Sequence[str] = ("viscous", "coulomb", "both"),
    seed: int | None = DEFAULT_SEED,
    model: str = "exact",
    n_walkers: int = 16,
    n_ensembles: int = 2,
    max_steps: int = 20_000,
    grid_points: int | None = None,
    skip_oscillations: int = 1,
    discrepancy: bool = False,
    read_options: Mapping[str, Any] | None = None,
) -> LawComparison:
    """Fit a run under each dissipation law and compare them by PSIS-LOO.

    Parameters
    ----------
    run : Run or path
        The recording, as for :func:`bayestribo.inference.fit`.
    laws : sequence of str
        Laws to compare, among :data:`LAWS` (at least two).
    seed : int or None
        Seed of all three fits (each law gets its own stream from it); default
        :data:`bayestribo.DEFAULT_SEED`.
    model, n_walkers, n_ensembles, max_steps, grid_points, skip_oscillations, discrepancy
        As in :func:`bayestribo.inference.fit`.
    read_options : mapping, optional
        Options of :func:`bayestribo.read_run` when ``run`` is a path.

    Returns
    -------
    LawComparison

    Raises
    ------
    BayestriboError
        If a law is unknown or fewer than two are given.
    """
    import arviz as az

    laws = list(dict.fromkeys(laws))
    unknown = [law for law in laws if law not in LAWS]
    if unknown or len(laws) < 2:
        raise BayestriboError(f"laws: expected two or more of {list(LAWS)}, got {list(laws)}")
    root = np.random.SeedSequence(seed)
    data_seed, *law_seeds = root.spawn(1 + len(LAWS))
    prepared = prepare(
        run,
        skip_oscillations=skip_oscillations,
        grid_points=grid_points,
        seed=np.random.default_rng(data_seed),
        read_options=read_options,
    )
    settings = SamplerSettings(n_walkers=n_walkers, n_ensembles=n_ensembles, max_steps=max_steps)
    idatas, table, notes = {}, {}, []
    optima: dict[str, dict[str, float]] = {}
    # Viscous first: its optimum is a starting point of "both".
    for law in sorted(laws, key=lambda law: law != "viscous"):
        # Each law's stream depends on the law, not on which others are compared.
        rng = np.random.default_rng(law_seeds[list(LAWS).index(law)])
        nested = None
        if law == "both" and "viscous" in optima:
            # Viscous is "both" with no friction: start there too (a weak friction
            # is otherwise hard to find from the friction-first default start).
            nested = {**optima["viscous"], "mu_k": 1e-6 * abs(prepared.data.y0), "mu_s_ratio": 1.2}
        sampled, idatas[law] = _fit_law(law, prepared, settings, rng, model, discrepancy, nested)
        s = sampled.run
        names = sampled.posterior.names
        best_row = np.unravel_index(np.argmax(s.log_prob), s.log_prob.shape)
        optima[law] = dict(zip(names, s.chains[best_row], strict=True))
        k_max = _loo(idatas[law])
        table[law] = {
            "pareto_k_max": k_max,
            "converged": bool(s.converged),
            "median": {n: float(np.median(s.chains[..., i])) for i, n in enumerate(names)},
        }
        if k_max > PARETO_K_LIMIT:
            notes.append(f"{law}: Pareto k up to {k_max:.2f}; its PSIS-LOO is unreliable")
        if not s.converged:
            notes.append(f"{law}: sampler not converged ({'; '.join(s.reasons)})")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frame = az.compare(idatas, ic="loo")
    for law, row in frame.iterrows():
        table[str(law)].update(
            {
                key: float(row[key])
                for key in ("rank", "elpd_loo", "p_loo", "elpd_diff", "weight", "se", "dse")
            }
        )
    best, as_good, verdict = _verdict(laws, table, frame)
    return LawComparison(prepared.name, table, best, verdict, as_good, notes)
