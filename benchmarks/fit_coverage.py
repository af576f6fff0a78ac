"""Coverage of the fit's 95 % intervals on realistic simulated runs.

(Named ``fit_coverage`` rather than ``coverage``: a ``coverage.py`` next to the
scripts would shadow the coverage package that numba and pytest import.)

Each run is simulated with :func:`bayestribo.simulate` with the real rig's effects
the fit does not model explicitly: the magnet pull fading over a quarter period
after the release, a displacement offset (a sensor zero of 0 to 0.5 mm), rest
segments before the release (0.05 s) and after the stop (0.1 s), white noise of 10 to
50 times the vibrometer resolution (log-uniform) on both channels, quantisation to
the resolution, and sample rates of 2, 5, 10 and 20 kHz (in turn). The parameters
are drawn from ζ ~ Uniform(0.01, 0.05), μ_k ~ Uniform(0.01, 0.05),
μ_s/μ_k ~ Uniform(1, 3), x₀ ~ Uniform(1, 2) mm, on the paper's rig (m = 0.035 kg,
f = 32.6 Hz, N = 0.31 N). Every run is fitted with the defaults
(:func:`bayestribo.inference.fit`, exact model) and the equal-tailed 95 % intervals of ζ
and μ_k are checked against the truth.

Reported: runs, converged runs, the coverage rate of each parameter (and of both at
once) over the converged runs with its 95 % binomial (Clopper-Pearson) interval,
coverage by noise factor and by sample rate, and the median fit time. A calibrated
fit covers 95 %: with 100 runs a rate between 0.89 and 0.99 is consistent with it.

Run::

    nice -n 10 python benchmarks/fit_coverage.py --runs 100 --workers 2

Finished runs are appended to ``benchmarks/results/fit_coverage_runs.jsonl``
(``--resume``, ``--report-only``); writes ``benchmarks/results/fit_coverage.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import RESULTS, niced_worker, write_results  # noqa: E402

__all__ = ["one_run", "summarise"]

RATES_HZ = (2000.0, 5000.0, 10000.0, 20000.0)
NOISE_RANGE = (10.0, 50.0)
PARAMS = ("zeta", "mu_k")
RAW = RESULTS / "fit_coverage_runs.jsonl"


def one_run(index: int, seed: int) -> dict[str, Any]:
    """Simulate one realistic run, fit it, record whether the 95 % intervals cover."""
    from bayestribo.inference import fit
    from bayestribo.synthetic import (
        DISPLACEMENT_RESOLUTION_M,
        VELOCITY_RESOLUTION_M_PER_S,
        DissipationLaw,
        Release,
        Sensor,
        simulate,
    )

    rng = np.random.default_rng([seed, index])
    truth = {
        "zeta": float(rng.uniform(0.01, 0.05)),
        "mu_k": float(rng.uniform(0.01, 0.05)),
        "mu_s_ratio": float(rng.uniform(1.0, 3.0)),
    }
    noise = float(np.exp(rng.uniform(*np.log(NOISE_RANGE))))
    setup = {
        "noise_factor": noise,
        "sample_rate_Hz": RATES_HZ[index % len(RATES_HZ)],
        "initial_displacement_m": float(rng.uniform(1e-3, 2e-3)),
        "offset_m": float(rng.uniform(0.0, 5e-4)),
    }
    out: dict[str, Any] = {"index": index, "truth": truth, "setup": setup}
    start = time.perf_counter()
    try:
        run = simulate(
            DissipationLaw(
                zeta=truth["zeta"], mu_k=truth["mu_k"], mu_s=truth["mu_k"] * truth["mu_s_ratio"]
            ),
            release=Release(
                initial_displacement_m=setup["initial_displacement_m"], offset_m=setup["offset_m"]
            ),
            sensor=Sensor(
                sample_rate_Hz=setup["sample_rate_Hz"],
                displacement_noise_m=noise * DISPLACEMENT_RESOLUTION_M,
                velocity_noise_m_per_s=noise * VELOCITY_RESOLUTION_M_PER_S,
                quantise=True,
            ),
            seed=int(rng.integers(2**31)),
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(run, seed=int(rng.integers(2**31)))
    except Exception as exc:  # recorded and reported, never silently dropped
        out["error"] = f"{type(exc).__name__}: {exc}"
        return out
    out["seconds"] = time.perf_counter() - start
    out["converged"] = result.converged
    out["interval"] = {name: list(result.interval(name, 0.95)) for name in PARAMS}
    out["mean"] = {name: float(np.mean(result.samples(name))) for name in PARAMS}
    out["sd"] = {name: float(np.std(result.samples(name), ddof=1)) for name in PARAMS}
    out["covered"] = {
        name: bool(out["interval"][name][0] <= truth[name] <= out["interval"][name][1])
        for name in PARAMS
    }
    out["noise_used"] = result.noise.get("description", "")
    return out


def _clopper_pearson(k: int, n: int) -> list[float]:
    if n == 0:
        return [math.nan, math.nan]
    lo = stats.beta.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
    hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
    return [float(lo), float(hi)]


def _rate(rows: list[dict[str, Any]], key: str | None) -> dict[str, Any]:
    if key is None:
        hits = [all(r["covered"].values()) for r in rows]
    else:
        hits = [r["covered"][key] for r in rows]
    k, n = int(np.sum(hits)), len(hits)
    return {"covered": k, "n": n, "rate": k / n if n else None, "ci95": _clopper_pearson(k, n)}


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Coverage rates overall, by noise factor band and by sample rate."""
    ok = [r for r in records if "covered" in r and r["converged"]]
    summary: dict[str, Any] = {
        "runs": len(records),
        "errors": [r["error"] for r in records if "error" in r],
        "not_converged": sum("covered" in r and not r["converged"] for r in records),
        "used": len(ok),
        "median_fit_seconds": float(np.median([r["seconds"] for r in ok])) if ok else None,
        "coverage": {name: _rate(ok, name) for name in PARAMS},
        "coverage_both": _rate(ok, None),
        "by_noise": {},
        "by_sample_rate": {},
    }
    for lo, hi in ((10, 20), (20, 35), (35, 50.01)):
        sel = [r for r in ok if lo <= r["setup"]["noise_factor"] < hi]
        summary["by_noise"][f"{lo}-{min(hi, 50):g}x"] = {n: _rate(sel, n) for n in PARAMS}
    for rate in RATES_HZ:
        sel = [r for r in ok if r["setup"]["sample_rate_Hz"] == rate]
        summary["by_sample_rate"][f"{rate:g}"] = {n: _rate(sel, n) for n in PARAMS}
    z = {n: np.array([(r["mean"][n] - r["truth"][n]) / r["sd"][n] for r in ok]) for n in PARAMS}
    summary["standardized_error"] = {
        n: {"mean": float(np.mean(v)), "sd": float(np.std(v, ddof=1))}
        for n, v in z.items()
        if v.size > 1
    }
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument("--raw", type=Path, default=RAW)
    args = parser.parse_args(argv)

    records = [
        json.loads(line)
        for line in (args.raw.read_text().splitlines() if args.raw.exists() else [])
        if line.strip() and (args.resume or args.report_only)
    ]
    start = time.perf_counter()
    if not args.report_only:
        done = {r["index"] for r in records}
        todo = [i for i in range(args.runs) if i not in done]
        args.raw.parent.mkdir(parents=True, exist_ok=True)
        with (
            open(args.raw, "a" if args.resume else "w") as raw,
            ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool,
        ):
            futures = [pool.submit(one_run, i, args.seed) for i in todo]
            for k, future in enumerate(as_completed(futures), 1):
                rec = future.result()
                records.append(rec)
                raw.write(json.dumps(rec) + "\n")
                raw.flush()
                if k % 10 == 0:
                    print(f"{k}/{len(todo)} runs, {time.perf_counter() - start:.0f} s", flush=True)
    elapsed = time.perf_counter() - start

    s = summarise(records)
    print(f"{s['runs']} runs, {s['used']} converged and used, {len(s['errors'])} errors")
    head = f"{'group':<22}{'param':<7}{'n':>5}{'rate':>7}   95 % CI"
    print(head)
    print("-" * len(head))

    def line(group: str, name: str, r: dict[str, Any]) -> None:
        if r["n"]:
            print(
                f"{group:<22}{name:<7}{r['n']:>5}{r['rate']:>7.3f}   "
                f"[{r['ci95'][0]:.3f}, {r['ci95'][1]:.3f}]"
            )

    for name in PARAMS:
        line("all", name, s["coverage"][name])
    line("all", "both", s["coverage_both"])
    for group, rows in (("noise", s["by_noise"]), ("rate Hz", s["by_sample_rate"])):
        for key, per in rows.items():
            for name in PARAMS:
                line(f"{group} {key}", name, per[name])
    path = write_results(
        "fit_coverage",
        {
            "benchmark": "fit_coverage",
            "description": __doc__.split("\n\n")[1:3],
            "seed": args.seed,
            "elapsed_s": elapsed,
            **s,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
