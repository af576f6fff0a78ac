"""Where a warm default fit's time goes, stage by stage, side by side with another commit.

The bundled run ``data/runs/glycerol-N0.31-r1.csv`` is fitted with the defaults
(:func:`bayestribo.inference.fit`) for seeds 1..``--seeds``, ``--rounds`` times, in
one warm worker process per tree (``PYTHONPATH`` on the tree; a warm-up fit of seed 0
first, not timed): each seed on both trees one after the other, the tree that goes
first alternating, so that the load of a shared machine and the drift of its speed
fall on both alike.
Each stage is timed in process CPU time by a wrapper on the function that does it:

* ``read``: the file read and validated (``io.files.as_run``);
* ``decay``: the energy decay analysed (``signal.decay.energy_decay``);
* ``start``: the optimum, the reweighted posterior and the walkers' start
  (``inference.start.find_start``);
* ``sampler``: the ensembles run to the stopping rule
  (``inference.sampling.run_ensembles``);
* ``checks``: the fit's checks (``inference.checks.check``);
* ``summary``: the draws summarised, the pointwise log-likelihood and the predictive
  Π included where the tree computes them there (``inference.summarising.summary``);

and the whole fit. Reported per tree: each stage's median over every fit, the fit's
median, and the ratio of the two trees' CPU time per seed (the median over rounds of
each tree's time; the same seed makes the same chains where the trees' samplers
agree, so a pair differs where the code does), with its median over seeds.

Run (by hand, a minute or two)::

    git worktree add --detach /tmp/base <commit>
    python benchmarks/fit_stages.py --baseline /tmp/base --seeds 20 --rounds 3

Writes ``benchmarks/results/fit_stages.json`` (``--output NAME``: ``NAME.json``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from _machine import commit, write_results  # noqa: E402

RUN = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
STAGES = {
    "read": ("bayestribo.io.files", "as_run"),
    "decay": ("bayestribo.signal.decay", "energy_decay"),
    "start": ("bayestribo.inference.start", "find_start"),
    "sampler": ("bayestribo.inference.sampling", "run_ensembles"),
    "checks": ("bayestribo.inference.checks", "check"),
    "summary": ("bayestribo.inference.summarising", "summary"),
}

WORKER = r"""
import importlib, json, sys, time
STAGES = json.loads(sys.argv[1]); run = sys.argv[2]
from bayestribo.inference import fit
spent = {}
def wrap(module, name, label):
    original = getattr(module, name)
    def timed(*args, **kwargs):
        cpu = time.process_time()
        try:
            return original(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - cpu
    return original, timed
for label, (module_name, name) in STAGES.items():
    module = importlib.import_module(module_name)
    original, timed = wrap(module, name, label)
    # the name where it is defined and wherever it was imported by name
    for other in list(sys.modules.values()):
        if getattr(other, "__name__", "").startswith("bayestribo") and (
            getattr(other, name, None) is original
        ):
            setattr(other, name, timed)
fit(run, seed=0)
print("ready", flush=True)
for line in sys.stdin:  # one seed a line; one line of JSON back per fit
    seed = int(line)
    spent.clear()
    cpu = time.process_time()
    result = fit(run, seed=seed)
    total = time.process_time() - cpu
    d = result.diagnostics
    print(json.dumps({"seed": seed, "total": total, **spent, "steps": d["n_steps"],
                      "ess_min": d["ess_min"]}), flush=True)
"""


class _Worker:
    """A warm process fitting one seed at a time on the tree ``tree``."""

    def __init__(self, tree: Path) -> None:
        env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONDONTWRITEBYTECODE": "1"}
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env.setdefault(var, "1")
        self.process = subprocess.Popen(
            [sys.executable, "-c", WORKER, json.dumps(STAGES), str(RUN)],
            env=env,
            cwd=str(tree),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.process.stdout is not None and self.process.stdin is not None
        if self.process.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the worker on {tree} did not start")

    def fit(self, seed: int) -> dict[str, Any]:
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(f"{seed}\n")
        self.process.stdin.flush()
        return json.loads(self.process.stdout.readline())

    def close(self) -> None:
        assert self.process.stdin is not None
        self.process.stdin.close()
        self.process.wait(timeout=60)


def _medians(rows: list[dict[str, Any]]) -> dict[str, float]:
    keys = ["total", *STAGES]
    return {k: statistics.median(r.get(k, 0.0) for r in rows) for k in keys}


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, required=True, help="worktree of the commit")
    parser.add_argument("--seeds", type=int, default=20, help="fits per round (seeds 1..n)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds per tree, alternating")
    parser.add_argument("--output", default="fit_stages")
    args = parser.parse_args(argv)
    seeds = list(range(1, args.seeds + 1))
    trees = {"current": ROOT, "baseline": args.baseline.resolve()}
    rows: dict[str, list[dict[str, Any]]] = {name: [] for name in trees}
    load_start = os.getloadavg()
    workers = {name: _Worker(tree) for name, tree in trees.items()}
    try:
        for r in range(args.rounds):
            for i, seed in enumerate(seeds):
                # each seed on both trees one after the other, the first tree
                # alternating: a drift of the machine's speed falls on both alike
                order = list(trees) if (r + i) % 2 == 0 else list(trees)[::-1]
                for name in order:
                    rows[name].append(workers[name].fit(seed))
            for name in trees:
                print(f"round {r + 1} {name}: {_medians(rows[name])}", flush=True)
    finally:
        for worker in workers.values():
            worker.close()
    medians = {name: _medians(rs) for name, rs in rows.items()}
    paired = []
    for seed in seeds:
        b = statistics.median(x["total"] for x in rows["baseline"] if x["seed"] == seed)
        c = statistics.median(x["total"] for x in rows["current"] if x["seed"] == seed)
        paired.append(b / c)
    summary = {
        "median_ms": {n: {k: 1000.0 * v for k, v in m.items()} for n, m in medians.items()},
        "paired_ratio_baseline_over_current": {
            "median": statistics.median(paired),
            "per_seed": paired,
        },
        "steps_median": {n: statistics.median(x["steps"] for x in rs) for n, rs in rows.items()},
    }
    for name, m in summary["median_ms"].items():
        print(name, {k: round(v, 1) for k, v in m.items()})
    print("paired ratio (baseline / current), median:", round(statistics.median(paired), 3))
    write_results(
        args.output,
        {
            "commits": {n: commit(t) for n, t in trees.items()},
            "run": str(RUN.relative_to(ROOT)),
            "seeds": seeds,
            "rounds": args.rounds,
            "load_average_start": load_start,
            "load_average_end": os.getloadavg(),
            **summary,
            "fits": rows,
        },
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
