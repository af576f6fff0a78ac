"""``law="auto"`` with laws from the registry and screening, side by side with a baseline tree.

Each recording is fitted with ``fit(..., law="auto")`` by two worker processes
(``benchmarks/_auto_worker.py``), one importing this tree and one a baseline worktree
(``--baseline``, e.g. ``git worktree add --detach /tmp/wt-base 2730dd2``), in
alternation: for each repeat and each recording, the two trees one after the other, the
first of them alternating between repeats, each worker having fitted the bundled run
with the default law once before (numba's cached kernels loaded; with ``--warm-auto``
also with ``law="auto"``, so that the first recording timed finds every kernel auto
uses loaded too). The machine is
shared, so the times compared are each process's CPU time of the call
(``time.process_time``), with the wall time and the load averages beside them.

Recordings: the bundled runs ``data/runs/glycerol-N0.31-r1.csv`` and ``air-r1.csv``
and the five real recordings of ``../shared/external-data`` (``--external``), read as
``benchmarks/real.py`` reads them (HarmOsc1-3: t and position in an arbitrary unit;
the spring-and-disc records: position and velocity, the mass from the file name).

Recorded per recording: each tree's law and verdict, the laws as good as it, each
law's row (elpd difference, its sd, sampled or screened and why); the ratio of CPU
times (this tree over the baseline, medians over the repeats); whether the same law
was chosen, and the same choices (verdict, laws as good, adequacy) in every repeat;
with ``--default``, each tree's default fit of the recording timed in the same worker
after its auto fit, and auto's CPU time over it; and the largest difference of a
posterior mean between the trees in units of the baseline's posterior sd, over every
quantity both summarise and every repeat (the same seed in both trees; ``--seeds``: a
seed per repeat, ``per_seed`` each one's times). The screening's margin is checked
against the sampled comparison: for every law this tree screened out, its sampled
``elpd_diff`` in the baseline (where the baseline compared it) and whether the
baseline found it as good as its best; for every law this tree settled (not sampled: it
could no longer change the choice, :mod:`bayestribo.inference.settling`), the same, and
the laws whose standing (as good or not) differs from the baseline's (``standing_differs``).

Run (by hand)::

    PYTHONPATH=. nice -n 5 python benchmarks/auto_screening.py --baseline /tmp/wt-base \
        --repeats 2

Writes ``benchmarks/results/auto_screening.json`` (``--output NAME``: ``NAME.json``)
with the machine description, both commits and the load averages.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import commit, write_results  # noqa: E402

ROOT = HERE.parent
BUNDLED = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
#: Bundled runs fitted besides ``BUNDLED`` (a run in air: no contact).
OTHER_BUNDLED = {"air-r1": ROOT / "data" / "runs" / "air-r1.csv"}
EXTERNAL = ROOT.parent / "shared" / "external-data"
#: elpd difference below which two laws are not told apart (the comparison's own).
SMALL = 4.0


def recordings(external: Path) -> dict[str, dict[str, Any]]:
    """Each recording's request (path and reading keywords) by a short name."""
    out: dict[str, dict[str, Any]] = {"bundled": {"path": str(BUNDLED), "read": None}}
    for name, path in OTHER_BUNDLED.items():
        out[name] = {"path": str(path), "read": None}
    appstat = external / "appstat2020-harmonic-oscillator"
    for p in sorted(appstat.glob("HarmOsc*.txt")):
        out[p.stem] = {
            "path": str(p),
            "read": {
                "columns": ["time_s", "displacement_m"],
                "metadata": {"length_unit": "arbitrary"},
            },
        }
    for p in sorted((external / "smorzamento-spring-disc").glob("*.csv")):
        mass = float(p.stem.split("_")[-2])
        out["smorzamento-" + p.stem.rsplit("_", 1)[-1]] = {
            "path": str(p),
            "read": {
                "columns": ["time_s", "displacement_m", "velocity_m_per_s", "ignore"],
                "metadata": {"mass_kg": mass},
            },
        }
    return out


