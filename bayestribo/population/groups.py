"""The population of repeats per group: a mean and a between-run σ per parameter.

Runs are grouped by any metadata key (``load_N``, ``lubricant``, ``water_mass_fraction``
...). Within a group, each parameter is drawn from Normal(mean, σ²), independently
across parameters (:mod:`bayestribo.population.likelihood`); groups are independent, so
each is sampled on its own, and the pooled population treats all runs as one group.
The posterior of σ is the Bayesian answer to a "standard deviation of three repeats".
"""

from __future__ import annotations

import itertools
import zlib
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.population.hyperpriors import SigmaPriorSpec, resolve, sigma_priors
from bayestribo.population.jobs import run_jobs
from bayestribo.population.likelihood import MarginalLikelihood
from bayestribo.population.sampler import sample_hyperparameters
from bayestribo.population.samples import FitLike, RunSamples, as_run_samples
from bayestribo.summary import ParameterSummary, check_prob, summarize

__all__ = [
    "POOLED",
    "GroupPosterior",
    "Population",
    "difference",
    "fit_group",
    "group_words",
    "population",
    "population_jobs",
]

#: Label of the population pooled over all groups.
POOLED = "all"


def _water(value: str) -> str:
    try:
        return f"water {100.0 * float(value):.3g} % by mass"
    except ValueError:
        return f"water {value}"


#: How a grouping key's value reads (docs/run-format.md's keys).
_GROUP_WORDS = {
    "law": lambda v: f"law {v}",
    "lubricant": lambda v: v,
    "water_mass_fraction": _water,
    "load_N": lambda v: f"N = {v} N",
}


def group_words(label: str) -> str:
    """A group's label as a reader writes it.

    Parameters
    ----------
    label : str
        A group label as the populations name them, ``key=value`` pairs joined by
        commas (``lubricant=glycerol,water_mass_fraction=0.0055,load_N=0.12``), or
        :data:`POOLED`.

    Returns
    -------
    str
        ``"glycerol, water 0.55 % by mass, N = 0.12 N"``: the lubricant by name, the
        water mass fraction in per cent, the load with its unit; other keys as
        ``key=value``; ``"all runs"`` for the pooled population.
    """
    if label == POOLED:
        return "all runs"
    parts = []
    for item in str(label).split(","):
        key, sep, value = item.partition("=")
        parts.append(_GROUP_WORDS[key](value) if sep and key in _GROUP_WORDS else item)
    return ", ".join(parts)


@dataclass(frozen=True)
class GroupPosterior:
    """Posterior of one group's population.

    Attributes
    ----------
    label : str
        ``"<key>=<value>"``, or :data:`POOLED`.
    value : object
        The group's value of the grouping key (None when pooled).
    runs : tuple of str
        Names of the runs in the group.
    parameters : tuple of str
        Parameter names.
    mean, sigma : dict of str to ndarray
        Posterior samples of the population mean and between-run σ per parameter.
    sigma_prior : dict of str to str
        Description of the σ prior of each parameter.
    diagnostics : dict
        Sampler diagnostics (:class:`bayestribo.population.sampler.HyperSamples`).
    """

    label: str
    value: Any
    runs: tuple[str, ...]
    parameters: tuple[str, ...]
    mean: dict[str, NDArray[np.float64]]
    sigma: dict[str, NDArray[np.float64]]
    sigma_prior: dict[str, str]
    diagnostics: dict[str, Any] = field(default_factory=dict)

    def summary(self, prob: float = 0.95) -> dict[str, dict[str, ParameterSummary]]:
        """Per parameter, posterior summaries of the population mean and of σ."""
        return {
            name: {
                "mean": ParameterSummary.from_samples(self.mean[name], prob),
                "sigma": ParameterSummary.from_samples(self.sigma[name], prob),
            }
            for name in self.parameters
        }

    def to_dict(self, prob: float = 0.95) -> dict[str, Any]:
        """JSON-ready summary: per parameter the mean's and σ's posterior summaries."""
        return {
            "label": self.label,
            "value": self.value,
            "runs": list(self.runs),
            "n_runs": len(self.runs),
            "parameters": {
                name: {
                    "mean": summarize(self.mean[name], prob),
                    "sigma": summarize(self.sigma[name], prob),
                    "sigma_prior": self.sigma_prior[name],
                }
                for name in self.parameters
            },
            "diagnostics": dict(self.diagnostics),
        }


