"""The default fit of the creep records with one channel kept: exit status and ΔE(A).

The 5 Hz Stribeck records of ``stribeck_verdict.py --rig creep`` (``_creep_sim.py``,
the mass creeps towards the equilibrium after its last half cycle; strengths 0.3, 1, 3,
``--seeds`` seeds each), with the displacement alone and with the velocity alone, each
fitted with the default law by ``stribeck_verdict._fit`` (the CLI's exit status; the
law's and the turning points' 95 % ΔE(A) bands against the true ΔE(A) at the smallest,
middle and largest analysed swing; *silently wrong*: exit 0 with the truth outside the
law's band at one of them, or the log-log slopes more than 0.5 apart; where the true
motion does not turn at one of the three swings, its ΔE there is not known and an exit
0 is counted as such). The package is
the one imported (``PYTHONPATH``), so the same script measures any tree; the results
name its commit.

Run::

    PYTHONPATH=<tree> nice -n 10 timeout 3600 python benchmarks/creep_one_channel_fits.py \\
        --workers 2 --output creep_one_channel_fits

Writes ``benchmarks/results/<output>.json``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import commit, niced_worker, write_results  # noqa: E402

CHANNELS = ("displacement", "velocity")


def _safe(truth_fn: Any) -> Any:
    """``truth_fn`` swing by swing, NaN where the true half cycle does not turn."""

    def safe(amplitude: Any) -> np.ndarray:
        out = []
        for a in np.atleast_1d(np.asarray(amplitude, dtype=float)):
            try:
                out.append(float(np.asarray(truth_fn(np.array([a])))[0]))
            except RuntimeError:
                out.append(math.nan)
        return np.array(out)

    return safe


def one(strength: float, seed: int) -> list[dict[str, Any]]:
    """Both one-channel fits of creep record ``seed`` at ``strength``."""
    import stribeck_verdict as sv

    from bayestribo import Run

    run, truth_fn, _, _ = sv._record("creep", strength, seed, False)
    out = []
    for channel in CHANNELS:
        kept = Run(
            time=run.time,
            displacement=run.displacement if channel == "displacement" else None,
            velocity=run.velocity if channel == "velocity" else None,
            metadata={},
        )
        rec = sv._fit(kept, None, seed, _safe(truth_fn))
        if rec.get("exit") == 0 and not all(map(math.isfinite, rec.get("truth_J", []))):
            # the true ΔE(A) not found at a swing (the true motion does not turn there)
            rec["outcome"] = "exit 0, truth not found"
        keep = ("exit", "law", "outcome", "warnings", "law_covered", "tp_covered", "refused")
        row = {"strength": strength, "seed": seed, "channel": channel}
        row.update({k: rec[k] for k in keep if k in rec})
        row["creep_warning"] = "CreepWarning" in rec.get("warnings", [])
        if rec.get("law_interval_J"):
            row["max_abs_z"] = max(abs(z) for z in sv.band_z(rec))
            row["confidently_wrong"] = sv.confidently_wrong(rec)
        out.append(row)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--output", default="creep_one_channel_fits")
    args = parser.parse_args(argv)
    import bayestribo

    tree = Path(bayestribo.__file__).resolve().parent.parent
    jobs = [(s, k) for k in range(1, args.seeds + 1) for s in (0.3, 1.0, 3.0)]
    start = time.time()
    rows: list[dict[str, Any]] = []
    with ProcessPoolExecutor(args.workers, initializer=niced_worker) as pool:
        for got in pool.map(one, *zip(*jobs, strict=True)):
            rows.extend(got)
            for r in got:
                print(r["strength"], r["seed"], r["channel"], r.get("exit"), r.get("outcome"))
    summary: dict[str, Any] = {}
    for channel in CHANNELS:
        sel = [r for r in rows if r["channel"] == channel]
        counts = {"records": len(sel)}
        outcomes = ("flagged", "covered", "silently wrong", "no band", "exit 0, truth not found")
        for outcome in outcomes:
            counts[outcome] = sum(r.get("outcome") == outcome for r in sel)
        counts["refused"] = sum(r.get("exit") == 2 for r in sel)
        counts["creep_warning"] = sum(r["creep_warning"] for r in sel)
        counts["confidently_wrong"] = sum(bool(r.get("confidently_wrong")) for r in sel)
        counts["silently_wrong_records"] = [
            f"{r['strength']:g}-{r['seed']}" for r in sel if r.get("outcome") == "silently wrong"
        ]
        summary[channel] = counts
    results = {
        "package_tree": str(tree),
        "package_commit": commit(tree),
        "benchmark_commit": commit(),
        "settings": vars(args),
        "wall_s": time.time() - start,
        "summary": summary,
        "rows": rows,
    }
    path = write_results(args.output, results)
    import json

    print(json.dumps(summary, indent=1))
    print(path)


if __name__ == "__main__":
    main()
