"""A pendulum recorded as a length: does the warning's advice work when followed?

Each record is its own simulation, independent of the package: ``solve_ivp`` (DOP853,
rtol 1e-10) half cycle by half cycle of a gravity pendulum with viscous damping and
Coulomb friction at the pivot,

    θ'' = -ω₀² sin θ - 2ζω₀ θ' - ω₀² μ_k sgn θ',

sticking at the first turning point where |sin θ| <= μ_s, released at rest from θ₀
after ``PRE`` s at rest, kept ``POST`` s after the stop, and recorded as a video
tracker or a laser on the bob would, ``x = r sin θ`` with r = g/ω₀² (a simple
pendulum, g = 9.80665 m/s²), in metres with white noise, the displacement alone
(``time_s,displacement_m``; sidecar ``natural_frequency_Hz``). For each release
angle and seed the command line is run as a user would, ``bayestribo fit FILE
--json``; where a warning advises an option (the ``--pendulum-radius ...`` it
prints, copied from the text as it stands), the fit is run again with it, and its
exit status, warnings and the 95 % intervals of ζ and the friction angle θ_c (= μ_k)
are checked against the truth.

Run::

    python benchmarks/pendulum_arm.py [--angles 10 20 40 60] [--seeds 0-9] [--jobs 2]

Results: ``benchmarks/results/pendulum_arm.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

#: The rig: small-swing frequency [Hz], ζ, μ_k and μ_s (a friction angle [rad]).
F0, ZETA, MU_K, MU_S = 0.7, 0.003, 0.004, 0.006
G = 9.80665
RADIUS = G / (2 * math.pi * F0) ** 2
#: Sample rate [Hz], rest before the release and after the stop [s], noise on x [m].
FS, PRE, POST, NOISE = 500.0, 1.0, 5.0, 2e-4
#: An option a warning advises, as printed (``--pendulum-radius simple``).
ADVICE = re.compile(r"\(--pendulum-radius (simple|[0-9.eE+-]+)\)")


def simulate(theta0: float) -> tuple[np.ndarray, np.ndarray]:
    """The noise-free angle [rad] sampled at ``FS`` from 0 to ``POST`` s after the stop
    (the record ends at rest, as a user records a decay to its end)."""
    w = 2 * math.pi * F0
    pieces: list[tuple[float, float, Any]] = []
    y, t0 = theta0, PRE
    while not (t0 > PRE and abs(math.sin(y)) <= MU_S):
        sgn = -1.0 if y > 0 else 1.0

        def rhs(_t: float, s: list[float], sgn: float = sgn) -> list[float]:
            return [s[1], -w * w * math.sin(s[0]) - 2 * ZETA * w * s[1] - w * w * MU_K * sgn]

        def turned(_t: float, s: list[float]) -> float:
            return s[1]

        turned.terminal = True  # type: ignore[attr-defined]
        turned.direction = 1.0 if sgn < 0 else -1.0  # type: ignore[attr-defined]
        sol = solve_ivp(
            rhs,
            (t0, t0 + 10 / F0),
            [y, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        pieces.append((t0, t1, sol.sol))
        y, t0 = float(sol.y_events[0][0][0]), t1
    t = np.arange(0.0, t0 + POST, 1.0 / FS)
    theta = np.full_like(t, y)  # stuck from t0 on
    theta[t < PRE] = theta0
    for start, end, motion in pieces:
        inside = (t >= start) & (t < end)
        theta[inside] = motion(t[inside])[0]
    return t, theta


def write_record(d: Path, degrees: float, seed: int) -> Path:
    """The record of one release angle and seed, with its sidecar."""
    t, theta = simulate(math.radians(degrees))
    rng = np.random.default_rng([seed, int(degrees)])
    x = RADIUS * np.sin(theta) + rng.normal(0.0, NOISE, t.size)
    path = d / f"pendulum_{int(degrees)}deg_seed{seed}.csv"
    rows = [f"{a:.4f},{b:.7f}" for a, b in zip(t, x, strict=True)]
    path.write_text("time_s,displacement_m\n" + "\n".join(rows) + "\n")
    path.with_suffix(".json").write_text(json.dumps({"natural_frequency_Hz": F0}))
    return path


def command(args: list[str], env: dict[str, str], timeout: float) -> dict[str, Any]:
    """``bayestribo fit ARGS --json`` in a subprocess: exit, warnings, coverage, CPU."""
    t0 = os.times()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "bayestribo", "fit", *args, "--json"],
            capture_output=True,
            text=True,
            env=env,
            timeout=timeout,
        )
        rc, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = None, "", "timeout"
    t1 = os.times()
    rec: dict[str, Any] = {
        "args": args[1:],
        "rc": rc,
        "cpu_s": round(t1.children_user - t0.children_user, 2),
        "warnings": re.findall(r"^bayestribo fit: warning: (.*)$", err, re.MULTILINE),
    }
    if rc not in (0, 1):
        rec["stderr"] = err[-1500:]
    try:
        res = json.loads(out)
    except json.JSONDecodeError:
        return rec
    params = res.get("parameters") or {}
    rec["law"] = res.get("law")
    rec["converged"] = (res.get("diagnostics") or {}).get("converged")
    rec["coverage"] = {}
    for name, truth in (("zeta", ZETA), ("friction", MU_K)):
        key = "zeta" if name == "zeta" else "friction_displacement"
        if key not in params:
            continue
        if name == "friction":  # an angle once read as one, else x_c ≈ r μ_k [m]
            truth = MU_K if params[key].get("unit") == "rad" else MU_K * RADIUS
        lo, hi = params[key]["interval"]
        mean, sd = params[key].get("mean"), params[key].get("sd")
        rec["coverage"][name] = {
            "parameter": key,
            "unit": params[key].get("unit"),
            "truth": truth,
            "interval": [lo, hi],
            "mean": mean,
            "sd": sd,
            "z": None if not sd else (mean - truth) / sd,
            "covers": bool(lo <= truth <= hi),
        }
    return rec


def one(degrees: float, seed: int, d: Path, env: dict[str, str], timeout: float) -> dict:
    """The default fit of one record, and the fit its warnings advise, if any."""
    path = write_record(d, degrees, seed)
    first = command([str(path)], env, timeout)
    advised = sorted({m for w in first["warnings"] for m in ADVICE.findall(w)})
    rec: dict[str, Any] = {"degrees": degrees, "seed": seed, "first": first, "advised": advised}
    if advised:
        rec["followed"] = command([str(path), "--pendulum-radius", advised[0]], env, timeout)
    return rec


def seeds(text: str) -> list[int]:
    """``0-9`` or ``0,3,5``."""
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def summary(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per release angle: advised, exits, coverage of the followed fits."""
    out: dict[str, Any] = {}
    for deg in sorted({r["degrees"] for r in records}):
        rs = [r for r in records if r["degrees"] == deg]
        fol = [r["followed"] for r in rs if "followed" in r]
        row: dict[str, Any] = {
            "records": len(rs),
            "first_exits": [r["first"]["rc"] for r in rs],
            "advised": sum(bool(r["advised"]) for r in rs),
            "followed_exits": [f["rc"] for f in fol],
        }
        for name in ("zeta", "friction"):
            cov = [f["coverage"][name] for f in fol if name in (f.get("coverage") or {})]
            row[name] = {
                "covered": sum(c["covers"] for c in cov),
                "of": len(cov),
                "z": [round(c["z"], 2) for c in cov if c["z"] is not None],
            }
        out[str(int(deg))] = row
    return out