def difference(
    a: GroupPosterior, b: GroupPosterior, parameter: str, prob: float = 0.95, *, seed: int = 0
) -> dict[str, Any]:
    """Posterior of mean_a − mean_b for one parameter (independent groups).

    The two groups' posteriors are independent, so draws are paired after a seeded
    shuffle of each. Returns :func:`~bayestribo.summary.summarize` of the
    difference plus ``prob_positive`` = P(mean_a > mean_b | data).
    """
    if parameter not in a.mean or parameter not in b.mean:
        raise BayestriboError(f"parameter: {parameter!r} is not in both groups")
    rng = np.random.default_rng(seed)
    n = min(len(a.mean[parameter]), len(b.mean[parameter]))
    da = rng.permutation(a.mean[parameter])[:n]
    db = rng.permutation(b.mean[parameter])[:n]
    d = da - db
    out = summarize(d, prob)
    out.update({"a": a.label, "b": b.label, "prob_positive": float(np.mean(d > 0))})
    return out


@dataclass(frozen=True)
class Population:
    """The population of repeats: per-group and pooled posteriors.

    Attributes
    ----------
    by : str, tuple of str or None
        The grouping key(s).
    parameters : tuple of str
        Parameter names.
    groups : dict
        Group value -> :class:`GroupPosterior`, sorted by value.
    pooled : GroupPosterior or None
        All runs as one population.
    """

    by: str | tuple[str, ...] | None
    parameters: tuple[str, ...]
    groups: dict[Any, GroupPosterior]
    pooled: GroupPosterior | None

    def difference(self, parameter: str, a: Any, b: Any, prob: float = 0.95) -> dict[str, Any]:
        """Posterior of the difference of two groups' means (group values ``a``, ``b``)."""
        for value in (a, b):
            if value not in self.groups:
                raise BayestriboError(
                    f"group: {value!r} is not among the groups {list(self.groups)}"
                )
        return difference(self.groups[a], self.groups[b], parameter, prob)

    def differences(self, parameter: str, prob: float = 0.95) -> list[dict[str, Any]]:
        """Differences of every pair of groups that both model ``parameter`` (a before b
        in the group order; groups of another law or series may not)."""
        return [
            self.difference(parameter, a, b, prob)
            for a, b in itertools.combinations(self.groups, 2)
            if parameter in self.groups[a].parameters and parameter in self.groups[b].parameters
        ]

    def summary(self, prob: float = 0.95) -> dict[str, dict[str, dict[str, ParameterSummary]]]:
        """:meth:`GroupPosterior.summary` of every group and of the pooled population.

        Parameters
        ----------
        prob : float
            Probability of the equal-tailed credible intervals, in (0, 1).

        Returns
        -------
        dict
            ``{group label: {parameter: {"mean": ParameterSummary, "sigma": ...}}}``,
            the groups in their order, then the pooled population under its label
            (:data:`POOLED`) when there is one.
        """
        check_prob(prob)
        members = [*self.groups.values(), *([] if self.pooled is None else [self.pooled])]
        return {g.label: g.summary(prob) for g in members}

    def to_dict(self, prob: float = 0.95) -> dict[str, Any]:
        """JSON-ready summary of every group, the pooled population and the differences."""
        return {
            "by": self.by,
            "parameters": list(self.parameters),
            "groups": [g.to_dict(prob) for g in self.groups.values()],
            "pooled": None if self.pooled is None else self.pooled.to_dict(prob),
            "differences": {name: self.differences(name, prob) for name in self.parameters},
        }


def _group_seed(seed: int, label: str) -> int:
    """A seed per group from the campaign seed and the group's label (not its position)."""
    return int(np.random.SeedSequence([seed, zlib.crc32(label.encode())]).generate_state(1)[0])


