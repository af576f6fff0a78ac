"""The first ``--law auto`` on a machine: laws compiled ahead by workers, or one by one.

On a fresh install every law ``auto`` compares is compiled on its first use (about 15 s
of CPU each). ``bayestribo/model/laws/ahead.py`` hands them to worker processes (as many
as the CPUs) while the command goes on. Each round runs ``bayestribo fit RUN --law auto
--json`` twice in fresh processes, each with a new empty law cache
(``BAYESTRIBO_CACHE_DIR``): with ``BAYESTRIBO_COMPILE_WORKERS=0`` (every law compiled by
the command as it needs it, as before) and with the default (workers), the one that goes
first alternating between rounds. The package's own compiled functions are cached beside
its modules and warm in both (a first run of ``auto`` with a throwaway law cache is made,
untimed, with ``--warm-up``).

Reported per run and mode: the wall time the user waits (``time.perf_counter`` around
the command), medians over the rounds, their ratio; the CPU of the command and its
compile workers (``getrusage`` of the children: the workers are the command's own
children, waited for); whether the two modes' answers are the same (the JSON output
with its timing fields removed, compared whole).

Run (by hand, some 4 minutes a round on two cores)::

    timeout 3600 python benchmarks/law_ahead.py --repeats 2 --warm-up

``--campaign``: each of ``--runs`` is a folder, and the command is ``bayestribo campaign
DIR --law auto --json --workers 2 --no-figures`` (a campaign's own pool: the laws
compiled first by the workers, or by each fit's worker as it needs them); the answers
compared are the campaign's JSON without its timing fields and output paths.

Writes ``benchmarks/results/law_ahead.json`` (``--output NAME``: ``NAME.json``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from _machine import commit, write_results  # noqa: E402

RUNS = [ROOT / "data" / "runs" / "air-r1.csv"]
#: Timing fields of the fit's JSON, left out when answers are compared.
TIMING = {"seconds", "cpu_seconds"}


def _untimed(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _untimed(v) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [_untimed(v) for v in value]
    return value


def measure(run: Path, workers: str | None, campaign: bool = False) -> dict[str, Any]:
    """One ``fit RUN --law auto --json`` (``campaign``: ``campaign RUN --law auto --json
    --workers 2`` on the folder ``RUN``) in a fresh process with an empty law cache;
    ``workers`` the value of ``BAYESTRIBO_COMPILE_WORKERS`` (None: unset)."""
    cache = tempfile.mkdtemp(prefix="bayestribo-law-ahead-")
    env = {**os.environ, "BAYESTRIBO_CACHE_DIR": cache}
    env.pop("BAYESTRIBO_COMPILE_WORKERS", None)
    if workers is not None:
        env["BAYESTRIBO_COMPILE_WORKERS"] = workers
    command = ["fit", str(run), "--law", "auto", "--json"]
    out_dir = ""
    if campaign:
        out_dir = tempfile.mkdtemp(prefix="bayestribo-law-ahead-out-")
        command = ["campaign", str(run), "--law", "auto", "--json", "--workers", "2"]
        command += ["--out", out_dir, "--no-figures"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "bayestribo", *command],
        env=env,
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    out: dict[str, Any] = {
        "workers": "default" if workers is None else workers,
        "exit_code": done.returncode,
        "wall_s": wall,
        "cpu_s_with_workers": (after.ru_utime - before.ru_utime)
        + (after.ru_stime - before.ru_stime),
    }
    text = done.stdout.replace(out_dir, "OUT") if campaign else done.stdout
    try:
        answer = json.loads(text)
    except json.JSONDecodeError:
        out["error"] = done.stderr[-2000:]
        return out
    if campaign:
        runs = answer.get("runs") if isinstance(answer, dict) else None
        out["laws"] = sorted({str(r.get("law")) for r in runs or [] if isinstance(r, dict)})
    else:
        out["law"] = answer.get("law")
    out["answer"] = _untimed(answer)
    return out


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="+", type=Path, default=RUNS)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--warm-up", action="store_true", help="an untimed run first")
    parser.add_argument(
        "--campaign",
        action="store_true",
        help="each of --runs a folder: bayestribo campaign DIR --law auto --workers 2",
    )
    parser.add_argument("--output", default="law_ahead")
    args = parser.parse_args(argv)
    if args.warm_up:
        measure(args.runs[0], None, args.campaign)
    load_start = os.getloadavg()
    rows: list[dict[str, Any]] = []
    for run in args.runs:
        for k in range(args.repeats):
            modes: list[str | None] = ["0", None] if k % 2 == 0 else [None, "0"]
            pair = {m: measure(run, m, args.campaign) for m in modes}
            one, other = pair["0"], pair[None]
            same = "answer" in one and one.get("answer") == other.get("answer")
            for m in modes:
                pair[m].pop("answer", None)
            rows.append(
                {
                    "run": run.name,
                    "round": k,
                    "same_answer": same,
                    "one_by_one": one,
                    "ahead": other,
                }
            )
            print(json.dumps(rows[-1]), flush=True)
    summary = {}
    for run in args.runs:
        mine = [r for r in rows if r["run"] == run.name]
        serial = statistics.median(r["one_by_one"]["wall_s"] for r in mine)
        ahead = statistics.median(r["ahead"]["wall_s"] for r in mine)
        summary[run.name] = {
            "one_by_one_wall_s": serial,
            "ahead_wall_s": ahead,
            "ratio_ahead_to_one_by_one": ahead / serial,
            "answers_same_every_round": all(r["same_answer"] for r in mine),
            "exit_codes": sorted(
                {r[m]["exit_code"] for r in mine for m in ("one_by_one", "ahead")}
            ),
        }
    path = write_results(
        args.output,
        {
            "benchmark": "law_ahead",
            "description": __doc__,
            "commit": commit(),
            "command": "python benchmarks/law_ahead.py " + " ".join(argv or sys.argv[1:]),
            "cpus_usable": len(os.sched_getaffinity(0)),
            "load_average_start": load_start,
            "load_average_end": os.getloadavg(),
            "summary": summary,
            "rounds": rows,
        },
    )
    print(json.dumps(summary, indent=1))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
