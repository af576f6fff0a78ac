"""The default law at several seeds on real recordings and bundled runs, beside a baseline.

Each fit, ``fit(run, seed=s)`` with the defaults, is made by two worker processes,
one per tree (``PYTHONPATH``), the two trees alternating from fit to fit (which goes
first alternates too), and timed in process CPU time. Recordings:

* the appstat recordings of ``../shared/external-data`` (``HarmOsc1-3``, read as
  ``benchmarks/real.py`` reads them), whole, and HarmOsc2's first half (``real.py``'s
  segment before its cut at the middle turning point of the whole's analysed decay,
  18.30 s), where the default law's μ_k lies on a ridge at 0;
* the bundled runs of ``data/runs`` (every CSV, or the first ``--bundled``).

Recorded per fit: converged, its reasons, the steps, the smallest effective sample
size, the independence move's weight in the kernel of the draws kept and the step it
was taken out at (where the tree has them), and each parameter's posterior mean and sd
(:meth:`~bayestribo.inference.FitResult.summary`). Summarised per recording and tree:
the seeds not converged, the largest and median steps, and each parameter's seed
spread, (max − min of the means)/(mean sd); between the trees: the largest
|a seed's mean − the other tree's mean over its seeds| / sd, per parameter, each
tree's seeds against the other's (goal: below 0.2 sd, the goal of issue 39 for
seeds).

Run (by hand)::

    git worktree add --detach /tmp/wt-base main
    timeout 5400 nice -n 10 python benchmarks/default_seeds.py --baseline /tmp/wt-base \\
        --seeds 6 --output default_seeds_NAME
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

ROOT = HERE.parent
BUNDLED = ROOT / "data" / "runs"
REAL = ("HarmOsc1", "HarmOsc2", "HarmOsc3")
#: The goal for the seeds' answers: within this many posterior sds.
SD_GOAL = 0.2


def _cut(run: Any) -> float:
    """``real.py``'s cut: the middle turning point of the whole's analysed decay [s]."""
    from bayestribo.inference import prepare

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        times = np.asarray(prepare(run).decay.turning_times, dtype=float)
    return float(times[(times.size - 1) // 2])


def _run_of(request: dict[str, Any]) -> Any:
    """The Run (or path) a request names."""
    if "path" in request:
        return request["path"]
    from real import load, segment

    run = load(request["recording"])[0]
    if request["segment"] == "whole":
        return run
    return segment(run, request["segment"], _cut(run))


def worker() -> int:
    """Fit one request per stdin line, one JSON line out per fit (see the module notes)."""
    import bayestribo
    from bayestribo.inference import fit

    print(json.dumps({"module": bayestribo.__file__}), flush=True)
    for line in sys.stdin:
        request = json.loads(line)
        run = _run_of(request)
        cpu = time.process_time()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(run, seed=int(request["seed"]))
        cpu = time.process_time() - cpu
        d = result.diagnostics
        out = {
            "seed": request["seed"],
            "cpu_seconds": cpu,
            "converged": bool(result.converged),
            "reasons": list(d.get("reasons", [])),
            "n_steps": int(d["n_steps"]),
            "ess_min": float(d["ess_min"]),
            "independence_weight": d.get("independence_weight"),
            "independence_dropped": d.get("independence_dropped"),
            "warnings": sorted(
                {w.category.__name__ for w in caught if w.category.__module__.startswith("bayes")}
            ),
            "mean": {k: float(s.mean) for k, s in result.summary().items()},
            "sd": {k: float(s.sd) for k, s in result.summary().items()},
        }
        print(json.dumps(out), flush=True)
    return 0


class Worker:
    """A fitting process of one tree, driven line by line."""

    def __init__(self, tree: Path) -> None:
        env = {**os.environ, "PYTHONPATH": str(tree)}
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env[var] = "1"
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), "--worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
            cwd=tempfile.gettempdir(),
        )
        assert self.proc.stdout is not None
        self.module = json.loads(self.proc.stdout.readline())["module"]
        if not self.module.startswith(str(tree)):
            raise RuntimeError(f"the worker for {tree} imported {self.module}")

    def fit(self, request: dict[str, Any]) -> dict[str, Any]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"worker exited with {self.proc.wait()}")
        return json.loads(line)

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


def _spread(fits: list[dict[str, Any]]) -> dict[str, float]:
    """Each parameter's (max − min of the means) / (mean sd) over the fits."""
    out = {}
    for name in fits[0]["mean"]:
        means = [f["mean"][name] for f in fits]
        sd = float(np.mean([f["sd"][name] for f in fits]))
        out[name] = float((max(means) - min(means)) / sd) if sd > 0 else 0.0
    return out