def fit_group(
    label: str,
    value: Any,
    runs: Sequence[RunSamples],
    parameters: tuple[str, ...],
    priors: Mapping[str, SigmaPriorSpec],
    seed: int,
    sampler_kwargs: Mapping[str, Any],
) -> GroupPosterior:
    """Sample one group's population (a job of :func:`population_jobs`).

    Parameters
    ----------
    label : str
        The group's label; with ``seed`` it sets the sampler's seed.
    value : object
        The group's value of the grouping key (None when pooled).
    runs : sequence of RunSamples
        The group's runs.
    parameters : tuple of str
        Parameter names.
    priors : mapping of str to SigmaPriorSpec
        Prior on the between-run σ of each parameter (the default resolved on the
        group's runs, :func:`bayestribo.population.hyperpriors.resolve`).
    seed : int
        Campaign seed.
    sampler_kwargs : mapping
        ``n_walkers``, ``max_steps``, ``progress``, ``non_negative`` of
        :func:`bayestribo.population.sampler.sample_hyperparameters`.
    """
    like = MarginalLikelihood(runs, parameters)
    resolved = {p: resolve(priors[p], [np.std(r.values[p]) for r in runs]) for p in parameters}
    hyper = sample_hyperparameters(
        like, [resolved[p] for p in parameters], seed=_group_seed(seed, label), **sampler_kwargs
    )
    return GroupPosterior(
        label=label,
        value=value,
        runs=tuple(r.name for r in runs),
        parameters=parameters,
        mean={p: hyper.beta[:, 0, j] for j, p in enumerate(parameters)},
        sigma={p: hyper.sigma[:, j] for j, p in enumerate(parameters)},
        sigma_prior={p: resolved[p].describe() for p in parameters},
        diagnostics=hyper.diagnostics,
    )


def _sort_key(value: Any) -> tuple[Any, ...]:
    if isinstance(value, tuple):
        return tuple(_sort_key(v) for v in value)
    return (0, value) if isinstance(value, int | float) else (1, str(value))


def population(
    runs: Iterable[RunSamples | FitLike],
    parameters: Sequence[str] = ("zeta", "mu_k"),
    *,
    by: str | Sequence[str] | None = None,
    pooled: bool = True,
    sigma_prior: Mapping[str, SigmaPriorSpec | float] | None = None,
    seed: int = 0,
    max_samples: int | None = 1000,
    n_walkers: int | None = None,
    max_steps: int = 10_000,
    prob: float = 0.95,
    progress: bool = False,
    executor: Executor | None = None,
    non_negative: Collection[str] | None = None,
) -> Population:
    """Infer the population of repeats from per-run posterior samples.

    Parameters
    ----------
    runs : iterable of RunSamples or fit results
        Per-run posteriors (fit results need ``samples``, ``prior_logpdf`` and
        ``metadata``, as :class:`bayestribo.inference.FitResult` has).
    parameters : sequence of str
        Parameters modelled jointly, default ζ and μ_k (dimensionless).
    by : str or sequence of str, optional
        Metadata key to group by (e.g. ``"load_N"``, ``"lubricant"``), or several keys
        (a group per combination; its value is then a tuple); None: only the pooled
        population.
    pooled : bool
        Also infer the population of all runs together.
    sigma_prior : mapping, optional
        Prior on the between-run σ per parameter: a prior object, or a scale
        for the default scale-free prior resolved per group
        (:func:`bayestribo.population.hyperpriors.sigma_priors`).
    seed : int
        Campaign seed; each group's sampler seed derives from it and the group label.
    max_samples : int, optional
        Per-run samples kept (a seeded random subset).
    n_walkers, max_steps : int
        Walkers per ensemble (None: 16, or twice the hyperparameters where that is
        more) and step ceiling of each group's sampler
        (:func:`bayestribo.population.sampler.sample_hyperparameters`).
    prob : float
        Only checked here; intervals are chosen when summarising.
    progress : bool
        Show emcee's progress bars.
    executor : concurrent.futures.Executor, optional
        Sample the groups on it, side by side (a process pool, a Dask client's
        executor); each group's seed follows from its label, so the result is the same
        as in series. Warnings of the groups are given again here.
    non_negative : collection of str, optional
        Parameters whose population mean cannot be negative; default
        :data:`bayestribo.population.sampler.NON_NEGATIVE`.

    Returns
    -------
    Population

    Raises
    ------
    BayestriboError
        If a run lacks the grouping key or a parameter, or nothing is asked for.
    """
    jobs, assemble = population_jobs(
        runs,
        parameters,
        by=by,
        pooled=pooled,
        sigma_prior=sigma_prior,
        seed=seed,
        max_samples=max_samples,
        n_walkers=n_walkers,
        max_steps=max_steps,
        prob=prob,
        progress=progress,
        non_negative=non_negative,
    )
    return assemble(run_jobs(fit_group, jobs, executor))


