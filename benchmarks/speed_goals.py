"""Issue 42's speed goals, every ratio measured in one run on one machine.

Runs, one after the other in fresh processes on this tree (no other benchmark at the
same time), the benchmark behind each goal and writes each one's JSON as
``results/<OUTPUT>_<part>.json``, then one summary, ``results/<OUTPUT>.json``: per goal
the figure measured, the goal's bound and whether it is met, with the machine, the
commit and the load averages before and after each part.

=========  ==========================================  ============================
part       benchmark (its arguments here)              goals read from it
=========  ==========================================  ============================
fit        ``fit.py --repeats 20 --realistic 0``       warm default fit ≤ 0.1 s CPU
                                                       at ESS ≥ 1000, all converged
forward    ``forward.py``                              ``exact_pi`` ≤ 5× and
                                                       ``averaged_pi`` ≤ 3× ``np.exp``
                                                       + ``np.sin`` (64 × 256 points)
peers      ``peers.py --repeats 5 --ivp-steps 2``      numba RK4 + emcee at equal ESS
                                                       ≥ 150× the package's time
cli        ``cli_startup.py --repeats 5``              every ``--help`` ≤ 1.3× ``import
                                                       numpy``; ``fit RUN`` ≤ 4× the
                                                       warm fit
watch      ``campaign_watch.py``                       file closed → answer on the
                                                       page ≤ 2× the warm fit
auto       ``auto_ratio.py --seeds 1 2 3``             ``--law auto`` ≤ 10× the default
                                                       fit on every recording
laws       ``auto_ratio.py --every-law --seeds 1 2     every law ≤ 3× the default fit
           3``                                         (median over the seeds) and
                                                       converged, every recording
=========  ==========================================  ============================

Each ratio is measured side by side within its part (the two sides timed in the same
minutes, in process CPU time except where the part says otherwise); the parts run in
the order above. ``--parts`` runs some of them; ``--summarise`` rebuilds the summary
from part files already written (``--output``'s), running nothing.

Run (by hand, about 15 minutes on 2 cores, 847 s at 1fb7f8d; the real corpus where
``BAYESTRIBO_REAL_CORPUS`` names it)::

    python benchmarks/speed_goals.py --output speed_goals

Writes ``benchmarks/results/speed_goals.json`` and its seven part files.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import RESULTS, commit, write_results  # noqa: E402

#: Each part's script and arguments (``--output`` is added).
PARTS: dict[str, list[str]] = {
    "fit": ["fit.py", "--repeats", "20", "--realistic", "0", "--ode-evals", "2"],
    "forward": ["forward.py"],
    "peers": ["peers.py", "--repeats", "5", "--ivp-steps", "2"],
    "cli": ["cli_startup.py", "--repeats", "5"],
    "watch": ["campaign_watch.py"],
    "auto": ["auto_ratio.py", "--seeds", "1", "2", "3"],
    "laws": ["auto_ratio.py", "--every-law", "--seeds", "1", "2", "3"],
}


def _row(goal: str, measured: float | int | str, bound: str, met: bool, **more: Any) -> dict:
    return {"goal": goal, "measured": measured, "bound": bound, "met": bool(met), **more}


def _fit(d: dict) -> list[dict]:
    cpu = d["median_cpu_seconds"]
    return [
        _row(
            "warm default fit, bundled run (median CPU s over seeds)",
            round(cpu, 4),
            "<= 0.1 s at ESS >= 1000, all converged",
            cpu <= 0.1 and d["ess_min"] >= 1000 and d["all_converged"],
            smallest_ess=round(d["ess_min"]),
            wall_s=round(d["median_seconds"], 4),
        )
    ]


def _forward(d: dict) -> list[dict]:
    r = d["ratios"]
    return [
        _row(
            "exact_pi / (np.exp + np.sin), 64 sets x 256 times",
            round(r["exact_over_floor_64"], 2),
            "<= 5",
            r["exact_over_floor_64"] <= 5,
        ),
        _row(
            "averaged_pi / (np.exp + np.sin), 64 sets x 256 times",
            round(r["averaged_over_floor_64"], 2),
            "<= 3",
            r["averaged_over_floor_64"] <= 3,
        ),
    ]


def _peers(d: dict) -> list[dict]:
    ratio = d["ratios_to_package"]["user_rk4_time_at_equal_ess"]
    return [
        _row(
            "numba RK4 + plain emcee / the package, at equal ESS",
            round(ratio, 1),
            ">= 150",
            ratio >= 150,
        )
    ]


def _cli(d: dict) -> list[dict]:
    tree = d["trees"]["current"]
    worst = max(tree["every_help_over_import_numpy"].values())
    fit = tree["fit_over_warm_fit"]
    floor = tree["import_floor_over_warm_fit"]
    return [
        _row("slowest --help / import numpy", round(worst, 2), "<= 1.3", worst <= 1.3),
        _row(
            "bayestribo fit RUN (fresh process) / the warm fit",
            round(fit, 2),
            "<= 4",
            fit <= 4,
            import_floor_over_warm_fit=round(floor, 2),
        ),
    ]


def _watch(d: dict) -> list[dict]:
    s = d["summary"]["atomic"]
    return [
        _row(
            "file closed -> answer on the page / warm fit (acquire's files)",
            round(s["page_over_fit"], 2),
            "<= 2",
            s["page_over_fit"] <= 2,
        )
    ]


def _auto(d: dict) -> list[dict]:
    ratios = {name: s["ratio_median"] for name, s in d["summary"].items()}
    over = {name: round(r, 1) for name, r in ratios.items() if r > 10}
    return [
        _row(
            "--law auto / default fit, recordings within 10x (median over seeds)",
            f"{len(ratios) - len(over)} of {len(ratios)}",
            "all",
            not over,
            over=over,
            worst=round(max(ratios.values()), 1),
        )
    ]


def _laws(d: dict) -> list[dict]:
    n_laws = len(d["laws"])
    total = n_laws * len(d["summary"])
    over = sum(len(s["over_3x"]) for s in d["summary"].values())
    fits = sum(len(rows) for rows in d["fits"].values())
    unconverged = {n: s["not_converged"] for n, s in d["summary"].items() if s["not_converged"]}
    worst = max(d["summary"].items(), key=lambda kv: kv[1]["worst_ratio"])
    return [
        _row(
            "every law / default fit, (recording, law) within 3x (median over seeds)",
            f"{total - over} of {total}",
            "all",
            over == 0,
            worst=f"{worst[1]['worst_law']} on {worst[0]}: {worst[1]['worst_ratio']:.1f}x",
        ),
        _row(
            "every law converged at every seed, (recording, law)",
            f"{total - sum(map(len, unconverged.values()))} of {total}",
            "all",
            not unconverged,
            not_converged=unconverged,
            fits=fits,
        ),
    ]


READERS: dict[str, Callable[[dict], list[dict]]] = {
    "fit": _fit,
    "forward": _forward,
    "peers": _peers,
    "cli": _cli,
    "watch": _watch,
    "auto": _auto,
    "laws": _laws,
}


def run_part(part: str, output: str) -> dict[str, Any]:
    """Run one part's benchmark in a fresh process; its load, seconds and exit code."""
    script, *args = PARTS[part]
    command = [f"benchmarks/{script}", *args, "--output", f"{output}_{part}"]
    load = os.getloadavg()
    start = time.monotonic()
    done = subprocess.run(
        [sys.executable, *command],
        cwd=HERE.parent,
    )
    return {
        "command": " ".join(
            ["python", f"benchmarks/{script}", *args, "--output", f"{output}_{part}"]
        ),
        "exit_code": done.returncode,
        "wall_s": round(time.monotonic() - start, 1),
        "load_average_before": load,
        "load_average_after": os.getloadavg(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="+", choices=list(PARTS), default=list(PARTS))
    parser.add_argument("--output", default="speed_goals", help="results/<OUTPUT>.json")
    parser.add_argument(
        "--summarise", action="store_true", help="read the part files written; run nothing"
    )
    args = parser.parse_args(argv)
    runs: dict[str, Any] = {}
    if not args.summarise:
        for part in args.parts:
            print(f"== {part}", flush=True)
            runs[part] = run_part(part, args.output)
    else:
        previous = RESULTS / f"{args.output}.json"
        if previous.exists():
            runs = json.loads(previous.read_text()).get("runs", {})
    goals: list[dict] = []
    for part in args.parts:
        path = RESULTS / f"{args.output}_{part}.json"
        if not path.exists():
            goals.append(_row(f"{part}: no result", "-", "-", False, file=path.name))
            continue
        for row in READERS[part](json.loads(path.read_text())):
            goals.append({"part": part, "file": path.name, **row})
    out = write_results(
        args.output,
        {
            "about": __doc__.split("\n\n")[0],
            "commit": commit(),
            "runs": runs,
            "goals": goals,
            "met": sum(g["met"] for g in goals),
            "of": len(goals),
        },
    )
    width = max(len(g["goal"]) for g in goals)
    for g in goals:
        mark = "met" if g["met"] else "NOT met"
        print(f"{g['goal']:<{width}}  {g['measured']!s:>12}  ({g['bound']}: {mark})")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