class Worker:
    """A worker process importing one tree's bayestribo."""

    def __init__(self, tree: Path, warm_auto: bool = False) -> None:
        env = dict(os.environ, PYTHONPATH=str(tree))
        self.proc = subprocess.Popen(
            [sys.executable, str(HERE / "_auto_worker.py")],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
            cwd=str(tree),
        )
        self.module = json.loads(self.proc.stdout.readline())["module"]
        self.fit({"warm_up": True, "path": str(BUNDLED), "auto": warm_auto})

    def fit(self, request: dict[str, Any]) -> dict[str, Any]:
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"the worker of {self.module} ended")
        return json.loads(line)

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def mean_shift(new: dict[str, Any], old: dict[str, Any]) -> dict[str, float]:
    """|mean_new - mean_old| / sd_old of every quantity both fits summarise."""
    out = {}
    for k, m in old["mean"].items():
        if k in new["mean"] and old["sd"].get(k):
            out[k] = abs(new["mean"][k] - m) / old["sd"][k]
    return out


def screen_check(new: dict[str, Any], old: dict[str, Any]) -> dict[str, Any]:
    """For every law the new tree screened out or settled: the baseline's sampled elpd
    difference and whether the baseline found it as good as its best (and, for a
    settled law, whether the new tree's estimate at the optimum said the same)."""
    out = {}
    for law, row in new["table"].items():
        if not (row.get("screened") or row.get("settled")):
            continue
        base = old["table"].get(law, {})
        out[law] = {
            "screen": row.get("screen"),
            "settle": row.get("settle"),
            "as_good": law in (new.get("as_good") or []),
            "baseline_elpd_diff": base.get("elpd_diff"),
            "baseline_dse": base.get("dse"),
            "baseline_as_good": law in (old.get("as_good") or []),
            "baseline_reduces_to": base.get("reduces_to"),
        }
    return out


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, required=True)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--seeds",
        type=int,
        nargs="*",
        help="one seed per repeat, in turn (overrides --seed; --repeats defaults to their number)",
    )
    parser.add_argument("--external", type=Path, default=EXTERNAL)
    parser.add_argument("--only", nargs="*", help="recordings to fit (default: all)")
    parser.add_argument("--trees", nargs="*", default=["baseline", "current"])
    parser.add_argument("--output", default="auto_screening")
    parser.add_argument(
        "--warm-auto",
        action="store_true",
        help="each worker also fits the bundled run with law='auto' before anything is timed",
    )
    parser.add_argument(
        "--warm-all",
        action="store_true",
        help="each worker also fits every recording with law='auto' (seed 99) before "
        "anything is timed: every compiled kernel the recordings use loaded",
    )
    parser.add_argument(
        "--default",
        action="store_true",
        help="also time the default fit of each recording after its auto fit (same worker)",
    )
    args = parser.parse_args(argv)
    if args.seeds and "--repeats" not in (argv if argv is not None else sys.argv):
        args.repeats = len(args.seeds)
    runs = recordings(args.external)
    if args.only:
        runs = {k: v for k, v in runs.items() if k in args.only}
    trees = {"baseline": args.baseline.resolve(), "current": ROOT}
    trees = {k: v for k, v in trees.items() if k in args.trees}
    load_start = os.getloadavg()
    workers = {name: Worker(tree, args.warm_auto) for name, tree in trees.items()}
    fits: dict[str, dict[str, list[dict[str, Any]]]] = {
        name: {tree: [] for tree in trees} for name in runs
    }

    def record(complete: bool) -> Path:
        return write_results(
            args.output,
            {
                "complete": complete,
                "settings": {
                    k: v if isinstance(v, (int, float, list, type(None))) else str(v)
                    for k, v in vars(args).items()
                },
                "commits": {name: commit(tree, short=True) for name, tree in trees.items()},
                "modules": {name: w.module for name, w in workers.items()},
                "load_average_start": list(load_start),
                "load_average_now": list(os.getloadavg()),
                "summary": summarise(fits),
                "fits": fits,
            },
        )

    order = list(trees)
    if args.warm_all:
        for name, request in runs.items():
            for tree in order:
                workers[tree].fit({**request, "name": name, "seed": 99, "default": False})
    for repeat in range(args.repeats):
        seed = args.seeds[repeat % len(args.seeds)] if args.seeds else args.seed
        for name, request in runs.items():
            for tree in order if repeat % 2 == 0 else order[::-1]:
                out = workers[tree].fit(
                    {**request, "name": name, "seed": seed, "default": args.default}
                )
                fits[name][tree].append(out)
                default = out.get("default_cpu_seconds")
                print(
                    f"{name:<14} {tree:<8} {out['cpu_seconds']:7.1f} s CPU "
                    f"{out['seconds']:7.1f} s wall  {out['law']}"
                    + (f"  (default fit {default:.2f} s CPU)" if default else ""),
                    flush=True,
                )
            record(False)
    for w in workers.values():
        w.close()
    path = record(True)
    for name, row in summarise(fits).items():
        print(name, json.dumps(row))
    print(f"wrote {path}")
    return 0


