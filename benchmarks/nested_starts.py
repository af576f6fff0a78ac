"""A law of several terms taken to its optimum from its nested laws' optima, against the
first guesses' multi-start, on every recording of the speed goals.

For each recording of ``speed_goals_laws.json``'s commands (the two bundled runs and
the 17 real recordings the speed goals take, read by the command a user gives, a
pendulum on its restoring force), prepared as ``bayestribo.fit`` prepares it, the
twelve laws of ``law="auto"`` are taken to their optima smallest first, as the
comparison takes them. Each law of two or three terms is optimised both ways on the
same posterior (:func:`bayestribo.inference.comparison._posterior`):

* ``multi``: the first guesses' multi-start, started also at the largest nested law's
  optimum (:func:`bayestribo.inference.start.find_optimum` with
  :func:`bayestribo.inference.reduction.nested_start`: the comparison before);
* ``nested``: from each law of one term fewer's optimum, the best kept
  (:func:`bayestribo.inference.start.maximum_from_starts` with
  :func:`bayestribo.inference.reduction.nested_starts`: the comparison now);

and each one's log posterior density at its optimum and CPU time are written (the
nested optima carried on to the larger laws). Reported: per pair the difference of the
log densities (nested − multi) and the ratio of the CPU times; over all, how many are
within 0.01, better or worse, and the total times.

Run (by hand, about 5 minutes; the real corpus where ``BAYESTRIBO_REAL_CORPUS`` names
it)::

    python benchmarks/nested_starts.py

Writes ``benchmarks/results/nested_starts.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import provenance, write_results  # noqa: E402

#: Log densities within this are the same optimum (the least squares' tolerance).
SAME = 0.01


def one_recording(argv: list[str]) -> list[dict[str, Any]]:
    """Both optimisers on every law of several terms of one recording (in this process)."""
    import warnings

    import numpy as np

    from bayestribo.cli._common import read_run_from_args
    from bayestribo.cli.main import build_parser
    from bayestribo.inference import comparison
    from bayestribo.inference.choice import complexity
    from bayestribo.inference.pipeline import prepare
    from bayestribo.inference.reduction import law_of, nested_start, nested_starts
    from bayestribo.inference.start import find_optimum, maximum_from_starts

    warnings.simplefilter("ignore")
    args = build_parser().parse_args(["fit", *argv])
    run = read_run_from_args(args)
    if getattr(args, "restoring", None):
        run = run.with_metadata(restoring=args.restoring)
    prepared = prepare(run)
    optima: dict[str, dict[str, float]] = {}
    rows = []
    for law in sorted(comparison.auto_laws(), key=complexity):  # as the comparison does
        posterior = comparison._posterior(law, prepared.data, "exact", False)
        cpu = time.process_time()
        multi = find_optimum(
            posterior, prepared.decay, also_start_at=nested_start(law, prepared, optima)
        )
        multi_cpu = time.process_time() - cpu
        starts = nested_starts(law, prepared, optima)
        if starts is None:
            optima[law] = dict(zip(posterior.names, multi[0], strict=True))
            continue
        cpu = time.process_time()
        nested = maximum_from_starts(posterior, starts, prepared.decay)
        nested_cpu = time.process_time() - cpu
        optima[law] = dict(zip(posterior.names, nested[0], strict=True))
        lp_multi = float(posterior(np.asarray(multi[0])[None])[0])
        lp_nested = float(posterior(np.asarray(nested[0])[None])[0])
        rows.append(
            {
                "law": law_of(law).name,
                "terms": len(law_of(law).terms),
                "log_density_multi": lp_multi,
                "log_density_nested": lp_nested,
                "difference": lp_nested - lp_multi,
                "cpu_seconds_multi": multi_cpu,
                "cpu_seconds_nested": nested_cpu,
            }
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="nested_starts", help="results/<OUTPUT>.json")
    parser.add_argument("--one", help=argparse.SUPPRESS)  # a recording's command, as JSON
    args = parser.parse_args(argv)
    if args.one is not None:
        print(json.dumps(one_recording(json.loads(args.one))))
        return 0
    load = os.getloadavg()
    commands = json.loads((HERE / "results" / "speed_goals_laws.json").read_text())["commands"]
    corpus = os.environ.get("BAYESTRIBO_REAL_CORPUS", "/tmp/real-corpus-cache")
    recordings: dict[str, Any] = {}
    for name, command in commands.items():
        command = [c.replace("/tmp/real-corpus-cache", corpus) for c in command]
        command = [c.replace("/work/main/", str(HERE.parent) + "/") for c in command]
        if not Path(command[0]).exists():
            recordings[name] = {"skipped": f"{command[0]} not found"}
            print(f"{name}: skipped", flush=True)
            continue
        # each recording in a fresh process (a law's compiled code loaded once there)
        done = subprocess.run(
            [sys.executable, __file__, "--one", json.dumps(command)],
            capture_output=True,
            text=True,
            check=True,
        )
        rows = json.loads(done.stdout.splitlines()[-1])
        recordings[name] = {"command": command, "laws": rows}
        worst = min(r["difference"] for r in rows)
        print(f"{name}: {len(rows)} laws, least difference {worst:+.4f}", flush=True)
    rows = [r for rec in recordings.values() for r in rec.get("laws", [])]
    same = sum(abs(r["difference"]) <= SAME for r in rows)
    better = [r["difference"] for r in rows if r["difference"] > SAME]
    worse = [r["difference"] for r in rows if r["difference"] < -SAME]
    multi = sum(r["cpu_seconds_multi"] for r in rows)
    nested = sum(r["cpu_seconds_nested"] for r in rows)
    ratios = sorted(r["cpu_seconds_nested"] / r["cpu_seconds_multi"] for r in rows)
    summary = {
        "pairs": len(rows),
        "same_within": SAME,
        "same": same,
        "better": len(better),
        "better_by": [min(better, default=0.0), max(better, default=0.0)],
        "worse": len(worse),
        "worse_by": [min(worse, default=0.0), max(worse, default=0.0)],
        "least_difference": min((r["difference"] for r in rows), default=0.0),
        "cpu_seconds_multi": multi,
        "cpu_seconds_nested": nested,
        "cpu_ratio_total": nested / multi if multi else None,
        "cpu_ratio_median": ratios[len(ratios) // 2] if ratios else None,
        "cpu_ratio_range": [ratios[0], ratios[-1]] if ratios else None,
    }
    print(json.dumps(summary, indent=1))
    from bayestribo.inference.choice import complexity
    from bayestribo.inference.comparison import auto_laws

    settings = {"laws": sorted(auto_laws(), key=complexity), "same_within": SAME}
    write_results(
        args.output,
        {
            **provenance("bayestribo.inference.start", settings, load),
            "summary": summary,
            "recordings": recordings,
        },
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