def population_jobs(
    runs: Iterable[RunSamples | FitLike],
    parameters: Sequence[str] = ("zeta", "mu_k"),
    *,
    by: str | Sequence[str] | None = None,
    pooled: bool = True,
    sigma_prior: Mapping[str, SigmaPriorSpec | float] | None = None,
    seed: int = 0,
    max_samples: int | None = 1000,
    n_walkers: int | None = None,
    max_steps: int = 10_000,
    prob: float = 0.95,
    progress: bool = False,
    non_negative: Collection[str] | None = None,
) -> tuple[list[tuple[Any, ...]], Callable[[Sequence[GroupPosterior]], Population]]:
    """The independent samplers of :func:`population`, to run on a shared queue.

    Parameters are those of :func:`population`. Returns the arguments of one
    :func:`fit_group` call per group (the pooled population last) and the function
    that assembles their results, in that order, into the :class:`Population`; so
    ``assemble([fit_group(*job) for job in jobs])`` is ``population(...)``.
    """
    check_prob(prob)
    parameters = tuple(parameters)
    if not parameters:
        raise BayestriboError("parameters: expected at least one parameter name")
    if by is None and not pooled:
        raise BayestriboError("by, pooled: nothing to infer (no grouping key and pooled=False)")
    samples = as_run_samples(runs, parameters, max_samples=max_samples, seed=seed)
    priors = sigma_priors(parameters, sigma_prior)
    kwargs = {
        "n_walkers": n_walkers,
        "max_steps": max_steps,
        "progress": progress,
        "non_negative": None if non_negative is None else tuple(sorted(non_negative)),
    }
    jobs: list[tuple[Any, ...]] = []
    if by is not None:
        keys = (by,) if isinstance(by, str) else tuple(by)
        if not keys:
            raise BayestriboError("by: expected a metadata key or a non-empty sequence of keys")
        members: dict[Any, list[RunSamples]] = {}
        for run in samples:
            for key in keys:
                if key not in run.metadata or run.metadata[key] is None:
                    raise BayestriboError(f"run {run.name!r}: metadata has no {key!r} to group by")
            value = tuple(run.metadata[k] for k in keys)
            members.setdefault(value[0] if len(keys) == 1 else value, []).append(run)
        for group in members.values():
            group.sort(key=lambda r: r.name)  # results independent of the runs' order
        for value in sorted(members, key=_sort_key):
            values = (value,) if len(keys) == 1 else value
            label = ",".join(f"{k}={v}" for k, v in zip(keys, values, strict=True))
            jobs.append((label, value, members[value], parameters, priors, seed, kwargs))
    samples.sort(key=lambda r: r.name)
    if pooled:
        jobs.append((POOLED, None, samples, parameters, priors, seed, kwargs))
    by_keys = by if by is None or isinstance(by, str) else tuple(by)

    def assemble(fitted: Sequence[GroupPosterior]) -> Population:
        fitted = list(fitted)
        if len(fitted) != len(jobs):
            raise BayestriboError(f"fitted: expected {len(jobs)} groups, got {len(fitted)}")
        whole = fitted.pop() if pooled else None
        return Population(by_keys, parameters, {g.value: g for g in fitted}, whole)

    return jobs, assemble
