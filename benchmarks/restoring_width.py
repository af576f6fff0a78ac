"""Where the width of the intervals on a nonlinear restoring force comes from.

On the runs of ``benchmarks/restoring_coverage.py`` (the displacement alone recorded,
the velocity the package's Savitzky-Golay derivative), for the first run of each case:

* the noise of the increments of Π through the derivative, 2000 Monte Carlo draws
  (``increment_draws``): the mean correlation of neighbouring increments at lags 1-3,
  the Monte Carlo's variances over the likelihood's, and the variance of the sum of
  all the increments over the sum of their variances (what independent increments
  take as 1); the first-order correlation of ``signal/derivative_correlation.py``
  against the Monte Carlo's;
* ``--fits N``: N fits of each variant on the same noise (the case's seeds), with
  z = (mean - truth)/sd of ζ, c₂ and μ_k and the χ² of the standardized residuals at
  the optimum over the increments: ``duffing-5pc`` as it is, with β held at the truth
  (and no standard error to marginalise), the same simulator on a linear spring
  (β = 0) fitted on the linear spring, and that linear spring fitted through the
  nonlinear path (``restoring`` ``duffing`` with β held at 0).

Run: ``python benchmarks/restoring_width.py --fits 20 --output restoring_width``
(``results/restoring_width.json``); ``--bundled --output NAME`` hashes what the
likelihood observes of each bundled run, to compare two packages.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
import zlib
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

import restoring_coverage as rc
from _machine import write_results

VARIANTS: dict[str, dict[str, Any]] = {
    "duffing": {},
    "duffing-beta-true": {"beta": 0.033},
    "linear-spring": {"linear_spring": True, "restoring": "linear"},
    "linear-spring-nonlinear-path": {
        "linear_spring": True,
        "restoring": "duffing",
        "beta": 0.0,
    },
}


def _record(name: str, index: int, seed: int, linear_spring: bool = False):
    """The case's run ``index`` (its noise as restoring_coverage draws it)."""
    case = dict(rc.CASES[name])
    if linear_spring:
        case["beta"] = 0.0
    t, x, _ = rc.simulate(case)
    entropy = [seed, zlib.crc32(name.encode()), index]
    xs = x + np.random.default_rng(entropy).normal(0.0, case["noise"], x.size)
    return t, xs, entropy, case


def noise_of_increments(name: str, seed: int, linear_spring: bool = False) -> dict[str, Any]:
    """The increments' noise through the derivative on run 0 of ``name``."""
    from bayestribo.inference.preparation import prepare
    from bayestribo.io.run import Run
    from bayestribo.signal.increments import increment_draws, increment_weights

    t, xs, _, case = _record(name, 0, seed, linear_spring)
    meta = dict(case["meta"])
    if linear_spring:
        meta["restoring"] = "linear"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(Run(t, xs, metadata={"gain_uncertainty": 0.0, **meta}))
    decay, data = prepared.decay, prepared.data
    tau = decay.tau
    h = float(tau[1] - tau[0])
    edges, weights = increment_weights(tau.size, h, data.increments.size)
    sigma = prepared.noise.displacement / decay.scaling.length_scale
    force = decay.restoring
    draws = increment_draws(
        tau,
        decay.y,
        decay.yp,
        edges,
        weights,
        sigma,
        0.0,
        derived="velocity",
        savgol_window=decay.savgol_window,
        n_replicates=2000,
        seed=1,
        potential=None if force is None else force.potential,
    )
    variance = draws.var(axis=0, ddof=1)
    measured = np.corrcoef(draws.T)
    m = measured.shape[0]
    spring = decay.y if force is None else np.asarray(force.spring(decay.y))
    try:
        from bayestribo.signal.derivative_correlation import derived_velocity_correlation
    except ImportError:  # a package before it
        first = None
    else:
        first = derived_velocity_correlation(
            spring, decay.yp, edges, weights, variance, sigma, decay.savgol_window, h
        )
    lag1 = np.diag(measured, 1)
    out = {
        "increments": m,
        "samples_per_increment": float(np.median(np.diff(edges))),
        "savgol_window": decay.savgol_window,
        "lag_correlation": [float(np.mean(np.diag(measured, k))) for k in (1, 2, 3)],
        "variance_over_likelihood_median": float(np.median(variance / data.variance)),
        "sum_variance_over_sum_of_variances": float(draws.sum(axis=1).var() / variance.sum()),
    }
    if first is not None:
        sd = np.sqrt(variance)
        out["first_order_lag1_mean"] = float(np.mean(np.diag(first, 1)))
        out["first_order_lag1_rms_difference"] = float(
            math.sqrt(np.mean((np.diag(first, 1) - lag1) ** 2))
        )
        out["first_order_sum_ratio"] = float(sd @ first @ sd / variance.sum())
    return out


def one_fit(variant: str, index: int, seed: int) -> dict[str, Any]:
    """A fit of ``duffing-5pc``'s run ``index`` as ``variant`` says."""
    from bayestribo import fit
    from bayestribo.io.run import Run
    from bayestribo.model.restoring import duffing as module

    spec = VARIANTS[variant]
    t, xs, entropy, case = _record("duffing-5pc", index, seed, spec.get("linear_spring", False))
    meta = dict(case["meta"])
    if "restoring" in spec:
        meta["restoring"] = spec["restoring"]
    run = Run(t, xs, metadata={"gain_uncertainty": 0.0, **meta})
    force = module.DUFFING
    measure = force.measure
    if "beta" in spec:
        beta = float(spec["beta"])

        def held(_times: Any, _values: Any) -> tuple[Any, dict[str, float]]:
            return module.duffing(beta), {"beta": beta, "beta_se": 1e-12 * max(beta, 1e-9)}

        object.__setattr__(force, "measure", held)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(run, law=rc.LAW, seed=int(np.random.default_rng(entropy).integers(2**31)))
    finally:
        object.__setattr__(force, "measure", measure)
    diagnostics = result.record.diagnostics or {}
    out: dict[str, Any] = {
        "index": index,
        "chi2_map": diagnostics.get("chi2_map"),
        "increments": diagnostics.get("n_increments"),
    }
    for p, truth in rc.TRUTH.items():
        s = np.asarray(result.samples(rc.REPORTED[p]), dtype=float)
        out[p] = {"sd": float(s.std(ddof=1)), "z": float((s.mean() - truth) / s.std(ddof=1))}
    return out


