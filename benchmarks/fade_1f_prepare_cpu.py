"""CPU of ``prepare`` (the energy decay, its noise and the increments) with this tree
and another, alternating, on bundled runs and a decay into 1/f noise.

Each round imports each tree in its own subprocess (its ``PYTHONPATH``), prepares
every record once after a warm-up and reports process CPU seconds per record; the
trees alternate first from round to round. The ratio is this tree's median over the
other's.

Run::

    python benchmarks/fade_1f_prepare_cpu.py --base <worktree of main> [--rounds 5]

Results: ``benchmarks/results/fade_1f_prepare_cpu.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

RUNS = ("air-r1", "glycerol-N0.31-r1", "water3.00pc-N0.46-r1", "water9.00pc-N0.12-r1")


def measure(paths: list[str]) -> dict[str, float]:
    """Process CPU seconds of ``prepare`` on each path (after one warm-up each)."""
    import warnings

    from bayestribo.inference.preparation import prepare

    out = {}
    for p in paths:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prepare(p)
            start = time.process_time()
            prepare(p)
            out[Path(p).stem] = time.process_time() - start
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--name", default="fade_1f_prepare_cpu")
    ap.add_argument("--paths", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.paths:
        print(json.dumps(measure(json.loads(a.paths))))
        return
    from fade_1f import write_record

    with tempfile.TemporaryDirectory() as tmp:
        fade, _ = write_record(Path(tmp), "viscous", 0.005, 0)
        paths = [str(ROOT / "data" / "runs" / f"{r}.csv") for r in RUNS] + [str(fade)]
        trees = {"branch": ROOT, "main": a.base.resolve()}
        found: dict[str, list[dict[str, float]]] = {k: [] for k in trees}
        for i in range(a.rounds):
            order = list(trees) if i % 2 == 0 else list(trees)[::-1]
            for name in order:
                env = {**os.environ, "PYTHONPATH": str(trees[name]), "MPLBACKEND": "Agg"}
                cmd = [sys.executable, __file__, "--paths", json.dumps(paths)]
                res = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tmp)
                found[name].append(json.loads(res.stdout.strip().splitlines()[-1]))
    records = list(found["branch"][0])
    ratios = {
        r: statistics.median(x[r] for x in found["branch"])
        / statistics.median(x[r] for x in found["main"])
        for r in records
    }
    load = os.getloadavg()
    out = {
        "commit": commit(),
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "load_average": load,
        "rounds": found,
        "ratio_branch_over_main": ratios,
    }
    print(write_results(a.name, out))
    print(json.dumps(ratios, indent=1), "load", load)


if __name__ == "__main__":
    main()
