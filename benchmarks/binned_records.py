"""Records whose swings are within ten times their noise a sample, many samples a period.

A seismometer-like free decay, simulated independently of the package (the closed
form of a linear oscillator with viscous damping and Coulomb friction, half cycle by
half cycle, each about its own centre ±x_c): 0.11 Hz, sampled at 10 Hz (91 samples a
period), 4-8 cycles recorded from a random phase, its first amplitude 0.1 (arbitrary
unit) under white noise of 3-10 % of it; viscous (ζ 0.05-0.10) and viscous + Coulomb
(ζ 0.04-0.08, x_c 1.5-2.5 % of the first amplitude). Each record is given to
:func:`bayestribo.fit` here and to the package of ``--base`` (a worktree of main, in a
subprocess): refused or answered, binned or not (``BinnedRecordWarning``), and whether
each 95 % interval of ζ and of the friction displacement x_c holds the truth.

Run::

    python benchmarks/binned_records.py --base /path/to/main-worktree --seeds 12

Results: ``benchmarks/results/binned_records.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

FREQUENCY_HZ, RATE_HZ, AMPLITUDE = 0.11, 10.0, 0.1


def simulate(zeta: float, x_c: float, cycles: float, noise: float, seed: int) -> tuple:
    """Times [s] and displacement [arbitrary] of a free decay (closed form, see above),
    its first turning point at ``AMPLITUDE`` a random part of a period before t = 0,
    with white noise of ``noise`` standard deviation."""
    rng = np.random.default_rng(seed)
    omega = 2.0 * math.pi * FREQUENCY_HZ
    omega_d = omega * math.sqrt(1.0 - zeta * zeta)
    half = math.pi / omega_d
    t = np.arange(0.0, cycles / FREQUENCY_HZ, 1.0 / RATE_HZ)
    x = np.empty(t.size)
    start = -rng.uniform(0.0, 2.0 * half)
    x0, t0 = AMPLITUDE, start
    while True:
        centre = math.copysign(x_c, x0)  # moving towards the other side: friction opposes
        stuck = abs(x0) <= x_c
        inside = (t >= t0) & (t < t0 + half) if not stuck else t >= t0
        s = t[inside] - t0
        if stuck:
            x[inside] = x0
            break
        x[inside] = centre + (x0 - centre) * np.exp(-zeta * omega * s) * (
            np.cos(omega_d * s) + zeta * omega / omega_d * np.sin(omega_d * s)
        )
        x0 = centre - (x0 - centre) * math.exp(-zeta * omega * half)
        t0 += half
        if t0 > t[-1]:
            break
    return t, x + rng.normal(0.0, noise, t.size)


def cases(seeds: int) -> list[dict[str, Any]]:
    """The simulated records' settings, ``seeds`` per law."""
    out = []
    for law in ("viscous", "viscous+coulomb"):
        for seed in range(seeds):
            rng = np.random.default_rng([seed, 7 if law == "viscous" else 11])
            zeta = rng.uniform(0.05, 0.10) if law == "viscous" else rng.uniform(0.04, 0.08)
            x_c = 0.0 if law == "viscous" else AMPLITUDE * rng.uniform(0.015, 0.025)
            out.append(
                {
                    "law": law,
                    "seed": seed,
                    "zeta": float(zeta),
                    "x_c": float(x_c),
                    "cycles": float(rng.uniform(4.0, 8.0)),
                    "noise": float(AMPLITUDE * rng.uniform(0.03, 0.10)),
                }
            )
    return out


def one(case: dict[str, Any]) -> dict[str, Any]:
    """Fit one simulated record with the package imported here."""
    import bayestribo
    from bayestribo.errors import BayestriboError, MisfitWarning
    from bayestribo.io.run import Run

    t, x = simulate(case["zeta"], case["x_c"], case["cycles"], case["noise"], case["seed"])
    run = Run(t, x, None, {"length_unit": "arbitrary"})
    cpu = time.process_time()
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            result = bayestribo.fit(run)
        except BayestriboError as e:
            return {"answer": "refused", "why": str(e)[:160]}
    names = {w.category.__name__ for w in said}
    out: dict[str, Any] = {
        "answer": "fit",
        "binned": "BinnedRecordWarning" in names,
        "exit_1": any(issubclass(w.category, MisfitWarning) for w in said),
        "warnings": sorted(names),
        "converged": bool(result.converged),
        "cpu_s": round(time.process_time() - cpu, 2),
    }
    friction = "friction_displacement" if "friction_displacement" in result.summary() else None
    for name, truth in (("zeta", case["zeta"]), (friction, case["x_c"])):
        if name is None:
            continue
        lo, hi = result.interval(name)
        draws = result.samples(name)
        out[name] = {
            "mean": float(np.mean(draws)),
            "interval": [float(lo), float(hi)],
            "z": float((np.mean(draws) - truth) / np.std(draws)) if np.std(draws) > 0 else None,
            "covers": bool(lo <= truth <= hi),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=False)
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--name", default="binned_records")
    ap.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    a = ap.parse_args()
    todo = cases(a.seeds)
    if a.worker is not None:
        a.worker.write_text(json.dumps([one(c) for c in todo]))
        return
    found = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = [("here", ROOT)] + ([("base", a.base.resolve())] if a.base else [])
        for label, tree in trees:
            path = Path(tmp) / f"{label}.json"
            env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
            cmd = [sys.executable, __file__, "--seeds", str(a.seeds), "--worker", str(path)]
            subprocess.run(cmd, check=True, env=env, cwd=tmp)
            found[label] = json.loads(path.read_text())
    rows = []
    for i, case in enumerate(todo):
        row = {**case, "here": found["here"][i]}
        if "base" in found:
            row["base"] = found["base"][i]
        rows.append(row)
    here = [r["here"] for r in rows]
    fits = [h for h in here if h["answer"] == "fit"]
    summary: dict[str, Any] = {
        "records": len(rows),
        "answered_here": len(fits),
        "binned_here": sum(h["binned"] for h in fits),
        "converged_here": sum(h["converged"] for h in fits),
        "exit_1_here": sum(h["exit_1"] for h in fits),
    }
    for name in ("zeta", "friction_displacement"):
        for law in ("viscous", "viscous+coulomb"):
            got = [r["here"][name]["covers"] for r in rows if r["law"] == law and name in r["here"]]
            summary[f"{name} covered ({law})"] = f"{sum(got)} of {len(got)}"
    if "base" in found:
        summary["answered_base"] = sum(r["base"]["answer"] == "fit" for r in rows)
    print(json.dumps(summary, indent=1))
    payload = {"commit": commit(), "summary": summary, "rows": rows}
    if a.base:
        payload["base_commit"] = commit(a.base)
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
