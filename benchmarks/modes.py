"""Mode check calibration: false modes, weights of true modes, and fits of real recordings.

:func:`bayestribo.inference.modes.find_modes` (the rule of its module notes) on

* independent draws of unimodal laws (normal, Student t₃ and t₁, log-normal σ = 1.5
  and 2.5, exponential × uniform), 100 seeds × 1000, 4000 and 10 000 draws each:
  the fraction of samples where a second mode is split off (false modes);
* a two-Gaussian mixture in 2-D (weights 0.75/0.25, 8.9 sd apart) sampled with the
  package's ``run_ensembles`` (32 walkers × 2 ensembles, walkers started uniformly
  over both), ``--seeds`` seeds: modes found, and the error of the minor weight;
* fits of the bundled runs (every ``--every``-th file, 2 seeds, with and without the
  discrepancy term): fits with more than one population, and fits made not converged
  by the check;
* fits of the AppStat2020 recordings HarmOsc1-3 (6 seeds, with and without the
  discrepancy term): populations found (kind, weight), converged or not, and any
  crash.

Run: ``python benchmarks/modes.py [--seeds N] [--every K]``; writes
``benchmarks/results/modes.json`` and prints a summary.
"""

from __future__ import annotations

import argparse
import glob
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import write_results

from bayestribo.inference.modes import find_modes
from bayestribo.inference.sampling import SamplerSettings, run_ensembles

REPO = Path(__file__).resolve().parents[1]
APPSTAT = REPO.parent / "shared/external-data/appstat2020-harmonic-oscillator"

LAWS = {
    "normal": lambda r, n: r.standard_normal((n, 3)),
    "student-t3": lambda r, n: r.standard_t(3, size=(n, 2)),
    "student-t1": lambda r, n: r.standard_t(1, size=(n, 2)),
    "lognormal-1.5": lambda r, n: np.column_stack([r.lognormal(0, 1.5, n), r.standard_normal(n)]),
    "lognormal-2.5": lambda r, n: np.column_stack([r.lognormal(0, 2.5, n), r.standard_normal(n)]),
    "exponential-uniform": lambda r, n: np.column_stack([r.exponential(1.0, n), r.uniform(size=n)]),
}

WEIGHT = 0.25
CENTRES = np.array([[0.0, 0.0], [8.0, 4.0]])


def _mixture(theta: np.ndarray) -> np.ndarray:
    th = np.atleast_2d(theta)
    a = -0.5 * np.sum((th - CENTRES[0]) ** 2, axis=1) + np.log(1.0 - WEIGHT)
    b = -0.5 * np.sum((th - CENTRES[1]) ** 2, axis=1) + np.log(WEIGHT)
    return np.logaddexp(a, b)


def false_modes() -> list[dict]:
    out = []
    for name, law in LAWS.items():
        for n in (1000, 4000, 10_000):
            split = sum(
                find_modes(law(np.random.default_rng(s), n)[None], np.zeros((1, n)), [], 16).n_modes
                > 1
                for s in range(100)
            )
            out.append({"law": name, "draws": n, "samples": 100, "with_a_false_mode": split})
    return out


def mixture(seeds: int) -> dict:
    found, errors, kinds = 0, [], []
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        start = rng.uniform([-2.0, -2.0], [10.0, 6.0], size=(2, 32, 2))
        settings = SamplerSettings(n_walkers=32, n_ensembles=2, max_steps=4000)
        run = run_ensembles(_mixture, start, settings, seed=1000 + seed)
        report = find_modes(run.chains, run.log_prob, ["x", "y"], 32)
        if report.n_modes == 2:
            found += 1
            errors.append(report.modes[1].weight - WEIGHT)
            kinds.append(report.modes[1].kind)
    return {
        "seeds": seeds,
        "two_modes_found": found,
        "minor_weight_true": WEIGHT,
        "minor_weight_error_mean": float(np.mean(errors)) if errors else None,
        "minor_weight_error_sd": float(np.std(errors)) if errors else None,
        "minor_weight_error_max_abs": float(np.max(np.abs(errors))) if errors else None,
        "minor_kinds": sorted(set(kinds)),
    }


def _fit_row(label: str, run, seed: int, discrepancy: bool) -> dict:
    from bayestribo import fit

    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = fit(run, seed=seed, discrepancy=discrepancy)
    except Exception as exc:  # a crash is a result here, never hidden
        return {"run": label, "seed": seed, "discrepancy": discrepancy, "crash": repr(exc)}
    m = r.diagnostics["modes"]
    return {
        "run": label,
        "seed": seed,
        "discrepancy": discrepancy,
        "converged": r.converged,
        "n_modes": m["n_modes"],
        "matters": m["matters"],
        "minor": [
            {
                "kind": x["kind"],
                "weight": x["weight"],
                "log_prob_below_main": m["modes"][0]["log_prob"] - x["log_prob"],
            }
            for x in m["modes"][1:]
        ],
        "seconds": time.perf_counter() - t0,
    }


def fits(every: int) -> tuple[list[dict], list[dict]]:
    from bayestribo import read_run

    bundled = []
    for path in sorted(glob.glob(str(REPO / "data/runs/*.csv")))[::every]:
        for seed in range(2):
            for disc in (False, True):
                bundled.append(_fit_row(Path(path).name, path, seed, disc))
    real = []
    for name in ("HarmOsc1.txt", "HarmOsc2.txt", "HarmOsc3.txt"):
        path = APPSTAT / name
        if not path.exists():
            print(f"  {name}: not found at {path}", file=sys.stderr)
            continue
        meta = {"length_unit": "arbitrary"}
        run = read_run(path, columns=["time_s", "displacement_m"], metadata=meta)
        for seed in range(6):
            for disc in (False, True):
                real.append(_fit_row(name, run, seed, disc))
    return bundled, real


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--every", type=int, default=6)
    args = parser.parse_args()
    iid = false_modes()
    print(
        "false modes in independent draws:",
        sum(r["with_a_false_mode"] for r in iid),
        "of",
        sum(r["samples"] for r in iid),
    )
    mix = mixture(args.seeds)
    print("two-mode mixture:", mix)
    bundled, real = fits(args.every)
    n_multi = sum(r.get("n_modes", 1) > 1 for r in bundled)
    n_crash = sum("crash" in r for r in bundled + real)
    print(
        f"bundled fits: {len(bundled)}, with more than one population: {n_multi}; "
        f"crashes: {n_crash}"
    )
    for r in real:
        print(r)
    path = write_results(
        "modes",
        {"independent_draws": iid, "mixture": mix, "bundled_fits": bundled, "real_fits": real},
    )
    print(f"written {path}")


if __name__ == "__main__":
    main()
