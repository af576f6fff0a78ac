"""Accuracy of the single-run fit: the information limit and the classical baselines.

1. **Information limit.** Runs simulated with the paper's values (ζ = 0.0236,
   μ_k = 0.0294, μ_s = 1.2 μ_k, N = 0.31 N, x₀ = 1.5 mm, 10 kHz, an ideal release)
   at the vibrometer resolution (1x) and 30x it are fitted; the posterior standard
   deviations of ζ and μ_k are compared with the Cramér-Rao bound of the same
   likelihood: J = ∂M/∂θ, the model increments' derivatives by central finite
   differences (step 0.1 posterior sd) at the posterior mean with respect to
   θ = (ζ, μ_k, y0) at fixed μ_s/μ_k, extended by the equilibrium nuisance (δ₀, δ₁)
   whose derivatives are minus the design columns, I = Jᵀ V⁻¹ J plus the nuisance's
   prior precision, bound = √diag(I⁻¹). Reported: sd/bound per run and the median
   per noise level (1 = the posterior is as narrow as the data allow; the issue's
   goal is within 20 %).
2. **Against the baselines.** The estimator benchmark's runs
   (``benchmarks/estimators.py``: same simulation and seeds, noise 1x, 10x, 100x the
   resolution), the first ``--baseline-runs`` per level: the posterior mean's bias
   and RMSE beside every classical estimator's on the same runs (computed here,
   side by side), and the estimator benchmark's own RMSE over its 150 runs (from
   ``benchmarks/results/estimators.json``) for reference.

Run: ``nice -n 10 python benchmarks/fit_accuracy.py [--crb-runs 5] [--baseline-runs 10]
[--workers 2]``; writes ``benchmarks/results/fit_accuracy.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fitsetup import likelihood_of  # noqa: E402
from _machine import RESULTS, niced_worker, write_results  # noqa: E402

__all__ = ["baseline_run", "crb_run", "fisher_bound"]

TRUE_ZETA = 0.0236
TRUE_MU = 0.0294
CRB_LEVELS = (1.0, 30.0)
BASELINE_LEVELS = (1, 10, 100)  # as benchmarks/estimators.py
THETA = ("zeta", "mu_k", "y0")


def fisher_bound(lik: Any, mean: dict[str, float], sd: dict[str, float]) -> dict[str, float]:
    """Cramér-Rao standard deviations of ζ, μ_k, y0 for the likelihood ``lik``."""
    ratio = mean["mu_s_ratio"]

    def increments(theta: np.ndarray) -> np.ndarray:
        z, m, y = (np.array([v]) for v in theta)
        return lik.model_increments({"zeta": z, "mu_k": m, "mu_s_ratio": ratio, "y0": y})[0]

    theta0 = np.array([mean[n] for n in THETA])
    cols = []
    for i, name in enumerate(THETA):
        h = 0.1 * sd[name]
        up, down = theta0.copy(), theta0.copy()
        up[i] += h
        down[i] -= h
        cols.append((increments(up) - increments(down)) / (2 * h))
    x = lik.data.offset_design
    jac = np.column_stack([*cols, -x[:, 0], -x[:, 1], x[:, 2]])
    info = jac.T @ (jac / lik.variance()[:, None])
    info[3, 3] += lik.offset_sd**-2
    info[4, 4] += lik.drift_sd**-2
    info[5, 5] += 1.0  # the noise level's error, standard normal
    cov = np.linalg.inv(info)
    return {name: float(np.sqrt(cov[i, i])) for i, name in enumerate(THETA)}


def _fit(run: Any, seed: int) -> Any:
    from bayestribo.inference import fit

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit(run, seed=seed)


def crb_run(level: float, index: int) -> dict[str, Any]:
    """Fit one simulated run; posterior sd against the Cramér-Rao bound."""
    from bayestribo.synthetic import (
        DISPLACEMENT_RESOLUTION_M,
        VELOCITY_RESOLUTION_M_PER_S,
        DissipationLaw,
        Release,
        Sensor,
        simulate,
    )

    run = simulate(
        DissipationLaw(zeta=TRUE_ZETA, mu_k=TRUE_MU, mu_s=1.2 * TRUE_MU),
        release=Release(magnet_fade_s=0.0),
        sensor=Sensor(
            displacement_noise_m=level * DISPLACEMENT_RESOLUTION_M,
            velocity_noise_m_per_s=level * VELOCITY_RESOLUTION_M_PER_S,
        ),
        seed=7000 + index + int(level),
    )
    result = _fit(run, seed=index)
    names = [*THETA, "mu_s_ratio"]
    mean = {n: float(np.mean(result.samples(n))) for n in names}
    sd = {n: float(np.std(result.samples(n), ddof=1)) for n in names}
    bound = fisher_bound(likelihood_of(run), mean, sd)
    return {
        "level": level,
        "index": index,
        "converged": result.converged,
        "sd": {n: sd[n] for n in ("zeta", "mu_k")},
        "crb": {n: bound[n] for n in ("zeta", "mu_k")},
        "ratio": {n: sd[n] / bound[n] for n in ("zeta", "mu_k")},
    }


def baseline_run(level: int, index: int) -> dict[str, Any]:
    """One of the estimator benchmark's runs: the fit and every classical estimator."""
    from bayestribo.estimators.all import estimate_all
    from bayestribo.synthetic import (
        DISPLACEMENT_RESOLUTION_M,
        PAPER_RIG,
        VELOCITY_RESOLUTION_M_PER_S,
        DissipationLaw,
        Sensor,
        simulate,
    )

    seed0 = 1000 * (BASELINE_LEVELS.index(level) + 1)  # benchmarks/estimators.py seeds
    run = simulate(
        DissipationLaw(zeta=TRUE_ZETA, mu_k=TRUE_MU),
        rig=PAPER_RIG,
        sensor=Sensor(
            displacement_noise_m=level * DISPLACEMENT_RESOLUTION_M,
            velocity_noise_m_per_s=level * VELOCITY_RESOLUTION_M_PER_S,
        ),
        seed=seed0 + index,
    )
    out: dict[str, Any] = {"level": level, "index": index, "estimates": {}}
    result = _fit(run, seed=index)
    out["estimates"]["bayes_posterior_mean"] = {
        "zeta": float(np.mean(result.samples("zeta"))),
        "mu_k": float(np.mean(result.samples("mu_k"))),
        "converged": result.converged,
    }
    for e in estimate_all(run, skip_oscillations=1):
        signal = e.data.split(" ")[0] if "peaks" in e.data else "x and v"
        out["estimates"][f"{e.method} ({signal})"] = {"zeta": e.zeta, "mu_k": e.mu_k}
    return out