def summarise(fits: dict[str, dict[str, list[dict[str, Any]]]]) -> dict[str, Any]:
    """Per recording: CPU medians and their ratio, laws chosen, mean shifts, screening."""
    out: dict[str, Any] = {}
    for name, by_tree in fits.items():
        row: dict[str, Any] = {}
        for tree, runs in by_tree.items():
            if runs:
                row[f"{tree}_cpu_median"] = statistics.median(r["cpu_seconds"] for r in runs)
                row[f"{tree}_laws"] = sorted({r["law"] for r in runs})
                default = [r["default_cpu_seconds"] for r in runs if r.get("default_cpu_seconds")]
                if default:
                    row[f"{tree}_default_cpu_median"] = statistics.median(default)
                    row[f"{tree}_auto_over_default"] = (
                        row[f"{tree}_cpu_median"] / row[f"{tree}_default_cpu_median"]
                    )
        new, old = by_tree.get("current") or [], by_tree.get("baseline") or []
        if new and old:
            row["cpu_ratio"] = row["current_cpu_median"] / row["baseline_cpu_median"]
            row["same_law"] = row["current_laws"] == row["baseline_laws"]
            # every repeat's choices (verdict, laws as good, adequacy) in both trees
            choices = {
                tree: sorted(
                    {
                        json.dumps([r["verdict"], sorted(r["as_good"] or []), r["adequate"]])
                        for r in by_tree[tree]
                    }
                )
                for tree in ("current", "baseline")
            }
            row["same_choices"] = choices["current"] == choices["baseline"]
            row["choices"] = {tree: [json.loads(c) for c in v] for tree, v in choices.items()}
            # the same seed's fits in both trees (every repeat), the largest shift of all
            finite: dict[str, float] = {}
            for a, b in zip(new, old, strict=False):
                for k, v in mean_shift(a, b).items():
                    if math.isfinite(v) and v > finite.get(k, -1.0):
                        finite[k] = v
            if finite:
                worst = max(finite, key=finite.get)
                row["largest_mean_shift_sd"] = {worst: finite[worst]}
            row["per_seed"] = [
                {
                    "seed": a["seed"],
                    "current_cpu": a["cpu_seconds"],
                    "baseline_cpu": b["cpu_seconds"],
                    "current_default_cpu": a.get("default_cpu_seconds"),
                    "baseline_default_cpu": b.get("default_cpu_seconds"),
                    "current_law": a["law"],
                    "baseline_law": b["law"],
                }
                for a, b in zip(new, old, strict=False)
            ]
            row["screened"] = screen_check(new[0], old[0])
            # the laws screened out or settled that the baseline's sampled comparison
            # placed otherwise (as good where the new tree says not, or the reverse)
            row["standing_differs"] = sorted(
                law
                for law, check in row["screened"].items()
                if check["as_good"] != check["baseline_as_good"]
                and check.get("baseline_reduces_to") is None
            )
        out[name] = row
    return out


if __name__ == "__main__":
    sys.exit(main())
