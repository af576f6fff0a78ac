"""Records through a sensor's analog high-pass: named, and answered when the advice is followed.

Each record is its own simulation, none from the package's simulator: the closed-form
viscous + Coulomb decay of ``unseen_rigs.simulate`` (noise-free, at ten times the
record's rate), put through an analog high-pass by :func:`scipy.signal.lsim` and taken
at the record's samples (one pole ``s/(s + ω_c)``, an RC coupling; two
poles ``s²/(s² + 2ζ_g ω_c s + ω_c²)``, ζ_g = 0.7, a geophone), the sensor's white
noise added after it, written as a velocity alone (mm/s) or a displacement alone (mm)
with the rig's sidecar. Per record the rig is drawn (f 2-8 Hz, ζ 0.004-0.015, μ_k
0.01-0.03, released at 20 mm from rest, 1 s of rest before and 3 s after, 500 Hz) and
the corner is a fraction of f (0.1, 0.3, 1).

For each record, the sign this tree reads (:func:`bayestribo.signal.high_pass.
detect_high_pass` at the prepared run's turning times, what the fit's warning says
with its ``--sensor-high-pass`` option: a ``HighPassWarning`` is a misfit, exit 1);
where it names one, ``bayestribo fit FILE --json`` with the option as the warning
writes it (:func:`unseen_rigs3.warning_advice` on the warning's text), else the bare
fit; and the fit with the true declaration: exit status and whether the 95 % intervals
of ζ and μ_k cover. Main's package (``--base``) fits the bare record of the first
``--main-seeds`` seeds of each case (a misfitting fit is slow: 40 s of CPU and more).

Run::

    python benchmarks/high_pass.py --base /path/to/main-worktree [--seeds 8] [--jobs 2]

Results: ``benchmarks/results/high_pass.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import lsim

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results
from unseen_rigs import rig, sidecar
from unseen_rigs3 import csv_rows, fit_record, warning_advice

#: Corner frequencies as fractions of the rig's frequency.
RATIOS = (0.1, 0.3, 1.0)
#: The geophone's damping (two poles).
DAMPING = 0.7
#: Sensor noise after the filter: velocity [m/s] and displacement [m].
NOISE = {"velocity": 2e-4, "displacement": 2e-6}
#: The cases: (channel, poles).
CASES = (("velocity", 1), ("velocity", 2), ("displacement", 1))


def high_passed(t: np.ndarray, u: np.ndarray, cutoff: float, order: int) -> np.ndarray:
    """``u`` through the analog high-pass, its state zero at the first sample (the
    sensor settled at rest: the record starts in the rest before the release)."""
    w = 2 * np.pi * cutoff
    if order == 1:
        system = ([1.0, 0.0], [1.0, w])
    else:
        system = ([1.0, 0.0, 0.0], [1.0, 2 * DAMPING * w, w * w])
    _, y, _ = lsim(system, u - u[0], t)
    return y


def record(d: Path, channel: str, order: int, ratio: float, seed: int) -> dict[str, Any]:
    """Write one record and return its path, truth and declaration."""
    rng = np.random.default_rng(1000 * order + 100 * int(10 * ratio) + seed)
    f = float(rng.uniform(2.0, 8.0))
    p = {
        "f": f,
        "zeta": float(rng.uniform(0.004, 0.015)),
        "mu_k": float(rng.uniform(0.01, 0.03)),
        "N": 1.0,
        "m": 0.3,
        "x0": 0.02,
        "fs": 500.0,
        "t_pre": 1.0,
        "t_post": 3.0,
        "nx": 0.0,
        "nv": 0.0,
    }
    # the analog filter on the motion sampled ten times finer, then the record's samples
    r = rig(seed, **{**p, "fs": 10 * p["fs"]})
    cutoff = ratio * f
    u = r["v"] if channel == "velocity" else r["x"]
    y = high_passed(r["t"], u, cutoff, order)[::10]
    r["t"] = r["t"][::10]
    y = y + rng.normal(0, NOISE[channel], y.size)
    name = f"{channel}_{order}p_{ratio:g}f_s{seed}"
    path = d / f"{name}.csv"
    column = "velocity_mm_per_s" if channel == "velocity" else "displacement_mm"
    path.write_text(f"time_s,{column}\n" + "\n".join(csv_rows([r["t"], y * 1e3], ".6f")) + "\n")
    sidecar(path, r["meta"])
    declared = f"{cutoff:.6g}" if order == 1 else f"{cutoff:.6g}:2:{DAMPING}"
    return {
        "name": name,
        "path": path,
        "channel": channel,
        "order": order,
        "ratio": ratio,
        "seed": seed,
        "cutoff_Hz": cutoff,
        "frequency_Hz": f,
        "truth": {k: r["truth"][k] for k in ("zeta", "mu_k")},
        "declared": ["--sensor-high-pass", declared],
    }


_NAMED = re.compile(r"--sensor-high-pass ([0-9.eE+-]+(?::[0-9.]+)*)")


def brief(fit: dict[str, Any]) -> dict[str, Any]:
    """Exit status, warnings' categories and coverage of a :func:`fit_record`."""
    cov = fit.get("coverage") or {}
    return {
        "command": fit["command"],
        "rc": fit["rc"],
        "cpu_s": fit["cpu_s"],
        "warnings": [w[0] if isinstance(w, list | tuple) else w for w in fit["warnings"]],
        "covers": {k: v.get("covers") for k, v in cov.items()},
        "z": {k: v.get("z") for k, v in cov.items()},
    }