def _baseline_table(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for level in BASELINE_LEVELS:
        per: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
        for r in records:
            if r["level"] != level:
                continue
            for method, est in r["estimates"].items():
                for name in ("zeta", "mu_k"):
                    if est.get(name) is not None:
                        per[method][name].append(est[name])
        for method, vals in per.items():
            row: dict[str, Any] = {"noise_factor": level, "method": method}
            for name, truth in (("zeta", TRUE_ZETA), ("mu_k", TRUE_MU)):
                v = np.array(vals.get(name, []))
                row[f"{name}_n"] = int(v.size)
                row[f"{name}_bias"] = float(np.mean(v - truth)) if v.size else None
                row[f"{name}_rmse"] = float(np.sqrt(np.mean((v - truth) ** 2))) if v.size else None
            rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--crb-runs", type=int, default=5, help="runs per noise level")
    parser.add_argument("--baseline-runs", type=int, default=10, help="runs per noise level")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        crb_f = [
            pool.submit(crb_run, level, i) for i in range(args.crb_runs) for level in CRB_LEVELS
        ]
        base_f = [
            pool.submit(baseline_run, level, i)
            for i in range(args.baseline_runs)
            for level in BASELINE_LEVELS
        ]
        crb = [f.result() for f in crb_f]
        base = [f.result() for f in base_f]
    elapsed = time.perf_counter() - start

    crb_summary = {}
    print("information limit: posterior sd / Cramér-Rao bound")
    for level in CRB_LEVELS:
        rows = [r for r in crb if r["level"] == level]
        entry = {
            "runs": len(rows),
            "converged": sum(r["converged"] for r in rows),
            "median_ratio": {
                n: float(np.median([r["ratio"][n] for r in rows])) for n in ("zeta", "mu_k")
            },
            "ratios": {n: [r["ratio"][n] for r in rows] for n in ("zeta", "mu_k")},
            "median_crb": {
                n: float(np.median([r["crb"][n] for r in rows])) for n in ("zeta", "mu_k")
            },
        }
        crb_summary[str(level)] = entry
        print(
            f"  {level:>4g}x: ζ {entry['median_ratio']['zeta']:.3f} "
            f"(bound {entry['median_crb']['zeta']:.2e}), μ_k {entry['median_ratio']['mu_k']:.3f} "
            f"(bound {entry['median_crb']['mu_k']:.2e}), {entry['converged']}/{len(rows)} converged"
        )

    table = _baseline_table(base)
    reference = json.loads((RESULTS / "estimators.json").read_text())["rows"]
    ref = {
        (r["noise_factor"], f"{r['method']} ({r['signal']})"): r
        for r in reference
        if r["method"] != "all"
    }
    for row in table:
        r = ref.get((row["noise_factor"], row["method"]))
        row["estimators_benchmark_rmse"] = (
            None if r is None else {"zeta": r.get("zeta_rmse"), "mu_k": r.get("mu_k_rmse")}
        )

    def fmt(v: Any) -> str:
        return "-" if v is None else f"{v:.2e}"

    print(f"\nRMSE on the estimator benchmark's runs ({args.baseline_runs} per level)")
    print(
        f"{'noise':>6} {'method':<42}{'ζ RMSE':>10}{'μ_k RMSE':>10}{'ζ (150)':>10}{'μ_k (150)':>10}"
    )
    for row in table:
        ref_rmse = row["estimators_benchmark_rmse"] or {}
        print(
            f"{row['noise_factor']:>5}x {row['method']:<42}{fmt(row['zeta_rmse']):>10}"
            f"{fmt(row['mu_k_rmse']):>10}{fmt(ref_rmse.get('zeta')):>10}"
            f"{fmt(ref_rmse.get('mu_k')):>10}"
        )
    path = write_results(
        "fit_accuracy",
        {
            "benchmark": "fit_accuracy",
            "description": __doc__.split("\n\n")[1:3],
            "elapsed_s": elapsed,
            "information_limit": crb_summary,
            "information_limit_runs": crb,
            "baselines": {
                "runs_per_level": args.baseline_runs,
                "not_converged_fits": sum(
                    not r["estimates"]["bayes_posterior_mean"]["converged"] for r in base
                ),
                "rows": table,
            },
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