def _against(fits: list[dict[str, Any]], other: list[dict[str, Any]]) -> dict[str, float]:
    """Each parameter's largest |a fit's mean − the other fits' mean| / that fit's sd."""
    out = {}
    for name in fits[0]["mean"]:
        centre = float(np.mean([f["mean"][name] for f in other]))
        out[name] = float(
            max(abs(f["mean"][name] - centre) / f["sd"][name] for f in fits if f["sd"][name] > 0)
        )
    return out


def summarise(fits: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    """Per tree and between the trees (see the module notes)."""
    out: dict[str, Any] = {}
    for tree, rows in fits.items():
        steps = [r["n_steps"] for r in rows]
        out[tree] = {
            "seeds": len(rows),
            "not_converged": [r["seed"] for r in rows if not r["converged"]],
            "move_taken_out": [r["seed"] for r in rows if r.get("independence_dropped")],
            "steps_max": max(steps),
            "steps_median": float(np.median(steps)),
            "ess_min": min(r["ess_min"] for r in rows),
            "cpu_seconds_median": float(np.median([r["cpu_seconds"] for r in rows])),
            "seed_spread_sd": _spread(rows),
        }
    if set(fits) == {"current", "baseline"}:
        current, baseline = fits["current"], fits["baseline"]
        shared = [n for n in current[0]["mean"] if n in baseline[0]["mean"]]
        keep = [{**r, "mean": {n: r["mean"][n] for n in shared}} for r in current]
        base = [{**r, "mean": {n: r["mean"][n] for n in shared}} for r in baseline]
        against = {n: max(_against(keep, base)[n], _against(base, keep)[n]) for n in shared}
        out["between_trees_sd"] = against
        out["between_trees_max_sd"] = max(against.values())
        out["cpu_ratio_median"] = float(
            np.median(
                [
                    c["cpu_seconds"] / b["cpu_seconds"]
                    for c, b in zip(current, baseline, strict=True)
                ]
            )
        )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--baseline", type=Path, help="worktree of the commit to compare with")
    parser.add_argument("--seeds", type=int, default=6, help="seeds 1..n per recording")
    parser.add_argument("--bundled", type=int, default=None, help="first N bundled runs (all)")
    parser.add_argument("--real", nargs="*", default=[*REAL, "HarmOsc2 first half"])
    parser.add_argument("--output", default="default_seeds", help="results/<output>.json")
    args = parser.parse_args(argv)
    if args.worker:
        return worker()
    from _machine import commit, write_results

    trees = {"current": ROOT}
    if args.baseline is not None:
        trees["baseline"] = args.baseline.resolve()
    workers = {name: Worker(tree) for name, tree in trees.items()}
    requests: dict[str, dict[str, Any]] = {}
    for name in args.real:
        recording, _, which = name.partition(" ")
        requests[name] = {"recording": recording, "segment": which or "whole"}
    for path in sorted(BUNDLED.glob("*.csv"))[: args.bundled]:
        requests[path.stem] = {"path": str(path)}
    results: dict[str, Any] = {
        "settings": {"seeds": list(range(1, args.seeds + 1)), "recordings": list(requests)},
        "source": {
            name: {"commit": commit(tree), "module": w.module}
            for (name, tree), w in zip(trees.items(), workers.values(), strict=True)
        },
        "load_average_start": list(os.getloadavg()),
        "recordings": {},
    }
    k = 0
    for name, request in requests.items():
        fits: dict[str, list[dict[str, Any]]] = {tree: [] for tree in trees}
        for seed in results["settings"]["seeds"]:
            order = list(trees) if k % 2 == 0 else list(reversed(trees))
            k += 1
            for tree in order:
                fits[tree].append(workers[tree].fit({**request, "seed": seed}))
        summary = summarise(fits)
        results["recordings"][name] = {"summary": summary, "fits": fits}
        results["load_average_now"] = list(os.getloadavg())
        write_results(args.output, results)
        line = ", ".join(
            f"{t}: {len(summary[t]['not_converged'])} not converged, "
            f"steps ≤ {summary[t]['steps_max']}"
            for t in trees
        )
        between = summary.get("between_trees_max_sd")
        extra = f"; between trees ≤ {between:.2f} sd" if between is not None else ""
        print(f"{name}: {line}{extra}", flush=True)
    for w in workers.values():
        w.close()
    rows = results["recordings"].values()
    results["overall"] = {
        tree: {
            "not_converged": sum(len(r["summary"][tree]["not_converged"]) for r in rows),
            "fits": sum(r["summary"][tree]["seeds"] for r in rows),
        }
        for tree in trees
    }
    if "baseline" in trees:
        results["overall"]["between_trees_max_sd"] = max(
            r["summary"]["between_trees_max_sd"] for r in rows
        )
        results["overall"]["recordings_over_goal"] = [
            n
            for n, r in results["recordings"].items()
            if r["summary"]["between_trees_max_sd"] >= SD_GOAL
        ]
    path = write_results(args.output, results)
    print(json.dumps(results["overall"], indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