def summary(records: list[dict[str, Any]]) -> dict[str, Any]:
    """z mean and sd per parameter, χ²/m."""
    out: dict[str, Any] = {"runs": len(records)}
    for p in rc.TRUTH:
        z = np.array([r[p]["z"] for r in records])
        out[p] = {"z_mean": float(z.mean()), "z_sd": float(z.std(ddof=1))}
    out["chi2_per_increment"] = float(
        np.mean([r["chi2_map"] / r["increments"] for r in records if r["chi2_map"]])
    )
    return out


def bundled_observations() -> dict[str, Any]:
    """Per bundled run: a hash of what the likelihood observes (``prepare``'s grid,
    increments, variances and nuisance design) and whether its increments are
    correlated, for the package imported."""
    import glob
    import hashlib

    from bayestribo.inference.preparation import prepare

    out = {}
    root = Path(__file__).resolve().parents[1] / "data" / "runs"
    for path in sorted(glob.glob(str(root / "*.csv"))):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = prepare(path).data
        digest = hashlib.sha256()
        for a in (data.tau_grid, data.increments, data.variance, data.offset_design):
            digest.update(np.ascontiguousarray(a).tobytes())
        out[Path(path).name] = {
            "sha256": digest.hexdigest()[:16],
            "correlated": data.correlation is not None,
        }
    return out


_TIMED = """
import sys, time, warnings, zlib
import numpy as np
sys.path.insert(0, {here!r})
import restoring_coverage as rc
from bayestribo import fit
from bayestribo.io.run import Run
name, index = {name!r}, {index}
case = rc.CASES[name]
entropy = [{seed}, zlib.crc32(name.encode()), index]
t, x, _ = rc.simulate(case)
xs = x + np.random.default_rng(entropy).normal(0.0, case["noise"], x.size)
run = Run(t, xs, metadata={{"gain_uncertainty": 0.0, **case["meta"]}})
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    fit(run, law=rc.LAW, seed=1)
    start = time.process_time()
    fit(run, law=rc.LAW, seed=int(np.random.default_rng(entropy).integers(2**31)))
    print(time.process_time() - start)
"""


def cpu_side_by_side(baseline: str, repeats: int, seed: int) -> dict[str, Any]:
    """Process CPU time of one fit (after a warm-up fit) of runs 0 .. repeats-1 of
    pendulum-90 and duffing-5pc, this tree's package and ``baseline``'s alternating, each
    in its own subprocess."""
    import os
    import statistics
    import subprocess

    trees = {"baseline": baseline, "this": str(Path(__file__).resolve().parents[1])}
    times: dict[str, dict[str, list[float]]] = {k: {} for k in trees}
    for name in ("pendulum-90", "duffing-5pc"):
        for index in range(repeats):
            order = ["baseline", "this"] if index % 2 == 0 else ["this", "baseline"]
            for tree in order:
                code = _TIMED.format(
                    here=str(Path(__file__).parent), name=name, index=index, seed=seed
                )
                env = {**os.environ, "PYTHONPATH": trees[tree]}
                done = subprocess.run(
                    [sys.executable, "-c", code], capture_output=True, text=True, env=env
                )
                cpu = float(done.stdout.strip().splitlines()[-1])
                times[tree].setdefault(name, []).append(cpu)
                print(name, index, tree, cpu, flush=True)
    summary = {}
    for name in times["this"]:
        before = statistics.median(times["baseline"][name])
        after = statistics.median(times["this"][name])
        summary[name] = {"baseline_median": before, "median": after, "ratio": after / before}
    return {"trees": trees, "seconds": times, "summary": summary}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--fits", type=int, default=0, help="fits per variant (0: none)")
    parser.add_argument("--variants", nargs="*", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--output", default="restoring_width")
    parser.add_argument(
        "--bundled",
        action="store_true",
        help="only the bundled runs' observations (run with each package to compare)",
    )
    parser.add_argument("--cpu", default=None, help="a baseline worktree: CPU side by side")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    results: dict[str, Any] = {"benchmark": "restoring_width", "seed": args.seed}
    if args.cpu:
        results["cpu"] = cpu_side_by_side(args.cpu, args.repeats, args.seed)
        print(write_results(args.output, results))
        return 0
    if args.bundled:
        import bayestribo

        results["package"] = str(Path(bayestribo.__file__).parent)
        results["bundled"] = bundled_observations()
        print(write_results(args.output, results))
        return 0
    noise = {}
    for name, linear in (("pendulum-90", False), ("duffing-5pc", False), ("duffing-5pc", True)):
        key = f"{name}{'-linear-spring' if linear else ''}"
        noise[key] = noise_of_increments(name, args.seed, linear)
        print(key, noise[key], flush=True)
    results["noise_of_increments"] = noise
    fits: dict[str, Any] = {}
    for variant in args.variants if args.fits else ():
        records = [one_fit(variant, i, args.seed) for i in range(args.fits)]
        fits[variant] = {"summary": summary(records), "records": records}
        print(variant, fits[variant]["summary"], flush=True)
        results["fits"] = fits
        write_results(args.output, results)
    print(write_results(args.output, results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
