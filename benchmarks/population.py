"""Population-of-repeats benchmark: coverage over repeated simulated campaigns.

Each simulated campaign is the paper's glycerol series: 5 loads (0.07-0.59 N) × 3
repeats. Run i has true (ζ_i, μ_k,i) ~ Normal(mean + slope·N_i, σ²) with the paper's
mean (0.0236, 0.0294) and repeat spreads σ = (0.0012, 0.0036). Each run is "fitted"
alone: it observes its parameters with Gaussian noise (sd 0.0004 for ζ, 0.0015 for
μ_k, correlation −0.6, like the single-run posteriors of a free decay) under an
independent Normal(0.03, 0.02²) prior per parameter, so its posterior is a correlated
normal that is sampled exactly (400 samples). The population is then inferred with
:func:`bayestribo.population.population` and :func:`bayestribo.population.trend`.

Reported over the campaigns, without a trend:

* coverage of the 50/90/95 % intervals of the pooled means and σ (15 runs) and of one
  load group's mean and σ (3 repeats: its σ interval is frequentist-checked at fixed
  truth, where a Bayesian interval under a half-Cauchy prior need not be exact);
* false-positive rate of the slope test (``prob_sign > 0.975``: nominal 5 %);

and with a load trend (slope 0.004 N⁻¹ on ζ, 0.012 N⁻¹ on μ_k: about 2σ over the load
range): coverage of the slope intervals and the power of the same test.

Run: ``python benchmarks/population.py [--campaigns N]``. Prints a table and writes
``benchmarks/results/population.json``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

from bayestribo.errors import ConvergenceWarning
from bayestribo.population import RunSamples, population, trend

LOADS = (0.07, 0.12, 0.31, 0.46, 0.59)
REPEATS = 3
MEAN = np.array([0.0236, 0.0294])
SIGMA = np.array([0.0012, 0.0036])
RUN_SD = np.array([0.0004, 0.0015])
RUN_CORR = -0.6
PRIOR_MEAN, PRIOR_SD = 0.03, 0.02
SLOPE = np.array([0.004, 0.012])
PARAMS = ("zeta", "mu_k")
PROBS = (0.5, 0.9, 0.95)
N_SAMPLES = 400


def _log_prior(x: np.ndarray) -> np.ndarray:
    z = (x - PRIOR_MEAN) / PRIOR_SD
    return (-0.5 * z**2 - math.log(PRIOR_SD * math.sqrt(2 * math.pi))).sum(axis=1)


def campaign(rng: np.random.Generator, slope: np.ndarray) -> list[RunSamples]:
    """One simulated campaign of exact per-run posteriors."""
    c = RUN_CORR * RUN_SD[0] * RUN_SD[1]
    cov = np.array([[RUN_SD[0] ** 2, c], [c, RUN_SD[1] ** 2]])
    p_inv = np.eye(2) / PRIOR_SD**2
    post_cov = np.linalg.inv(np.linalg.inv(cov) + p_inv)
    runs = []
    for load in LOADS:
        for r in range(REPEATS):
            theta = rng.normal(MEAN + slope * load, SIGMA)
            y = rng.multivariate_normal(theta, cov)
            mean = post_cov @ (np.linalg.solve(cov, y) + p_inv @ np.full(2, PRIOR_MEAN))
            x = rng.multivariate_normal(mean, post_cov, N_SAMPLES)
            runs.append(
                RunSamples(
                    f"L{load}-r{r}",
                    {"zeta": x[:, 0], "mu_k": x[:, 1]},
                    _log_prior(x),
                    {"load_N": load},
                )
            )
    return runs


def _covered(samples: np.ndarray, truth: float, prob: float) -> bool:
    lo, hi = np.quantile(samples, [(1 - prob) / 2, (1 + prob) / 2])
    return bool(lo <= truth <= hi)


def slope_only(args: argparse.Namespace) -> int:
    """False-positive rate and coverage of the load slope when there is no trend."""
    warnings.simplefilter("ignore", ConvergenceWarning)
    rng = np.random.default_rng(args.seed + 1)
    kw = {"max_steps": args.steps, "max_samples": None}
    hits = {p: 0 for p in PARAMS}
    n_unconverged = 0
    t0 = time.perf_counter()
    for c in range(args.campaigns):
        tr = trend(campaign(rng, np.zeros(2)), "load_N", PARAMS, seed=c, **kw)
        n_unconverged += not tr.diagnostics["converged"]
        for p in PARAMS:
            hits[p] += tr.slope_summary(p)["prob_sign"] > 0.975
    n = args.campaigns
    rows = []
    print(f"{'slope test, no trend':28s} {'false positives':>16s} {'rate':>6s} {'±2se':>6s}")
    for p in PARAMS:
        se2 = 2 * math.sqrt(0.05 * 0.95 / n)
        rows.append(
            {
                "parameter": p,
                "false_positives": hits[p],
                "rate": hits[p] / n,
                "nominal": 0.05,
                "two_se": se2,
            }
        )
        print(f"{p:28s} {hits[p]:16d} {hits[p] / n:6.3f} {se2:6.3f}")
    elapsed = time.perf_counter() - t0
    print(f"{n} campaigns in {elapsed:.0f} s; unconverged samplings: {n_unconverged}")
    path = write_results(
        "population_slope",
        {
            "campaigns": n,
            "seed": args.seed + 1,
            "max_steps": args.steps,
            "elapsed_s": elapsed,
            "unconverged_samplings": n_unconverged,
            "rows": rows,
        },
    )
    print(f"wrote {path}")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--campaigns", type=int, default=40)
    parser.add_argument("--seed", type=int, default=20100320)
    parser.add_argument(
        "--steps", type=int, default=10_000, help="ceiling on the population sampler's steps"
    )
    parser.add_argument(
        "--slope-only",
        action="store_true",
        help="only the slope test without a trend (false-positive rate), many campaigns: "
        "writes population_slope.json",
    )
    args = parser.parse_args()
    if args.slope_only:
        return slope_only(args)
    warnings.simplefilter("ignore", ConvergenceWarning)
    rng = np.random.default_rng(args.seed)
    counts: dict[str, int] = {}
    n_unconverged = 0
    t0 = time.perf_counter()
    kw = {"max_steps": args.steps, "max_samples": None}

    def tally(key: str, hit: bool) -> None:
        counts[key] = counts.get(key, 0) + int(hit)

    for c in range(args.campaigns):
        # No trend: pooled population, one load group, slope test.
        runs = campaign(rng, np.zeros(2))
        pop = population(runs, PARAMS, by=None, seed=c, **kw)
        grp = population(
            [r for r in runs if r.metadata["load_N"] == 0.31], PARAMS, seed=c, **kw
        ).pooled
        tr0 = trend(runs, "load_N", PARAMS, seed=c, **kw)
        # With a trend.
        tr1 = trend(campaign(rng, SLOPE), "load_N", PARAMS, seed=c, **kw)
        assert pop.pooled is not None
        for d in (pop.pooled.diagnostics, grp.diagnostics, tr0.diagnostics, tr1.diagnostics):
            n_unconverged += not d["converged"]
        for j, p in enumerate(PARAMS):
            for prob in PROBS:
                tally(f"pooled mean {p} @{prob}", _covered(pop.pooled.mean[p], MEAN[j], prob))
                tally(f"pooled sigma {p} @{prob}", _covered(pop.pooled.sigma[p], SIGMA[j], prob))
                tally(f"group(3) mean {p} @{prob}", _covered(grp.mean[p], MEAN[j], prob))
                tally(f"group(3) sigma {p} @{prob}", _covered(grp.sigma[p], SIGMA[j], prob))
                tally(f"slope {p} @{prob} (no trend)", _covered(tr0.slope[p], 0.0, prob))
                tally(f"slope {p} @{prob} (trend)", _covered(tr1.slope[p], SLOPE[j], prob))
            tally(f"slope test {p}: false positive", tr0.slope_summary(p)["prob_sign"] > 0.975)
            tally(f"slope test {p}: power", tr1.slope_summary(p)["prob_positive"] > 0.975)
        print(f"campaign {c + 1}/{args.campaigns} ({time.perf_counter() - t0:.0f} s)", flush=True)
    elapsed = time.perf_counter() - t0
    n = args.campaigns
    rows = []
    print(f"\n{'quantity':44s} {'rate':>6s} {'nominal':>8s} {'±2se':>6s}")
    for key, hits in counts.items():
        rate = hits / n
        nominal = None
        if "@" in key:
            nominal = float(key.split("@")[1].split()[0])
        elif "false positive" in key:
            nominal = 0.05
        se = 2 * math.sqrt(nominal * (1 - nominal) / n) if nominal is not None else float("nan")
        rows.append({"quantity": key, "rate": rate, "nominal": nominal, "two_se": se})
        nom = f"{nominal:.2f}" if nominal is not None else "-"
        print(f"{key:44s} {rate:6.3f} {nom:>8s} {se:6.3f}")
    print(f"\n{n} campaigns in {elapsed:.0f} s; unconverged samplings: {n_unconverged}")
    path = write_results(
        "population",
        {
            "campaigns": n,
            "seed": args.seed,
            "settings": {
                "loads_N": LOADS,
                "repeats": REPEATS,
                "mean": MEAN.tolist(),
                "sigma": SIGMA.tolist(),
                "run_sd": RUN_SD.tolist(),
                "run_corr": RUN_CORR,
                "slope_per_N": SLOPE.tolist(),
                "samples_per_run": N_SAMPLES,
                "max_steps": args.steps,
                "sigma_prior": "half-Cauchy(scale=0.01)",
            },
            "elapsed_s": elapsed,
            "unconverged_samplings": n_unconverged,
            "rows": rows,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