def table(path: Path) -> str:
    """The results by release angle as a Markdown table (``--table``)."""
    records = json.loads(path.read_text())["records"]
    out = [
        "| release | records | default fit: exit 0 / 1 (intervals of ζ covering at exit 0) "
        "| advised `--pendulum-radius simple` | followed: exit 0 / 1 | ζ covered, z mean ± sd "
        "| θ_c covered, z mean ± sd |",
        "|---|---|---|---|---|---|---|",
    ]
    for deg in sorted({r["degrees"] for r in records}):
        rs = [r for r in records if r["degrees"] == deg]
        first = [r["first"] for r in rs]
        zero = [f for f in first if f["rc"] == 0]
        covered0 = sum(bool(f.get("coverage", {}).get("zeta", {}).get("covers")) for f in zero)
        fol = [r["followed"] for r in rs if "followed" in r]
        cells = [
            f"{deg:.0f}°",
            str(len(rs)),
            f"{len(zero)} / {sum(f['rc'] == 1 for f in first)} ({covered0} of {len(zero)})",
            f"{sum(bool(r['advised']) for r in rs)} of {len(rs)}",
            f"{sum(f['rc'] == 0 for f in fol)} / {sum(f['rc'] == 1 for f in fol)}",
        ]
        for name in ("zeta", "friction"):
            cov = [f["coverage"][name] for f in fol if name in (f.get("coverage") or {})]
            z = np.array([c["z"] for c in cov if c["z"] is not None])
            spread = f"{z.mean():+.2f} ± {z.std(ddof=1):.2f}" if z.size > 1 else "-"
            cells.append(f"{sum(c['covers'] for c in cov)}/{len(cov)}, {spread}")
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--angles", type=float, nargs="+", default=[10.0, 20.0, 40.0, 60.0])
    ap.add_argument("--seeds", type=seeds, default=list(range(10)))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--name", default="pendulum_arm")
    ap.add_argument("--table", action="store_true", help="print the stored results as a table")
    a = ap.parse_args()
    if a.table:
        from _machine import RESULTS

        print(table(RESULTS / f"{a.name}.json"))
        return
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    jobs = [(deg, s) for s in a.seeds for deg in a.angles]
    records: list[dict[str, Any]] = []
    lock = threading.Lock()

    def run(job: tuple[float, int]) -> None:
        rec = one(job[0], job[1], d, env, a.timeout)
        with lock:  # what is done so far, written as it lands (a long run cut short)
            records.append(rec)
            partial = {"commit": commit(), "done": len(records), "of": len(jobs)}
            write_results(f"{a.name}_partial", {**partial, "records": records})

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        with ThreadPoolExecutor(a.jobs) as pool:
            list(pool.map(run, jobs))
    records.sort(key=lambda r: (r["degrees"], r["seed"]))
    for r in records:
        f = r.get("followed") or {}
        cov = " ".join(
            f"{k}:{'ok' if v['covers'] else 'MISS'}" for k, v in (f.get("coverage") or {}).items()
        )
        print(
            f"{r['degrees']:4.0f}° seed {r['seed']}: first rc={r['first']['rc']} "
            f"advised={r['advised']} then rc={f.get('rc')} {cov}"
        )
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    payload = {
        "commit": commit(),
        "date": stamp,
        "rig": {
            "f0_Hz": F0,
            "zeta": ZETA,
            "mu_k_rad": MU_K,
            "mu_s_rad": MU_S,
            "radius_m": RADIUS,
            "fs_Hz": FS,
            "rest_before_and_after_s": [PRE, POST],
            "noise_m": NOISE,
        },
        "summary": summary(records),
        "records": records,
    }
    print(json.dumps(payload["summary"], indent=1))
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
