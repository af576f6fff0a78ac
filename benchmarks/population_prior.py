"""Coverage of a group of three repeats' population mean and σ under each σ prior.

The commonest campaign group is three repeats. Each run's true value is drawn from
Normal(μ, σ²); the run "measures" it with Gaussian noise of sd ``m`` under a flat
prior, so its posterior is Normal(x_i, m²), sampled exactly (400 samples). The group's
population (:func:`bayestribo.population.population`) is inferred under each prior on
σ, and the 50/90/95 % intervals of μ and σ are scored against the truth, at three
ratios m/σ (runs far more precise than their spread, as precise, less precise).

Priors compared (scale s = 0.01, the package's default for ζ and μ_k; μ = 0.02,
σ = 0.002):

* ``half-Cauchy``: HalfCauchy(s), the package's default before this benchmark;
* ``scale-free``: ScaleFree(s), ∝ 1/σ from a tenth of the runs' posterior sd to
  10 s, the default now.

Run (minutes; in the background)::

    timeout 3600 python benchmarks/population_prior.py --groups 200

and read ``benchmarks/results/population_prior.json``.
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
from bayestribo.population import HalfCauchy, RunSamples, ScaleFree, population

MU, SIGMA, SCALE = 0.02, 0.002, 0.01
RATIOS = (0.2, 1.0, 3.0)  # m / σ
REPEATS = 3
N_SAMPLES = 400
PROBS = (0.5, 0.9, 0.95)
PRIORS = {"half-Cauchy": HalfCauchy(SCALE), "scale-free": ScaleFree(SCALE)}


def _group(rng: np.random.Generator, m: float) -> list[RunSamples]:
    runs = []
    for i in range(REPEATS):
        x = rng.normal(rng.normal(MU, SIGMA), m)
        samples = rng.normal(x, m, size=N_SAMPLES)
        runs.append(RunSamples(f"r{i}", {"zeta": samples}, np.zeros(N_SAMPLES), {}))
    return runs


def _covered(draws: np.ndarray, truth: float, prob: float) -> bool:
    lo, hi = np.quantile(draws, [(1 - prob) / 2, (1 + prob) / 2])
    return bool(lo <= truth <= hi)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--groups", type=int, default=200)
    parser.add_argument("--seed", type=int, default=20261129)
    args = parser.parse_args()
    t0 = time.perf_counter()
    hits: dict[tuple[str, float, str, float], list[bool]] = {}
    unconverged = 0
    for ratio in RATIOS:
        rng = np.random.default_rng([args.seed, int(ratio * 10)])
        for g in range(args.groups):
            runs = _group(rng, ratio * SIGMA)
            for label, prior in PRIORS.items():
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", ConvergenceWarning)
                    pop = population(
                        runs, ("zeta",), sigma_prior={"zeta": prior}, seed=g, max_samples=None
                    )
                unconverged += any(issubclass(w.category, ConvergenceWarning) for w in caught)
                post = pop.pooled
                for what, draws, truth in (
                    ("mean", post.mean["zeta"], MU),
                    ("sigma", post.sigma["zeta"], SIGMA),
                ):
                    for prob in PROBS:
                        hits.setdefault((label, ratio, what, prob), []).append(
                            _covered(draws, truth, prob)
                        )
        print(f"m/σ = {ratio}: {args.groups} groups, {time.perf_counter() - t0:.0f} s", flush=True)
    rows = []
    for (label, ratio, what, prob), h in sorted(hits.items()):
        n = len(h)
        rate = float(np.mean(h))
        rows.append(
            {
                "prior": label,
                "m_over_sigma": ratio,
                "quantity": what,
                "nominal": prob,
                "rate": rate,
                "n": n,
                "two_se": 2 * math.sqrt(prob * (1 - prob) / n),
            }
        )
        print(f"{label:12s} m/σ={ratio:<4} {what:6s} {prob:.2f}: {rate:.3f} (n={n})")
    write_results(
        "population_prior",
        {
            "settings": {
                "groups": args.groups,
                "seed": args.seed,
                "repeats": REPEATS,
                "mu": MU,
                "sigma": SIGMA,
                "ratios_m_over_sigma": list(RATIOS),
                "samples_per_run": N_SAMPLES,
                "priors": {k: v.describe() for k, v in PRIORS.items()},
            },
            "elapsed_s": time.perf_counter() - t0,
            "unconverged_samplings": unconverged,
            "rows": rows,
        },
    )


if __name__ == "__main__":
    main()
