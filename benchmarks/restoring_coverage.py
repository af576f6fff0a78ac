"""Coverage of the laws' fits on a nonlinear restoring force, given as ``restoring``.

Each run is simulated here, independently of the package: ``scipy.integrate.solve_ivp``
(DOP853, rtol 1e-10) half cycle by half cycle (the direction of motion, hence the sign
of the friction, is constant between velocity zeros) of

    θ'' = -ω₀² V'(θ) - 2ζω₀ θ' - c₂ θ'|θ'| - ω₀² μ_k sgn θ',

sticking at the first turning point where |V'(θ)| <= μ_k, in the two cases

==============  ===========================================================================
pendulum-90     V'(θ) = sin θ (radians), released at rest at 90°, f₀ = 0.5 Hz, 100 Hz
duffing-5pc     V'(x) = x + βx³ (mm), β = 0.033 mm⁻², released at 2 mm (the half period
                5 % shorter at the release than at small swings), f₀ = 2 Hz, 200 Hz
duffing-small   the same spring released at 0.8 mm (0.8 % shorter), 10 s, 10 µm of noise:
                β known to some 20 % only (its standard error from the half periods)
pendulum-90-    pendulum-90 recorded as a length (``length_unit`` ``arbitrary``) and
length-auto     fitted with ``restoring`` ``auto``: the pendulum is not open to it (its
                potential takes radians), and the Duffing spring it chooses is the
                wrong force
==============  ===========================================================================

with ζ = 0.005, c₂ = 0.01 per unit and μ_k = 0.002 units, 60 s (pendulum) or 20 s
(duffing-5pc) of motion, and white noise on the displacement alone (1 mrad; 1 µm), the
velocity derived by the package. Each run is fitted with :func:`bayestribo.fit`,
``law="viscous+quadratic+coulomb"`` and ``restoring`` given (the Duffing's β measured
from the record's half periods), and the 95 % interval, mean and sd of ζ, c₂ and μ_k
are recorded against the truth: coverage (with its Clopper-Pearson interval) and the
mean and sd of z = (mean - truth)/sd per parameter. A Duffing run records β, its
standard error and what its marginalisation added (the result's ``restoring`` record,
:mod:`bayestribo.inference.restoring_error`; absent in a package without it).

Run: ``python benchmarks/restoring_coverage.py --runs 40 --out
benchmarks/results/restoring_coverage.json``; ``--linear`` fits the same runs without
``restoring`` (``restoring_coverage_linear.json``).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
import warnings
import zlib
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats
from scipy.integrate import solve_ivp

ZETA, C2, MU_K = 0.005, 0.01, 0.002
TRUTH = {"zeta": ZETA, "c2": C2, "mu_k": MU_K}
#: The name of each parameter in the result (a run without a load reports the friction
#: as a displacement, in the run's unit: here the law's μ_k itself).
REPORTED = {"zeta": "zeta", "c2": "c2", "mu_k": "friction_displacement"}
LAW = "viscous+quadratic+coulomb"
CASES: dict[str, dict[str, Any]] = {
    "pendulum-90": {
        "f0": 0.5,
        "fs": 100.0,
        "x0": math.pi / 2,
        "duration": 60.0,
        "noise": 1e-3,
        "beta": None,
        "meta": {"length_unit": "rad", "restoring": "pendulum"},
    },
    "duffing-5pc": {
        "f0": 2.0,
        "fs": 200.0,
        "x0": 2.0,
        "duration": 20.0,
        "noise": 1e-3,
        "beta": 0.033,
        "meta": {"length_unit": "arbitrary", "restoring": "duffing"},
    },
    "pendulum-90-length-auto": {
        "f0": 0.5,
        "fs": 100.0,
        "x0": math.pi / 2,
        "duration": 60.0,
        "noise": 1e-3,
        "beta": None,
        "meta": {"length_unit": "arbitrary", "restoring": "auto"},
    },
    "duffing-small": {
        "f0": 2.0,
        "fs": 200.0,
        "x0": 0.8,
        "duration": 10.0,
        "noise": 1e-2,
        "beta": 0.033,
        "meta": {"length_unit": "arbitrary", "restoring": "duffing"},
    },
}


def spring(case: dict[str, Any], x: float) -> float:
    """V'(x) of the case."""
    if case["beta"] is None:
        return math.sin(x)
    return x + case["beta"] * x**3


