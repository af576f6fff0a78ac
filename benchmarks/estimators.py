"""Classical estimators benchmark: bias, RMSE and time per run at three noise levels.

Simulated tribometer runs (:func:`bayestribo.synthetic.recording.simulate`: the paper's rig,
m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236, μ_k = 0.0294, x₀ = 1.5 mm, a
magnet that fades over a quarter period, 10 kHz) with white noise on both channels
at the vibrometer's resolution (0.15 µm, 0.015 µm/s), 10x and 100x it. Each run is
analysed by every estimator of :func:`bayestribo.estimate_all` (skipping the first
oscillation, as the paper does); per estimator and signal: the number of runs with
a value, bias and RMSE of ζ and μ_k, the mean reported standard error against the
spread of the estimates (a calibration ratio: 1 for an honest standard error), and
the median time per run (peak finding included).

This table is the baseline the Bayesian fit must beat.

Run: ``python benchmarks/estimators.py [--runs N] [--quick]``. Prints a table and
writes ``benchmarks/results/estimators.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import scipy

from bayestribo import __version__
from bayestribo.estimators.all import METHODS, estimate_all
from bayestribo.synthetic import (
    DISPLACEMENT_RESOLUTION_M,
    PAPER_RIG,
    VELOCITY_RESOLUTION_M_PER_S,
    DissipationLaw,
    Sensor,
    simulate,
)

RESULTS = Path(__file__).resolve().parent / "results" / "estimators.json"
TRUE_ZETA = 0.0236
TRUE_MU = 0.0294
NOISE_FACTORS = (1, 10, 100)


def _machine() -> dict[str, object]:
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor(),
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "bayestribo": __version__,
    }


def run_level(factor: int, runs: int, seed0: int) -> list[dict[str, object]]:
    """All estimators on ``runs`` simulated runs at noise ``factor`` x resolution."""
    values: dict[tuple[str, str], list[tuple[float, float, float, float]]] = defaultdict(list)
    times: dict[str, list[float]] = defaultdict(list)
    failures: dict[tuple[str, str], int] = defaultdict(int)
    for i in range(runs):
        run = simulate(
            DissipationLaw(zeta=TRUE_ZETA, mu_k=TRUE_MU),
            rig=PAPER_RIG,
            sensor=Sensor(
                displacement_noise_m=factor * DISPLACEMENT_RESOLUTION_M,
                velocity_noise_m_per_s=factor * VELOCITY_RESOLUTION_M_PER_S,
            ),
            seed=seed0 + i,
        )
        start = time.perf_counter()
        estimate_all(run, skip_oscillations=1)
        times["all"].append(time.perf_counter() - start)
        for method in METHODS:
            start = time.perf_counter()
            table = estimate_all(run, skip_oscillations=1, methods=[method])
            times[method].append(time.perf_counter() - start)
            for e in table:
                signal = e.data.split(" ")[0] if "peaks" in e.data else "x and v"
                key = (method, signal)
                if e.zeta is None or (e.mu_k is None and method in _FRICTION):
                    failures[key] += 1
                    continue
                values[key].append(
                    (
                        e.zeta,
                        np.nan if e.zeta_se is None else e.zeta_se,
                        np.nan if e.mu_k is None else e.mu_k,
                        np.nan if e.mu_k_se is None else e.mu_k_se,
                    )
                )
    rows = []
    keys = sorted(set(values) | set(failures), key=lambda k: (METHODS.index(k[0]), k[1]))
    for method, signal in keys:
        a = np.array(values[(method, signal)], dtype=float).reshape(-1, 4)
        n = a.shape[0]
        row: dict[str, object] = {
            "noise_factor": factor,
            "method": method,
            "signal": signal,
            "runs": runs,
            "n_ok": n,
            "time_per_run_ms": 1e3 * float(np.median(times[method])),
        }
        for j, name, truth in ((0, "zeta", TRUE_ZETA), (2, "mu_k", TRUE_MU)):
            col = a[:, j]
            if n == 0 or np.all(np.isnan(col)):
                row.update({f"{name}_bias": None, f"{name}_rmse": None, f"{name}_se_ratio": None})
                continue
            err = col - truth
            sd = float(np.nanstd(col, ddof=1)) if n > 1 else float("nan")
            se = a[:, j + 1]
            ratio = float(np.nanmean(se) / sd) if sd > 0 and not np.all(np.isnan(se)) else None
            row[f"{name}_bias"] = float(np.nanmean(err))
            row[f"{name}_rmse"] = float(np.sqrt(np.nanmean(err**2)))
            row[f"{name}_se_ratio"] = ratio
        rows.append(row)
    rows.append(
        {
            "noise_factor": factor,
            "method": "all",
            "signal": "x and v",
            "runs": runs,
            "n_ok": runs,
            "time_per_run_ms": 1e3 * float(np.median(times["all"])),
        }
    )
    return rows


_FRICTION = ("feeny_liang", "nonsuccessive", "energy_ls_averaged", "energy_ls_exact")


def _fmt(v: object, spec: str = ".2e") -> str:
    return "-" if v is None else format(v, spec)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=150, help="runs per noise level")
    parser.add_argument("--quick", action="store_true", help="10 runs per level")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    runs = 10 if args.quick else args.runs
    start = time.perf_counter()
    rows = []
    for k, factor in enumerate(NOISE_FACTORS):
        rows += run_level(factor, runs, seed0=1000 * (k + 1))
    elapsed = time.perf_counter() - start

    head = (
        f"{'noise':>5} {'method':<22}{'signal':<14}{'ok':>4} {'ζ bias':>10}{'ζ RMSE':>10}"
        f"{'SE/SD':>9} {'μ bias':>10}{'μ RMSE':>10}{'SE/SD':>9}{'ms/run':>8}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r['noise_factor']:>4}x {r['method']:<22}{r['signal']:<14}{r['n_ok']:>4} "
            f"{_fmt(r.get('zeta_bias')):>10}{_fmt(r.get('zeta_rmse')):>10}"
            f"{_fmt(r.get('zeta_se_ratio'), '.3g'):>9} "
            f"{_fmt(r.get('mu_k_bias')):>10}{_fmt(r.get('mu_k_rmse')):>10}"
            f"{_fmt(r.get('mu_k_se_ratio'), '.3g'):>9}{r['time_per_run_ms']:>8.1f}"
        )
    print(f"\n{3 * runs} runs in {elapsed:.0f} s")
    out = {
        "benchmark": "estimators",
        "description": __doc__.split("\n\n")[1],
        "when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": _machine(),
        "truth": {"zeta": TRUE_ZETA, "mu_k": TRUE_MU, "load_N": 0.31, "x0_m": 1.5e-3},
        "noise": {
            "displacement_resolution_m": DISPLACEMENT_RESOLUTION_M,
            "velocity_resolution_m_per_s": VELOCITY_RESOLUTION_M_PER_S,
            "factors": list(NOISE_FACTORS),
        },
        "runs_per_level": runs,
        "elapsed_s": elapsed,
        "notes": (
            "se_ratio = mean reported standard error / standard deviation of the "
            "estimates over the runs (1 = honest). time_per_run_ms: median wall time of "
            "estimate_all(run, methods=[method]) including peak finding, both signals "
            "for the peak methods. Viscous-only methods have no μ_k."
        ),
        "rows": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
