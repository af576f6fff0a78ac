"""CPU time of the energy decay, this checkout against another (a worktree of main).

Three bundled runs (answered on their raw samples by both: the cost of the refusal
path's guard) and two simulated seismometer-like records of
``benchmarks/binned_records.py`` (viscous seed 11, answered raw by both; viscous
seed 0, which main refuses and this checkout answers binned: the raw attempt, then the
binned analysis). Each
checkout runs in its own subprocess, alternating, 5 times; per record the median of the
process CPU time of 3 calls after a warm one.

Run::

    python benchmarks/binned_cpu.py --base /path/to/main-worktree

Results: ``benchmarks/results/binned_cpu.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

CHILD = r"""
import glob, json, sys, time, warnings
warnings.simplefilter("ignore")
sys.path.insert(0, sys.argv[1] + "/benchmarks")
from binned_records import simulate
from bayestribo import read_run
from bayestribo.signal.decay import energy_decay
records = {}
for p in (sorted(glob.glob(sys.argv[1] + "/data/runs/*.csv"))[:3]):
    r = read_run(p)
    records["bundled " + p.rsplit("/", 1)[-1]] = (r.time, r.displacement, r.velocity)
from binned_records import cases
for case in (cases(12)[11], cases(12)[0]):  # main answers the first, refuses the second
    t, x = simulate(case["zeta"], case["x_c"], case["cycles"], case["noise"], case["seed"])
    records[f"simulated, viscous seed {case['seed']}"] = (t, x, None)
out = {}
for name, (t, x, v) in records.items():
    def once():
        try:
            energy_decay(t, x, v)
            return "answered"
        except Exception:
            return "refused"
    said = once()
    c = time.process_time()
    for _ in range(3):
        once()
    out[name] = [(time.process_time() - c) / 3, said]
print(json.dumps(out))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=True)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    trees = {"here": ROOT, "base": a.base.resolve()}
    runs: dict[str, list] = {k: [] for k in trees}
    before = list(os.getloadavg())
    for rep in range(a.repeats):
        for name in ("here", "base") if rep % 2 == 0 else ("base", "here"):
            env = {**os.environ, "PYTHONPATH": str(trees[name])}
            done = subprocess.run(
                [sys.executable, "-c", CHILD, str(ROOT)],
                env=env,
                cwd=tempfile.gettempdir(),  # not this checkout: its package would be imported
                capture_output=True,
                text=True,
                check=True,
            )
            runs[name].append(json.loads(done.stdout))
    rows = {}
    for record in runs["here"][0]:
        here = statistics.median(r[record][0] for r in runs["here"])
        base = statistics.median(r[record][0] for r in runs["base"])
        rows[record] = {
            "here_ms": round(1e3 * here, 2),
            "base_ms": round(1e3 * base, 2),
            "ratio": round(here / base, 3),
            "here": runs["here"][0][record][1],
            "base": runs["base"][0][record][1],
        }
        print(f"{record}: {rows[record]}")
    payload = {
        "commit": commit(),
        "base_commit": commit(a.base),
        "load_start": before,
        "load_end": list(os.getloadavg()),
        "repeats": a.repeats,
        "records": rows,
    }
    print(write_results("binned_cpu", payload))


if __name__ == "__main__":
    main()