def simulate(case: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The noise-free displacement and velocity sampled at ``fs`` from release to
    ``duration``."""
    w = 2.0 * math.pi * case["f0"]
    t = np.arange(0.0, case["duration"], 1.0 / case["fs"])
    x = np.empty_like(t)
    v = np.zeros_like(t)
    y, t0 = float(case["x0"]), 0.0
    filled = 0
    while filled < t.size:
        sgn = -1.0 if y > 0 else 1.0
        if abs(spring(case, y)) <= MU_K:
            x[filled:] = y  # stuck
            break

        def rhs(_t: float, s: list[float], sgn: float = sgn) -> list[float]:
            return [
                s[1],
                -w * w * spring(case, s[0])
                - 2 * ZETA * w * s[1]
                - C2 * s[1] * abs(s[1])
                - w * w * MU_K * sgn,
            ]

        def turned(_t: float, s: list[float]) -> float:
            return s[1]

        turned.terminal = True  # type: ignore[attr-defined]
        turned.direction = 1.0 if sgn < 0 else -1.0  # type: ignore[attr-defined]
        sol = solve_ivp(
            rhs,
            (t0, t0 + 10.0 / case["f0"]),
            [y, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(t, t1, side="right"))
        x[filled:stop], v[filled:stop] = sol.sol(t[filled:stop])
        filled = stop
        y, t0 = float(sol.y_events[0][0][0]), t1
    return t, x, v


def one_run(
    name: str, index: int, seed: int, max_steps: int | None, linear: bool = False
) -> dict[str, Any]:
    """Simulate and fit run ``index`` of case ``name`` (``linear``: without
    ``restoring``, the laws on the linear spring, for comparison)."""
    from bayestribo import fit
    from bayestribo.io.run import Run

    case = CASES[name]
    entropy = [seed, zlib.crc32(name.encode()), index]
    t, x, _ = simulate(case)
    xs = x + np.random.default_rng(entropy).normal(0.0, case["noise"], x.size)
    meta = {k: v for k, v in case["meta"].items() if not (linear and k == "restoring")}
    run = Run(t, xs, metadata={"gain_uncertainty": 0.0, **meta})
    out: dict[str, Any] = {"case": name, "index": index, "entropy": entropy}
    start = time.process_time()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            options = {} if max_steps is None else {"max_steps": max_steps}
            result = fit(
                run, law=LAW, seed=int(np.random.default_rng(entropy).integers(2**31)), **options
            )
    except Exception as exc:  # recorded, never dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    out["cpu_seconds"] = time.process_time() - start
    out["warnings"] = sorted({w.category.__name__ for w in caught})
    out["converged"] = bool(result.converged)
    spring = result.record.restoring or {}
    if "beta" in spring:
        out["beta"] = {
            "value": spring["beta"],
            "se": spring["beta_se"],
            # a pendulum fitted as a Duffing spring has no true β
            "z": None
            if case["beta"] is None
            else (spring["beta"] - case["beta"]) / spring["beta_se"],
            "error": spring.get("error"),
        }
    for p, truth in TRUTH.items():
        s = np.asarray(result.samples(REPORTED[p]), dtype=float)
        lo, hi = (float(b) for b in result.interval(REPORTED[p], 0.95))
        out[p] = {
            "mean": float(s.mean()),
            "sd": float(s.std(ddof=1)),
            "interval": [lo, hi],
            "covered": bool(lo <= truth <= hi),
            "z": float((s.mean() - truth) / s.std(ddof=1)),
        }
    return out


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Coverage and z statistics per case and parameter."""
    table: dict[str, Any] = {}
    for name in CASES:
        done = [r for r in records if r["case"] == name and "refused" not in r]
        row: dict[str, Any] = {
            "runs": sum(r["case"] == name for r in records),
            "refused": sum(r["case"] == name and "refused" in r for r in records),
        }
        for p in TRUTH:
            k, n = sum(r[p]["covered"] for r in done), len(done)
            z = np.array([r[p]["z"] for r in done])
            lo = stats.beta.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
            hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
            row[p] = {
                "covered": k,
                "of": n,
                "coverage": k / n if n else math.nan,
                "coverage_95ci": [float(lo), float(hi)],
                "z_mean": float(z.mean()) if n else math.nan,
                "z_sd": float(z.std(ddof=1)) if n > 1 else math.nan,
            }
        measured = [r["beta"] for r in done if "beta" in r and r["beta"]["z"] is not None]
        if measured:
            zb = np.array([b["z"] for b in measured])
            added = [
                max(b["error"]["sd_added_over_sd"][p] for p in TRUTH)
                for b in measured
                if b.get("error")
            ]
            row["beta"] = {
                "of": len(measured),
                "relative_se_mean": float(np.mean([b["se"] / b["value"] for b in measured])),
                "z_mean": float(zb.mean()),
                "z_sd": float(zb.std(ddof=1)) if zb.size > 1 else math.nan,
                "marginalised": len(added),
                "sd_added_over_sd_max": float(max(added)) if added else None,
                "sd_added_over_sd_median": float(np.median(added)) if added else None,
            }
        table[name] = row
    return table


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--cases", nargs="*", default=list(CASES))
    parser.add_argument("--max-steps", type=int, default=None)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument(
        "--linear", action="store_true", help="fit without 'restoring' (the linear spring)"
    )
    args = parser.parse_args(argv)
    _SOURCE.update(_source())
    records = []
    for name in args.cases:
        for i in range(args.runs):
            r = one_run(name, i, args.seed, args.max_steps, args.linear)
            records.append(r)
            brief = r.get("refused") or " ".join(
                f"{p} z={r[p]['z']:+.2f}{'' if r[p]['covered'] else '!'}" for p in TRUTH
            )
            print(f"{name} {i}: {brief}", flush=True)
            if args.out:
                _write(args, records)
    table = _write(args, records) if args.out else summarise(records)
    print(json.dumps(table, indent=1))
    return 0


def _source() -> dict[str, Any]:
    """The package's commit and whether its files differ from it, at the start."""

    def git(*a: str) -> str:
        here = Path(__file__).parent
        return subprocess.run(["git", *a], capture_output=True, text=True, cwd=here).stdout

    import bayestribo

    return {
        "package": str(Path(bayestribo.__file__).parent),
        "commit": git("rev-parse", "HEAD").strip(),
        "package_changed": bool(git("status", "--porcelain", "--", "../bayestribo").strip()),
    }


_SOURCE: dict[str, Any] = {}


def _write(args: argparse.Namespace, records: list[dict[str, Any]]) -> dict[str, Any]:
    table = summarise(records)
    payload = {
        "benchmark": "restoring_coverage",
        "law": LAW,
        "truth": TRUTH,
        "cases": CASES,
        "seed": args.seed,
        "restoring_given": not args.linear,
        **_SOURCE,
        "summary": table,
        "records": records,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(payload, indent=1, default=str) + "\n")
    return table


if __name__ == "__main__":
    sys.exit(main())
