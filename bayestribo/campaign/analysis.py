"""Campaign analysis: per-run fits → populations per group, ζ₀, ζ_k, d_k and load trends.

The runs of a campaign are split into tests without contact (``load_N`` = 0, or no
μ_k in the fit), whose pooled population gives ζ₀, and tests with contact, whose ζ
and μ_k populations are inferred per group of the ``by`` keys (default lubricant,
water fraction and load). For every series (the ``by`` keys other than the load)
with runs at two or more loads, the trend against load is inferred; for glycerol-water
series with two or more water fractions, the trend against the kinematic viscosity of
Eq. 43 (labels ``viscosity:...``; the paper's ζ rises with ν, Fig. 10a). Derived per
group (section 2.5 of the paper):

* ζ_k = ζ̄ − ζ₀ (group mean minus the pooled ζ₀, independent posteriors);
* d_k = 2 ζ_k √(k m) / N = 2 ζ_k m Ω / N [s/m] (√(km) is in N·s/m, divided by N),
  with m and Ω = 2πf from the runs' metadata, taken as exact (the metadata gives no
  uncertainty for them) and N the group's load.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from bayestribo._plural import count
from bayestribo.campaign.bands import group_runs, run_bands, run_metadata, swing_record
from bayestribo.campaign.dissipation import common_amplitudes, dissipation_samples, has_band
from bayestribo.errors import BayestriboError
from bayestribo.population.groups import Population, fit_group, population_jobs
from bayestribo.population.jobs import run_calls
from bayestribo.population.samples import FitLike, RunSamples, run_samples
from bayestribo.population.trend import Trend, trend
from bayestribo.summary import summarize

__all__ = ["DEFAULT_BY", "VISCOSITY_KEY", "CampaignAnalysis", "analyse_campaign"]

#: Metadata key of the kinematic viscosity computed with Eq. 43 [mm²/s].
VISCOSITY_KEY = "kinematic_viscosity_mm2_per_s"

#: Default grouping keys of a campaign.
DEFAULT_BY: tuple[str, ...] = ("lubricant", "water_mass_fraction", "load_N")


#: The law of a fit that does not say (a fit-like object of the paper's law).
_PAPER_LAW = "viscous+coulomb"


def _paper_quantity(name: str) -> dict[str, Any] | None:
    """How ζ or μ_k reads where a fit-like object does not describe it (the registry's
    words, as :func:`bayestribo.campaign.quantities.campaign_quantities` gives them)."""
    from bayestribo.model.laws.base import TERMS

    for term in ("viscous", "coulomb"):
        for p in TERMS[term].parameters:
            if p.name == name:
                return {
                    "name": p.name,
                    "symbol": p.symbol,
                    "unit": "1",
                    "label": p.label,
                    "term": term,
                    "non_negative": p.low >= 0.0,
                    "at_own_amplitude": False,
                }
    return None


def _law(result: Any) -> str:
    """The run's dissipation law (the paper's where a fit-like object does not say)."""
    return str(getattr(result, "law", None) or _PAPER_LAW)


def _has_friction(result: Any) -> bool:
    """A run with contact: a load that is not an explicit 0, and, where the load is
    missing, a friction fitted (as μ_k, or as a friction displacement). A run whose load
    is missing is never taken for a run in air where it has a friction term: it is
    excluded for want of a load to group by. A run with a load is a run with contact in
    every law (a law of drag alone included)."""
    load = (getattr(result, "metadata", {}) or {}).get("load_N")
    if load == 0:
        return False
    if isinstance(load, int | float) and not isinstance(load, bool) and load > 0:
        return True
    names = getattr(result, "parameter_names", None)
    if names is not None and not {"mu_k", "friction_displacement"} & set(names):
        quantities = getattr(result, "quantities", None) or {}
        return any(q.get("term") and _is_friction(q["term"]) for q in quantities.values())
    return True


def _is_friction(term: str) -> bool:
    from bayestribo.model.laws.base import get_term

    try:
        return get_term(term).kind == "friction"
    except (KeyError, ValueError):
        return False


def _digest(result: Any, prob: float, max_samples: int | None, seed: int) -> Any:
    """The run's digest: the quantities of its law (a fit result), or ζ and μ_k (a
    fit-like object without a law, as populations take)."""
    from bayestribo.campaign.digest import PARAMETERS, FitDigest, digest_fit

    if isinstance(result, FitDigest):
        return result
    if hasattr(result, "law") and hasattr(result, "attrs"):
        return digest_fit(result, prob=prob, max_samples=max_samples, seed=seed)
    return digest_fit(result, prob=prob, max_samples=max_samples, seed=seed, parameters=PARAMETERS)


def _quantities(result: Any) -> dict[str, dict[str, Any]]:
    """Name -> description of each quantity a run's digest keeps, in its law's order."""
    described = getattr(result, "quantities", None) or {}
    out = {}
    for name in getattr(result, "draws", {}):
        out[name] = described.get(name) or _paper_quantity(name) or {"name": name}
    return out


def _run_summary(result: Any, prob: float) -> dict[str, Any]:
    md = dict(getattr(result, "metadata", {}) or {})
    out: dict[str, Any] = {"run_id": md.get("run_id") or getattr(result, "run_name", None)}
    for key in ("series", "lubricant", "water_mass_fraction", "load_N", "repeat"):
        out[key] = md.get(key)
    out["law"] = _law(result)
    kept = result.summary_at(prob)
    for p, s in kept.items():
        out[p] = {"median": s["median"], "interval": s["interval"], "kind": s.get("kind")}
    out["converged"] = bool(getattr(result, "converged", True))
    return out


@dataclass(frozen=True)
class CampaignAnalysis:
    """Everything the campaign reports across runs.

    Attributes
    ----------
    by : tuple of str
        Grouping keys of the runs with contact.
    runs : list of dict
        Per-run summaries (metadata keys, the law, and the medians and intervals of
        the law's quantities).
    contact : Population or None
        Populations of the law's quantities per group (pooled over all runs with
        contact only when the load is the sole grouping key and one law is fitted).
        Where the runs were fitted in several laws, the law is the first grouping
        key (``law=...``): runs of two laws are never one population.
    zeta0 : Population or None
        Population of the drag quantities (ζ₀ in the paper's law) over the runs
        without contact, pooled (by law where they have several).
    series : Population or None
        Populations pooled over the loads of each series (the grouping keys other
        than the load), when there are such keys.
    trends : dict
        Series label -> :class:`Trend` against ``covariate``.
    derived : list of dict
        Per contact group: ζ_k and d_k summaries.
    excluded : list of dict
        Runs left out of the populations, ``{"run", "reason"}``: a fit that piles on
        a prior bound (no measurement), or a run without a grouping key the other
        runs have.
    laws : dict of str to list of str
        Each law fitted, with its runs.
    quantities : dict of str to dict
        Each quantity compared: its symbol, unit, label and term
        (:mod:`bayestribo.campaign.quantities`).
    left_out : dict of str to str
        Parameters of the laws not compared across runs, with why.
    dissipation : Population or None
        The law-free answer: populations of ΔE at common swings of each series
        (:mod:`bayestribo.campaign.dissipation`), per group of the grouping keys,
        whatever law each run was fitted in.
    dissipation_trends : dict
        Series label -> :class:`Trend` of ΔE at those swings against ``covariate``.
    dissipation_quantities : dict of str to dict
        Each ΔE at a swing compared: its symbol, unit and label (apart from
        :attr:`quantities`, the laws' own).
    dissipation_at_swing : dict or None
        Each analysed run's ΔE from its law's band at one swing every run of the
        populations reaches (:func:`bayestribo.campaign.bands.swing_record`:
        ``amplitude`` and ``rows``, each run's ``mean`` with its ``interval``); None
        where no fit holds a band.
    sigma_scales : dict of str to float
        The scale (typical between-run σ) of each quantity's σ prior (module notes of
        :mod:`bayestribo.population.hyperpriors`; a quantity without a default takes
        half the median over its runs, :func:`sigma_scale`).
    """

    by: tuple[str, ...]
    covariate: str
    prob: float
    runs: list[dict[str, Any]]
    contact: Population | None
    zeta0: Population | None
    series: Population | None = None
    trends: dict[str, Trend] = field(default_factory=dict)
    derived: list[dict[str, Any]] = field(default_factory=list)
    excluded: list[dict[str, str]] = field(default_factory=list)
    laws: dict[str, list[str]] = field(default_factory=dict)
    quantities: dict[str, dict[str, Any]] = field(default_factory=dict)
    left_out: dict[str, str] = field(default_factory=dict)
    sigma_scales: dict[str, float] = field(default_factory=dict)
    dissipation: Population | None = None
    dissipation_trends: dict[str, Trend] = field(default_factory=dict)
    dissipation_quantities: dict[str, dict[str, Any]] = field(default_factory=dict)
    dissipation_at_swing: dict[str, Any] | None = None

    @property
    def converged(self) -> bool:
        """Whether every run's sampler and every population and trend sampler converged."""
        pops = [self.contact, self.zeta0, self.series, *self.trends.values()]
        pops += [self.dissipation, *self.dissipation_trends.values()]
        runs = all(r.get("converged", True) for r in self.runs)
        return runs and all(_population_converged(pop) for pop in pops if pop is not None)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready report."""
        p = self.prob
        return {
            "by": list(self.by),
            "covariate": self.covariate,
            "prob": p,
            "runs": self.runs,
            "contact": None if self.contact is None else self.contact.to_dict(p),
            "zeta0": None if self.zeta0 is None else self.zeta0.to_dict(p),
            "series": None if self.series is None else self.series.to_dict(p),
            "trends": {k: t.to_dict(p) for k, t in self.trends.items()},
            "derived": self.derived,
            "excluded": self.excluded,
            "converged": self.converged,
            "laws": self.laws,
            "quantities": self.quantities,
            "left_out": self.left_out,
            "sigma_scales": self.sigma_scales,
            "dissipation": None if self.dissipation is None else self.dissipation.to_dict(p),
            "dissipation_trends": {k: t.to_dict(p) for k, t in self.dissipation_trends.items()},
            "dissipation_quantities": self.dissipation_quantities,
            "dissipation_at_swing": self.dissipation_at_swing,
        }

    def group_rows(self) -> list[dict[str, Any]]:
        """One row per group and parameter (CSV table)."""
        rows = []
        pops = [
            ("contact", self.contact),
            ("pooled over loads", self.series),
            ("no contact", self.zeta0),
            ("ΔE (law-free)", self.dissipation),
        ]
        for kind, pop in pops:
            if pop is None:
                continue
            groups = list(pop.groups.values()) + ([pop.pooled] if pop.pooled else [])
            for g in groups:
                for name in g.parameters:
                    m, s = summarize(g.mean[name], self.prob), summarize(g.sigma[name], self.prob)
                    rows.append(
                        {
                            "kind": kind,
                            "group": g.label,
                            "n_runs": len(g.runs),
                            "parameter": name,
                            "mean_median": m["median"],
                            "mean_low": m["interval"][0],
                            "mean_high": m["interval"][1],
                            "sigma_median": s["median"],
                            "sigma_low": s["interval"][0],
                            "sigma_high": s["interval"][1],
                            "sigma_prior": g.sigma_prior[name],
                            "converged": g.diagnostics.get("converged"),
                        }
                    )
        return rows

    def trend_rows(self) -> list[dict[str, Any]]:
        """One row per series and parameter (CSV table)."""
        rows = []
        every = [*self.trends.items(), *self.dissipation_trends.items()]
        for label, t in every:
            for name in t.parameters:
                s = t.slope_summary(name, self.prob)
                rows.append(
                    {
                        "series": label,
                        "covariate": t.covariate,
                        "parameter": name,
                        "slope_median": s["median"],
                        "slope_low": s["interval"][0],
                        "slope_high": s["interval"][1],
                        "prob_positive": s["prob_positive"],
                        "prob_sign": s["prob_sign"],
                        "n_runs": len(t.runs),
                    }
                )
        return rows


def _paired_difference(a: np.ndarray, b: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    n = min(len(a), len(b))
    return rng.permutation(a)[:n] - rng.permutation(b)[:n]


def _derived(contact: Population, zeta0: Population, runs: Sequence[Any], seed: int, prob: float):
    """ζ_k and d_k per group (module notes): where ζ is a quantity of both populations
    and the runs without contact are pooled."""
    if zeta0.pooled is None or "zeta" not in zeta0.parameters:
        return []
    rng = np.random.default_rng(seed)
    by_name = {str(r.metadata.get("run_id") or getattr(r, "run_name", None)): r for r in runs}
    out = []
    for g in contact.groups.values():
        if "zeta" not in g.parameters:
            continue
        zeta_k = _paired_difference(g.mean["zeta"], zeta0.pooled.mean["zeta"], rng)
        row: dict[str, Any] = {"group": g.label, "zeta_k": summarize(zeta_k, prob)}
        md = by_name[g.runs[0]].metadata if g.runs[0] in by_name else {}
        load, mass, freq = md.get("load_N"), md.get("mass_kg"), md.get("natural_frequency_Hz")
        if load and mass and freq:
            d_k = 2.0 * zeta_k * mass * 2.0 * math.pi * freq / load
            row["d_k_s_per_m"] = summarize(d_k, prob)
            row["load_N"] = load
        out.append(row)
    return out


def _viscosity_series(
    samples: list[RunSamples], keys: tuple[str, ...]
) -> list[tuple[str, list[RunSamples]]]:
    """Series of trends against the kinematic viscosity of Eq. 43 (glycerol-water).

    A series is a value of the grouping keys other than the water fraction, whose
    lubricant name contains "glycerol", with runs at two or more water fractions.
    Returns (label, runs with the viscosity [mm²/s] in their metadata) per series.
    """
    from bayestribo.model.viscosity import glycerol_water_viscosity

    if "water_mass_fraction" not in keys:
        return []
    other = tuple(k for k in keys if k != "water_mass_fraction")
    series: dict[tuple[Any, ...], list[RunSamples]] = {}
    for s in samples:
        if "glycerol" in str(s.metadata.get("lubricant", "")):
            series.setdefault(tuple(s.metadata.get(k) for k in other), []).append(s)
    out = []
    for value, members in series.items():
        if len({m.metadata["water_mass_fraction"] for m in members}) < 2:
            continue
        with_nu = [
            RunSamples(
                m.name,
                m.values,
                m.log_prior,
                {
                    **m.metadata,
                    VISCOSITY_KEY: float(
                        glycerol_water_viscosity(m.metadata["water_mass_fraction"])
                    ),
                },
            )
            for m in members
        ]
        label = ",".join(f"{k}={v}" for k, v in zip(other, value, strict=True))
        out.append((f"viscosity:{label}", with_nu))
    return out


def _cost(n_runs: int, n_parameters: int, n_coefficients: int) -> float:
    """Relative cost of one population sampler: its likelihood's work per step (runs ×
    parameters × coefficients of the mean; a trend has two, a group one)."""
    return float(n_runs * n_parameters * n_coefficients)


def _trend_job(
    members: list[RunSamples], covariate: str, kw: dict[str, Any], names: tuple[str, ...]
) -> Trend:
    """One series' trend (a module-level function, for a process pool)."""
    return trend(members, covariate, names, **kw)


def sigma_scale(name: str, medians: Sequence[float], widths: Sequence[float]) -> float:
    """The scale of a quantity's between-run σ prior (its typical between-run σ).

    ζ and μ_k keep the package's default, 0.01 (:mod:`bayestribo.population.hyperpriors`:
    about half the paper's values). Any other quantity takes half the median over its
    runs of |posterior median|, the same proportion; where that is zero (every run at
    zero), the median width of the runs' intervals. The prior reaches up to 10 × the
    scale (:class:`bayestribo.population.hyperpriors.ScaleFree`), well above any
    spread the runs can show.

    Parameters
    ----------
    name : str
        The quantity.
    medians, widths : sequence of float
        Each run's posterior median and credible-interval width, in its unit.
    """
    from bayestribo.population.hyperpriors import DEFAULT_SIGMA_SCALES

    if name in DEFAULT_SIGMA_SCALES:
        return float(DEFAULT_SIGMA_SCALES[name])
    typical = 0.5 * float(np.median(np.abs(np.asarray(medians, dtype=float))))
    if typical > 0 and math.isfinite(typical):
        return typical
    width = float(np.median(np.asarray(widths, dtype=float)))
    return width if width > 0 and math.isfinite(width) else 1.0


def _common(runs: Sequence[Any], drag_only: bool = False) -> tuple[str, ...]:
    """The quantities every one of ``runs`` keeps, in the first run's order (the drag
    terms' only, for runs without contact)."""
    first = _quantities(runs[0])
    names = [
        n
        for n, q in first.items()
        if all(n in _quantities(r) for r in runs)
        and not (drag_only and _is_friction(str(q.get("term") or _term_of(n))))
    ]
    return tuple(names)


def _term_of(name: str) -> str:
    return str((_paper_quantity(name) or {}).get("term", ""))


def _name(result: Any) -> str:
    metadata = getattr(result, "metadata", {}) or {}
    return str(metadata.get("run_id") or getattr(result, "run_name", None) or "?")


def _unusable(result: Any) -> str | None:
    """Why a fit cannot enter a population, or None. A fit whose sampler did not
    converge still enters (its status and the exit status say so): a short campaign
    is a legitimate first look."""
    bound = list(getattr(result, "at_prior_bound", []) or [])
    if bound:
        names = ", ".join(str(b["parameter"]) for b in bound)
        return f"posterior piles on its prior's upper bound ({names}): no measurement"
    return None


def _population_converged(pop: Any) -> bool:
    groups = list(getattr(pop, "groups", {}).values())
    for extra in (getattr(pop, "pooled", None),):
        if extra is not None:
            groups.append(extra)
    if not groups:  # a trend: its own diagnostics
        return bool(getattr(pop, "diagnostics", {}).get("converged", True))
    return all(bool(g.diagnostics.get("converged", True)) for g in groups)


def analyse_campaign(
    results: Sequence[FitLike],
    by: Sequence[str] = DEFAULT_BY,
    *,
    covariate: str = "load_N",
    prob: float = 0.95,
    seed: int = 0,
    max_samples: int | None = 300,
    max_steps: int = 10_000,
    sigma_prior: Mapping[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    executor: Executor | None = None,
    dissipation: bool = False,
) -> CampaignAnalysis:
    """Populations, ζ₀, ζ_k, d_k and load trends of a campaign's fits, in any law.

    Each run's quantities are its law's (:mod:`bayestribo.campaign.quantities`: ζ and
    μ_k in the paper's law, c₂ [kg/m] for quadratic drag, the exponent α of a power
    law, ...). Runs fitted in different laws are never one population: the law is
    then the first grouping key. ζ₀, ζ_k and d_k are the paper's (module notes), made
    where ζ is a quantity of the runs with and without contact.

    Parameters
    ----------
    results : sequence of fit results
        One per run (``samples``, ``prior_logpdf``, ``metadata``, ``parameter_names``;
        a :class:`bayestribo.inference.FitResult` also gives its ``law``), or their
        digests (:func:`bayestribo.campaign.digest.digest_fit`, made with this
        ``prob``, ``max_samples`` and ``seed``), which give the same analysis and keep
        a campaign's memory flat in the number of runs.
    by : sequence of str
        Grouping keys of the runs with contact; keys that no such run has are left out.
    covariate : str
        Metadata key of the trends (a numeric key, default the load [N]).
    prob : float
        Credible-interval probability of the summaries.
    seed, max_samples, max_steps
        As in :func:`bayestribo.population.population`. Single-run posteriors of a
        tribometer record are far narrower than the spread between repeats, so 300
        samples per run carry the population likelihood (the importance-sampling
        effective sample size is checked and warned about if not).
    sigma_prior : mapping, optional
        Per quantity, a prior on its between-run σ or a scale; the others
        take :func:`sigma_scale`'s.
    progress : callable, optional
        Called with a one-line message before each population or trend is sampled
        (the command line prints it).
    executor : concurrent.futures.Executor, optional
        Sample the groups of each population and the trends side by side on it (the
        campaign's process pool or Dask); the results are those of a serial run.
    dissipation : bool
        Also infer the law-free answer across runs: populations and trends of ΔE at
        common swings (:mod:`bayestribo.campaign.dissipation`). Off by default: it
        doubles the population work of a campaign whose laws hold; ``bayestribo
        campaign`` turns it on with ``--law auto`` and ``--law-free``.
    """
    say = progress if progress is not None else (lambda message: None)
    results = [_digest(r, prob, max_samples, seed) for r in results]
    if not results:
        raise BayestriboError("results: no fitted runs to analyse")
    excluded: list[dict[str, str]] = []
    usable = []
    for r in results:
        reason = _unusable(r)
        if reason is None:
            usable.append(r)
        else:
            excluded.append({"run": _name(r), "reason": reason})
    contact_runs = [r for r in usable if _has_friction(r)]
    free_runs = [r for r in usable if not _has_friction(r)]
    kw = {"seed": seed, "max_steps": max_steps}
    keys = tuple(k for k in by if any(r.metadata.get(k) is not None for r in contact_runs))
    complete = []
    for r in contact_runs:
        missing = [k for k in keys if r.metadata.get(k) is None]
        if missing:
            excluded.append(
                {
                    "run": _name(r),
                    "reason": f"metadata has no {', '.join(map(repr, missing))} to group by "
                    "(the other runs have it); add it to the run's sidecar",
                }
            )
        else:
            complete.append(r)
    contact_runs = complete
    if not contact_runs and not free_runs:
        reasons = "; ".join(f"{e['run']}: {e['reason']}" for e in excluded)
        raise BayestriboError(f"results: no usable fitted run to analyse ({reasons})")
    laws: dict[str, list[Any]] = {}
    for r in contact_runs:
        laws.setdefault(_law(r), []).append(r)
    free_laws: dict[str, list[Any]] = {}
    for r in free_runs:
        free_laws.setdefault(_law(r), []).append(r)
    described: dict[str, dict[str, Any]] = {}
    left_out: dict[str, str] = {}
    for r in contact_runs + free_runs:
        for n, q in _quantities(r).items():
            described.setdefault(n, {k: v for k, v in q.items() if k != "name"})
        left_out.update(getattr(r, "left_out", None) or {})
    unknown = sorted(set(sigma_prior or {}) - set(described))
    if unknown:
        raise BayestriboError(
            f"sigma_prior: {unknown} not among the quantities compared {sorted(described)}"
        )
    # Every population, pooled population and trend is an independent posterior: all
    # go on one queue (costliest first), so no worker idles at the end of a phase.
    calls: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
    costs: list[float] = []
    finish: list[Callable[[list[Any]], None]] = []
    found: dict[str, list[Population]] = {
        "contact": [],
        "zeta0": [],
        "series": [],
        "dissipation": [],
    }
    dissipation_trends: dict[str, Trend] = {}
    laws_free: dict[str, dict[str, Any]] = {}
    trends: dict[str, Trend] = {}
    scales: dict[str, float] = {}

    def scales_of(runs: Sequence[Any], names: tuple[str, ...]) -> dict[str, float]:
        out = {}
        for n in names:
            rows = [r.summary_at(prob)[n] for r in runs]
            medians = [row["median"] for row in rows]
            widths = [row["interval"][1] - row["interval"][0] for row in rows]
            out[n] = sigma_scale(n, medians, widths)
        return out

    def options(runs: Sequence[Any], names: tuple[str, ...]) -> dict[str, Any]:
        own = scales_of(runs, names)
        for n, v in own.items():
            scales.setdefault(n, v)
        given = {n: v for n, v in (sigma_prior or {}).items() if n in names}
        non_negative = tuple(n for n in names if described.get(n, {}).get("non_negative"))
        return {"sigma_prior": {**own, **given}, "non_negative": non_negative}

    def add_population(
        key: str, runs: list[RunSamples], names: tuple[str, ...], extra: dict, **options
    ):
        jobs, assemble = population_jobs(runs, names, **options, **extra, **kw)
        start = len(calls)
        calls.extend((fit_group, job) for job in jobs)
        costs.extend(_cost(len(job[2]), len(names), 1) for job in jobs)

        def done(results: list[Any]) -> None:
            found[key].append(assemble(results[start : start + len(jobs)]))

        finish.append(done)

    def add_trend(
        label: str, members: list[RunSamples], on: str, names, extra, into=trends
    ) -> None:
        at = len(calls)
        calls.append((_trend_job, (members, on, {**kw, **extra}, names)))
        costs.append(_cost(len(members), len(names), 2))

        def done(results: list[Any]) -> None:
            into[label] = results[at]

        finish.append(done)

    several = len(laws) > 1
    for law, law_runs in laws.items():
        names = _common(law_runs)
        if not names:
            for r in law_runs:
                excluded.append({"run": _name(r), "reason": f"law {law}: no quantity to compare"})
            continue
        extra = options(law_runs, names)
        samples = [
            _with_law(run_samples(r, names, max_samples=max_samples, seed=seed), law, several)
            for r in law_runs
        ]
        law_keys = (("law",) if several else ()) + keys
        series_keys = tuple(k for k in law_keys if k != covariate)
        # Pooled over all runs with contact only if nothing but the load tells them
        # apart; otherwise pooled over the loads of each series.
        words = ", ".join(law_keys) or "none"
        fitted_in = f" fitted in {law}" if several else ""
        say(f"population of {count(len(samples), 'run')} with contact{fitted_in}, by {words}")
        add_population(
            "contact", samples, names, extra, by=law_keys or None, pooled=not series_keys
        )
        if series_keys and covariate in law_keys:
            say(f"populations pooled over {covariate}, by {', '.join(series_keys)}")
            add_population("series", samples, names, extra, by=series_keys, pooled=False)
        series: dict[tuple[Any, ...], list[RunSamples]] = {}
        for s in samples:
            series.setdefault(tuple(s.metadata.get(k) for k in series_keys), []).append(s)
        labels = []
        for value, members in series.items():
            xs = {m.metadata.get(covariate) for m in members}
            if len(xs) >= 2 and all(isinstance(x, int | float) for x in xs):
                label = ",".join(f"{k}={v}" for k, v in zip(series_keys, value, strict=True))
                labels.append(label or "all")
                add_trend(label or "all", members, covariate, names, extra)
        if labels:
            say(f"trends against {covariate}: {', '.join(labels)}")
        viscosity = _viscosity_series(samples, law_keys)
        if viscosity:
            say(f"trends against {VISCOSITY_KEY}: {', '.join(lab for lab, _ in viscosity)}")
        for label, members in viscosity:
            add_trend(label, members, VISCOSITY_KEY, names, extra)
    # The law-free answer: ΔE at swings every run of a series reaches, whatever its law.
    series_keys = tuple(k for k in keys if k != covariate)
    by_series: dict[tuple[Any, ...], list[Any]] = {}
    for r in contact_runs if dissipation else []:
        by_series.setdefault(tuple(r.metadata.get(k) for k in series_keys), []).append(r)
    for value, members in by_series.items():
        label = ",".join(f"{k}={v}" for k, v in zip(series_keys, value, strict=True)) or "all"
        if not any(has_band(r) for r in members):
            continue  # fit-like objects without turning points: nothing law-free to compare
        amplitudes = common_amplitudes(members)
        if amplitudes is None:
            say(f"ΔE (law-free) of {label}: its runs reach no common swing; not compared")
            continue
        drawn = [
            dissipation_samples(r, amplitudes, n_samples=max_samples or 300, seed=seed)
            for r in members
        ]
        names = tuple(drawn[0].values)
        for n in names:
            laws_free.setdefault(
                n,
                {
                    "symbol": n.replace("A=", ""),
                    "unit": str((getattr(members[0], "turning_points", None) or {}).get("unit")),
                    "label": "energy dissipated per cycle at this swing, from the turning "
                    "points (law-free)",
                    "term": None,
                    "non_negative": True,
                },
            )
        extra = {
            "sigma_prior": {
                n: (sigma_prior or {}).get(n)
                or sigma_scale(
                    n,
                    [float(np.mean(d.values[n])) for d in drawn],
                    [4.0 * float(np.std(d.values[n])) for d in drawn],  # ≈ the 95 % width
                )
                for n in names
            },
            "non_negative": names,
        }
        for n in names:
            scales.setdefault(n, float(extra["sigma_prior"][n]))
        say(
            f"ΔE (law-free) of {label} at {count(len(names), 'common swing')}, "
            f"{count(len(drawn), 'run')}"
        )
        add_population("dissipation", drawn, names, extra, by=keys or None, pooled=not keys)
        if len({d.metadata.get(covariate) for d in drawn}) >= 2 and all(
            isinstance(d.metadata.get(covariate), int | float) for d in drawn
        ):
            add_trend(label, drawn, covariate, names, extra, into=dissipation_trends)
    several_free = len(free_laws) > 1
    for law, law_runs in free_laws.items():
        names = _common(law_runs, drag_only=True)
        if not names:
            for r in law_runs:
                reason = f"law {law}: no drag term to compare without contact"
                excluded.append({"run": _name(r), "reason": reason})
            continue
        extra = options(law_runs, names)
        zs = [
            _with_law(run_samples(r, names, max_samples=max_samples, seed=seed), law, several_free)
            for r in law_runs
        ]
        symbols = ", ".join(str(described.get(n, {}).get("symbol", n)) for n in names)
        symbols = "ζ₀" if names == ("zeta",) else f"{symbols} without contact"
        fitted_in = f" fitted in {law}" if several_free else ""
        say(f"{symbols} from {count(len(zs), 'run')} without contact{fitted_in}")
        if several_free:
            add_population("zeta0", zs, names, extra, by=("law",), pooled=False)
        else:
            add_population("zeta0", zs, names, extra)
    say(f"sampling {len(calls)} population and trend posteriors")
    step = max(1, len(calls) // 10)

    def sampled(finished: int, total: int) -> None:
        if finished == total or finished % step == 0:
            say(f"sampled {finished} of {total} posteriors")

    results_of_calls = run_calls(calls, executor, costs, done=sampled)
    for done in finish:
        done(results_of_calls)
    contact = _merge(found["contact"])
    dissipation = _merge(found["dissipation"])
    zeta0 = _merge(found["zeta0"])
    series_pop = _merge(found["series"])
    derived = (
        _derived(contact, zeta0, contact_runs, seed, prob)
        if contact is not None and zeta0 is not None and contact.groups
        else []
    )
    reasons = {e["run"]: e["reason"] for e in excluded}
    runs = []
    for r in results:
        row = _run_summary(r, prob)
        reason = reasons.get(_name(r))
        if reason is not None:
            row["status"] = f"excluded: {reason}"
        elif not row["converged"]:
            row["status"] = "used, sampler not converged"
        else:
            row["status"] = "used"
        runs.append(row)
    analysis = CampaignAnalysis(
        by=keys,
        covariate=covariate,
        prob=prob,
        runs=runs,
        contact=contact,
        zeta0=zeta0,
        series=series_pop,
        trends=trends,
        derived=derived,
        excluded=excluded,
        laws=_runs_by_law(contact_runs + free_runs),
        quantities=described,
        left_out=left_out,
        sigma_scales=scales,
        dissipation=dissipation,
        dissipation_trends=dissipation_trends,
        dissipation_quantities=laws_free,
    )
    # each run's ΔE from its law's band, at a swing every run of the populations reaches
    bands = run_bands({_name(r): r for r in results})
    if not bands:
        return analysis
    swing = swing_record(group_runs(analysis), bands, metadata=run_metadata(analysis))
    return replace(analysis, dissipation_at_swing=swing)


def _runs_by_law(runs: Sequence[Any]) -> dict[str, list[str]]:
    """Each law, with the runs fitted in it (with contact first, in the runs' order)."""
    out: dict[str, list[str]] = {}
    for r in runs:
        out.setdefault(_law(r), []).append(_name(r))
    return out


def _with_law(samples: RunSamples, law: str, several: bool) -> RunSamples:
    """A run's samples with its law in the metadata, where the law groups the runs."""
    if not several:
        return samples
    return RunSamples(
        samples.name, samples.values, samples.log_prior, {**samples.metadata, "law": law}
    )


def _merge(populations: list[Population]) -> Population | None:
    """One population of the populations of each law (their groups side by side)."""
    if not populations:
        return None
    if len(populations) == 1:
        return populations[0]
    groups: dict[Any, Any] = {}
    parameters: list[str] = []
    for pop in populations:
        groups.update(pop.groups)
        parameters.extend(p for p in pop.parameters if p not in parameters)
    return Population(populations[0].by, tuple(parameters), groups, None)
