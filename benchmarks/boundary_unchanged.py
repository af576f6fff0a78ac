"""The default fit where friction is clearly there or fixed at 0: the bundled runs and
the real recordings, fitted side by side with another tree's package (main), the two
alternating, each fit in its own process: answers and CPU time.

For each recording, each tree: ``bayestribo.fit(run, seed=1)`` (the default law, or
``--law``) in a fresh process with that tree on ``PYTHONPATH``, after one warm-up fit in
the same process; recorded: the process CPU time of the fit (``time.process_time``), the mean,
sd and 95 % interval of every reported quantity, and the result's ``boundary`` record
(absent in a package without it). The answers' difference is given in units of the
other tree's sd.

Run: ``python benchmarks/boundary_unchanged.py --base /tmp/main-tree --out
benchmarks/results/boundary_unchanged.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

ROOT = Path(__file__).resolve().parent.parent
EXTERNAL = Path("/work/shared/external-data")

_WORKER = r"""
import json, sys, time, warnings
sys.path.insert(0, sys.argv[2])
from real import load
import bayestribo as bt
name = sys.argv[1]
if name.startswith("bundled:"):
    run = bt.read_run(name.split(":", 1)[1])
else:
    run, _ = load(name)
warnings.simplefilter("ignore")
law = {"law": sys.argv[3]} if sys.argv[3] else {}
bt.fit(run, seed=2, **law)  # warm
cpu = time.process_time()
r = bt.fit(run, seed=1, **law)
cpu = time.process_time() - cpu
out = {"cpu_s": cpu, "law": r.law, "boundary": getattr(r, "boundary", None)}
out["summary"] = {
    k: {"mean": s.mean, "sd": s.sd, "interval": list(s.interval)} for k, s in r.summary().items()
}
print(json.dumps(out))
"""


def fit_in(tree: Path, name: str, law: str = "") -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, "-c", _WORKER, name, str(Path(__file__).resolve().parent), law],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def names(bundled: list[str], real: bool = True) -> list[str]:
    from real import recordings

    bundled_names = [f"bundled:{ROOT / 'data/runs' / b}" for b in bundled if b]
    return [*bundled_names, *(recordings() if real else [])]


def compare(a: dict, b: dict) -> dict:
    """Largest |mean difference| / sd and largest interval end difference / sd."""
    worst = 0.0
    for k, s in b["summary"].items():
        o = a["summary"].get(k)
        if o is None or not s["sd"]:
            continue
        worst = max(worst, abs(s["mean"] - o["mean"]) / s["sd"])
        for i in (0, 1):
            worst = max(worst, abs(s["interval"][i] - o["interval"][i]) / s["sd"])
    return {"max_shift_over_sd": worst, "identical": a["summary"] == b["summary"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--base", required=True, help="the other tree (main)")
    parser.add_argument("--bundled", default="air-r1.csv,glycerol-N0.31-r1.csv")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--no-real", action="store_true", help="the bundled runs only")
    parser.add_argument("--law", default="", help="the law fitted (default: the default law)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    from _machine import commit, machine

    rows = []
    for name in names(args.bundled.split(","), real=not args.no_real):
        row: dict = {"recording": name, "main": [], "branch": []}
        for i in range(args.repeats):
            order = [("main", Path(args.base)), ("branch", ROOT)]
            for label, tree in order if i % 2 == 0 else order[::-1]:
                row[label].append(fit_in(tree, name, args.law))
        row["answers"] = compare(row["main"][0], row["branch"][0])
        cpu_main = sorted(r["cpu_s"] for r in row["main"])
        cpu_branch = sorted(r["cpu_s"] for r in row["branch"])
        row["cpu_ratio_branch_over_main"] = (
            cpu_branch[len(cpu_branch) // 2] / cpu_main[len(cpu_main) // 2]
        )
        print(
            json.dumps(
                {
                    "recording": name,
                    **row["answers"],
                    "cpu_ratio": row["cpu_ratio_branch_over_main"],
                    "boundary": (row["branch"][0]["boundary"] or {}).get("mixed"),
                }
            ),
            flush=True,
        )
        rows.append(row)
    result = {
        "machine": machine(),
        "load": os.getloadavg(),
        "law": args.law or "default",
        "main": commit(Path(args.base)),
        "branch": commit(ROOT),
        "recordings": rows,
    }
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