def sign_of(path: str, env: dict[str, str]) -> dict[str, Any]:
    """The sign this tree reads in the record and the warning's advice, in a subprocess
    of ``env``'s package."""
    code = (
        "import json, sys, warnings; warnings.simplefilter('ignore')\n"
        "from bayestribo import read_run\n"
        "from bayestribo.inference.preparation import prepare\n"
        "from bayestribo.signal.high_pass import detect_high_pass\n"
        "run = read_run(sys.argv[1]); tt = prepare(run).decay.turning_times\n"
        "v = run.velocity is not None\n"
        "s = None if tt is None else detect_high_pass(run.time, run.velocity if v else "
        "run.displacement, tt, velocity=v)\n"
        "print(json.dumps(None if s is None else {'advice': s.advice(), 'order': s.order, "
        "'cutoff_Hz': s.cutoff_Hz, 'cutoff_se_Hz': s.cutoff_se_Hz, 'z': s.z, "
        "'damping': s.damping}))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, path], capture_output=True, text=True, env=env, timeout=900
    )
    try:
        return json.loads(proc.stdout) or {}
    except json.JSONDecodeError:
        return {"error": proc.stderr[-500:]}


def one(
    rec: dict[str, Any], here: dict[str, str], base: dict[str, str] | None, main_seeds: int
) -> dict[str, Any]:
    """The fits of one record (see the module notes)."""
    path, truth = str(rec["path"]), rec["truth"]
    out = {k: v for k, v in rec.items() if k != "path"}
    if base is not None and rec["seed"] < main_seeds:
        out["main"] = brief(fit_record(path, [], truth, base, 1800))
    sign = sign_of(path, here)
    out["sign"] = sign
    named = _NAMED.search(sign.get("advice", ""))
    out["named"] = named[1] if named else None
    if named:
        advice = warning_advice(sign["advice"], [])
        out["advice"] = advice
        out["followed"] = brief(fit_record(path, advice, truth, here, 1800))
    else:
        out["here"] = brief(fit_record(path, [], truth, here, 1800))
    out["declared_fit"] = brief(fit_record(path, rec["declared"], truth, here, 1800))
    return out


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per case and corner: exit codes, advice named, coverage followed and declared."""
    out = []
    keys = sorted({(r["channel"], r["order"], r["ratio"]) for r in rows})
    for channel, order, ratio in keys:
        sel = [r for r in rows if (r["channel"], r["order"], r["ratio"]) == (channel, order, ratio)]

        def rcs(part: str, sel: list[dict[str, Any]] = sel) -> dict[str, int]:
            codes = [str(r[part]["rc"]) for r in sel if part in r]
            return {c: codes.count(c) for c in sorted(set(codes))}

        def covered(part: str, sel: list[dict[str, Any]] = sel) -> str:
            fits = [r[part] for r in sel if part in r]
            both = sum(all(f["covers"].get(k) for k in ("zeta", "mu_k")) for f in fits)
            silent = sum(
                f["rc"] == 0 and not all(f["covers"].get(k) for k in ("zeta", "mu_k")) for f in fits
            )
            return f"{both}/{len(fits)} (silently wrong {silent})"

        named = [r for r in sel if r.get("named")]
        est = [float(r["named"].split(":")[0]) / r["cutoff_Hz"] for r in named if r.get("named")]
        out.append(
            {
                "channel": channel,
                "poles": order,
                "corner_over_f": ratio,
                "records": len(sel),
                "main_rc": rcs("main"),
                "main_covered": covered("main"),
                "here_unnamed_rc": rcs("here"),
                "here_unnamed_covered": covered("here"),
                "named": len(named),
                "named_corner_over_true": [round(e, 3) for e in est],
                "followed_rc": rcs("followed"),
                "followed_covered": covered("followed"),
                "declared_rc": rcs("declared_fit"),
                "declared_covered": covered("declared_fit"),
            }
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, help="a worktree of main, fitted beside this tree")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--ratios", type=float, nargs="*", default=list(RATIOS))
    ap.add_argument("--name", default="high_pass")
    ap.add_argument("--main-seeds", type=int, default=2)
    ap.add_argument("--channels", nargs="*", default=["velocity", "displacement"])
    a = ap.parse_args()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    here = {**env, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    base = None if a.base is None else {**env, "PYTHONPATH": str(a.base.resolve())}
    with tempfile.TemporaryDirectory() as tmp:
        recs = [
            record(Path(tmp), channel, order, ratio, seed)
            for channel, order in CASES
            if channel in a.channels
            for ratio in a.ratios
            for seed in range(a.seeds)
        ]
        with ThreadPoolExecutor(a.jobs) as pool:
            rows = []
            for row in pool.map(lambda r: one(r, here, base, a.main_seeds), recs):
                rows.append(row)
                print(
                    row["name"],
                    row.get("main", {}).get("rc"),
                    row.get("here", {}).get("rc"),
                    row["named"],
                    row.get("followed", {}).get("rc"),
                    row.get("followed", {}).get("covers"),
                    row["declared_fit"]["rc"],
                    row["declared_fit"]["covers"],
                    flush=True,
                )
    payload = {
        "commit": commit(),
        "base_commit": None if a.base is None else commit(a.base),
        "seeds": a.seeds,
        "main_seeds": a.main_seeds,
        "summary": summary(rows),
        "records": rows,
    }
    path = write_results(a.name, payload)
    print(json.dumps(payload["summary"], indent=1))
    print(path)


if __name__ == "__main__":
    main()
