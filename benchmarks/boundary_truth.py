"""Coverage of the default law's intervals when the truth sits on (or near) a boundary
of its prior: no friction (x_c = 0), or no viscous damping (ζ = 0).

Each run is simulated here, independently of the package, in closed form half cycle by
half cycle: between velocity zeros the sign s of the velocity is constant and

    x'' + 2ζω x' + ω² x = -ω² x_c s

is a damped linear oscillator about -s·x_c, released at rest; the motion sticks at the
first turning point with |x| <= x_c (μ_s = μ_k). The record is the displacement in
metres, ``time_s,displacement_m``, without load or mass (so the default law
``viscous+coulomb`` samples ζ, the friction displacement x_c, x_s, μ_s/μ_k and y₀),
with white noise of sd A/SNR; f = 1 Hz, A = 0.1 m, 30 periods.

Designs (fraction of the amplitude lost over the record, SNR, samples per period):

=======  =====  ======  ======
design   loss   SNR     /period
=======  =====  ======  ======
low      0.2    50      20
mid      0.5    500     50
high     0.9    1e4     200
=======  =====  ======  ======

Truths: ``xc0`` (viscous only), ``xc2`` / ``xc10`` (friction 2 % / 10 % of the loss),
``z0`` (Coulomb only), ``z2`` / ``z10`` (viscous damping 2 % / 10 % of the loss).
Each run is fitted with :func:`bayestribo.fit` (``seed=1``, the default law, or
``--law``); the 95 % intervals of ζ and x_c (the summary's, as the report shows them:
a quantity piled on its bound 0 has 0 as its lower end) are recorded against the truth,
with the result's ``boundary`` record where the package has one.

Run: ``python benchmarks/boundary_truth.py --runs 20 --out
benchmarks/results/boundary_truth_after.json`` (``PYTHONPATH`` chooses the package).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import warnings
import zlib
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

DESIGNS = {
    "low": {"loss": 0.2, "snr": 50.0, "per_period": 20},
    "mid": {"loss": 0.5, "snr": 500.0, "per_period": 50},
    "high": {"loss": 0.9, "snr": 1e4, "per_period": 200},
}
#: truth: (share of the loss to friction)
TRUTHS = {"xc0": 0.0, "xc2": 0.02, "xc10": 0.10, "z10": 0.90, "z2": 0.98, "z0": 1.0}
AMPLITUDE = 0.1  # m
FREQUENCY = 1.0  # Hz
PERIODS = 30


def truth_parameters(design: dict[str, float], share: float) -> tuple[float, float]:
    """ζ and x_c [m] that lose about ``design["loss"]`` of the amplitude over the
    record, the share ``share`` of it to friction."""
    omega = 2 * math.pi * FREQUENCY
    duration = PERIODS / FREQUENCY
    zeta_all = -math.log(1 - design["loss"]) / (omega * duration)
    xc_all = design["loss"] * AMPLITUDE / (4 * PERIODS)
    return (1 - share) * zeta_all, share * xc_all


def simulate(zeta: float, xc: float, t: np.ndarray) -> np.ndarray:
    """Displacement of the oscillator released at rest at AMPLITUDE, at times ``t``."""
    omega = 2 * math.pi * FREQUENCY
    wd = omega * math.sqrt(1 - zeta**2)
    half = math.pi / wd
    x = np.empty_like(t)
    x0, start, s = AMPLITUDE, 0.0, -1.0  # released at +A: moving down
    while start < t[-1] + half:
        inside = (t >= start) & (t < start + half)
        centre = -s * xc
        u0 = x0 - centre
        tau = t[inside] - start
        x[inside] = centre + u0 * np.exp(-zeta * omega * tau) * (
            np.cos(wd * tau) + zeta * omega / wd * np.sin(wd * tau)
        )
        x1 = centre - u0 * math.exp(-zeta * omega * half)
        start, x0, s = start + half, x1, -s
        if abs(x1) <= xc:  # sticks
            x[t >= start] = x1
            break
    return x


def record(design: str, share: float, seed: int, folder: Path) -> tuple[tuple[float, float], Path]:
    """A simulated record of ``design`` with ``share`` of the loss to friction, written
    to ``folder``: the truth (ζ, x_c [m]) and the file."""
    d = DESIGNS[design]
    zeta, xc = truth_parameters(d, share)
    t = np.arange(0, PERIODS / FREQUENCY, 1 / (FREQUENCY * d["per_period"]))
    rng = np.random.default_rng([seed, zlib.crc32(design.encode()), int(share * 100)])
    x = simulate(zeta, xc, t) + rng.normal(0, AMPLITUDE / d["snr"], t.size)
    path = folder / f"{design}_{share:g}_{seed}.csv"
    np.savetxt(path, np.c_[t, x], delimiter=",", header="time_s,displacement_m", comments="")
    return (zeta, xc), path


def one_run(design: str, truth: str, seed: int, law: str | None, folder: Path) -> dict:
    import bayestribo as bt

    (zeta, xc), path = record(design, TRUTHS[truth], seed, folder)
    run = bt.read_run(path)
    cpu = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            r = bt.fit(run, seed=1, **({"law": law} if law else {}))
        except Exception as exc:  # recorded, not hidden
            return {"design": design, "truth": truth, "seed": seed, "error": repr(exc)}
    cpu = time.process_time() - cpu
    summ = r.summary()
    out: dict[str, Any] = {
        "design": design,
        "truth": truth,
        "seed": seed,
        "law": r.law,
        "cpu_s": cpu,
        "zeta_true": zeta,
        "xc_true": xc,
        "warnings": sorted({type(w.message).__name__ for w in caught}),
        "converged": bool(r.converged),
    }
    for key, name, true in (("zeta", "zeta", zeta), ("xc", "friction_displacement", xc)):
        if name in summ:
            lo, hi = summ[name].interval
            out[key] = [float(lo), float(hi)]
            out[f"{key}_covered"] = bool(lo <= true <= hi)
        else:  # a law without that term: it is 0
            out[key] = [0.0, 0.0]
            out[f"{key}_covered"] = bool(true == 0.0)
    boundary = r.record.boundary if hasattr(r.record, "boundary") else None
    if boundary is not None:
        out["boundary"] = boundary
    return out


def table(rows: list[dict]) -> dict[str, dict[str, Any]]:
    """Coverage of ζ and x_c by design and truth."""
    out: dict[str, dict[str, Any]] = {}
    for row in rows:
        key = f"{row['design']}/{row['truth']}"
        cell = out.setdefault(key, {"n": 0, "zeta": 0, "xc": 0, "errors": 0})
        if "error" in row:
            cell["errors"] += 1
            continue
        cell["n"] += 1
        # a law without the term (law="auto"): its value is 0
        cell["zeta"] += row.get("zeta_covered", row["zeta_true"] == 0.0)
        cell["xc"] += row.get("xc_covered", row["xc_true"] == 0.0)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--designs", default=",".join(DESIGNS))
    parser.add_argument("--truths", default=",".join(TRUTHS))
    parser.add_argument("--law", default=None)
    parser.add_argument("--out", required=True)
    parser.add_argument(
        "--collect",
        nargs="+",
        default=None,
        help="write --out from the rows these runs' outputs printed (runs split in parts)",
    )
    parser.add_argument(
        "--max-share",
        type=float,
        default=None,
        help="the nested law's largest share of the draws (default the package's)",
    )
    args = parser.parse_args()
    if args.max_share is not None:
        from bayestribo.inference import boundary

        boundary.MAX_SHARE = args.max_share
    from _machine import commit, machine

    import bayestribo

    if args.collect:
        # the first row of each (design, truth, seed): parts may overlap
        by_key: dict[tuple, dict] = {}
        for log in args.collect:
            for line in Path(log).read_text().splitlines():
                if line.startswith('{"design"'):
                    row = json.loads(line)
                    by_key.setdefault((row["design"], row["truth"], row["seed"]), row)
        rows = list(by_key.values())
        result = {"machine": machine(), "law": args.law or "default", "runs": rows}
        result["coverage"] = table(rows)
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
        print(json.dumps(result["coverage"], indent=1))
        return
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        # seed by seed, so that a run cut short has every cell
        for seed in range(args.first, args.first + args.runs):
            for design in args.designs.split(","):
                for truth in args.truths.split(","):
                    row = one_run(design, truth, seed, args.law, Path(tmp))
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    result = {
        "machine": machine(),
        "package": str(Path(bayestribo.__file__).parent.parent),
        "commit": commit(Path(bayestribo.__file__).parent.parent),
        "law": args.law or "default",
        "max_share": args.max_share,
        "coverage": table(rows),
        "runs": rows,
    }
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result["coverage"], indent=1))


if __name__ == "__main__":
    main()
