"""The real corpus through the command line, as a new user would run it.

Every recording of ``data/real/manifest.json`` (recordings made by others, found as
``tests/_real_corpus.py`` says: ``$BAYESTRIBO_REAL_CORPUS/<source>/<file>`` first) is
given to ``bayestribo fit`` once per step of its ``steps``: the first what the source's
own description implies, each next one the package's printed advice followed. Each
command runs in its own process with ``--json`` (the same fit as the text output;
``--quiet`` leaves the printed warnings out, so it is not given). Recorded per step:
the command, the exit status, the warnings and the error printed, the wall and CPU
seconds (the child's user + system time), and from the JSON: the law, whether the law
holds, convergence, each parameter's mean and 95 % interval, and ΔE(A) (the law's band
and the turning points') at the reported amplitudes.

Run (in the background; a step with ``--law auto`` compares every candidate law)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus nice timeout 7200 python benchmarks/real_corpus.py

``--table`` prints the README's table from the results. Writes
``benchmarks/results/real_corpus.json`` (with ``--only NAME ...``, the recordings
named are run again and the file's other entries kept).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import commit, write_results

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("_real_corpus", ROOT / "tests" / "_real_corpus.py")
corpus = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(corpus)


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _summary(answer: dict[str, Any]) -> dict[str, Any]:
    """What the table needs of a fit's JSON: its law, verdicts, parameters and ΔE(A)."""
    keep = {}
    for key in ("law", "restoring", "adequate", "converged", "exit_status", "length_unit"):
        if key in answer:
            keep[key] = answer[key]
    diagnostics = answer.get("diagnostics") or {}
    keep["converged"] = diagnostics.get("converged")
    keep["ess_min"] = diagnostics.get("ess_min")
    for key in (
        "turning_point_dissipation",
        "parameters",
        "summary",
        "dissipation",
        "law_free",
        "law_comparison",
        "adequacy",
        "sampler",
        "frequency",
        "noise",
    ):
        if key in answer:
            keep[key] = answer[key]
    return keep


def run_step(path: Path, options: list[str], timeout: float) -> dict[str, Any]:
    """``bayestribo fit PATH OPTIONS --json`` in a child process."""
    exe = shutil.which("bayestribo")
    command = [exe] if exe else [sys.executable, "-m", "bayestribo.cli"]
    argv = [*command, "fit", str(path), *options, "--json"]
    wall, cpu = time.perf_counter(), _children_cpu()
    try:
        done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
        status, out, err = done.returncode, done.stdout, done.stderr
    except subprocess.TimeoutExpired as stopped:
        status, out, err = None, stopped.stdout or "", f"timed out after {timeout:g} s"
        out = out.decode() if isinstance(out, bytes) else out
    record: dict[str, Any] = {
        "command": " ".join(["bayestribo", "fit", path.name, *options]),
        "exit_status": status,
        "wall_s": round(time.perf_counter() - wall, 2),
        "cpu_s": round(_children_cpu() - cpu, 2),
        "warnings": [line for line in err.splitlines() if ": warning: " in line],
        "error": [line for line in err.splitlines() if ": error: " in line],
    }
    try:
        record["answer"] = _summary(json.loads(out)) if out.strip() else None
    except json.JSONDecodeError:
        record["answer"] = None
        record["stdout"] = out[-4000:]
    return record


def _answer(step: dict[str, Any]) -> str:
    """One cell: the refusal, or the law (or the law-free answer) and its parameters."""
    if step["exit_status"] == 2:
        error = step["error"][0] if step["error"] else "refused"
        return "refused: " + error.split(": error: ", 1)[-1].split(": ", 1)[-1][:160]
    answer = step.get("answer") or {}
    law = answer.get("law", "?")
    held = not any("no law compared holds" in w or "misfits" in w for w in step["warnings"])
    cells = []
    for name, p in (answer.get("parameters") or {}).items():
        if p.get("kind") == "posterior" and name != "y0":
            low, high = p["interval"]
            cells.append(f"{p['symbol']} {p['mean']:.3g} [{low:.3g}, {high:.3g}] {p['unit']}")
    if held:
        return f"`{law}` holds; " + "; ".join(cells)
    band = answer.get("turning_point_dissipation") or {}
    text = f"the turning points' ΔE(A) (`{law}` closest, misfits)"
    if band.get("amplitude"):
        unit = band.get("amplitude_unit", "")
        ends = []
        for i in (-1, 0):  # the largest swing first
            low, high = band["interval"][0][i], band["interval"][1][i]
            swing, mean = band["amplitude"][i], band["mean"][i]
            ends.append(f"A = {swing:.3g} {unit}: {mean:.3g} [{low:.3g}, {high:.3g}]")
        text += f" [{band.get('unit', '')}]"
        text += "; " + ", ".join(ends)
    return text


def markdown_table(results: dict[str, Any]) -> str:
    """The Markdown table of the README from a results file: one row per step."""
    rows = ["| recording | command | exit | answer | CPU s |", "|---|---|---|---|---|"]
    for name, entry in results["recordings"].items():
        for step in entry["steps"]:
            command = step["command"].replace("|", "\\|")
            rows.append(
                f"| {name} | `{command}` | {step['exit_status']} | {_answer(step)} | "
                f"{step['cpu_s']:.1f} |"
            )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", help="recording names to run (default: all)")
    parser.add_argument("--timeout", type=float, default=1800.0, help="per step [s]")
    parser.add_argument("--out", default="real_corpus", help="results name")
    parser.add_argument("--table", action="store_true", help="print the table, run nothing")
    args = parser.parse_args(argv)
    if args.table:
        path = Path(__file__).resolve().parent / "results" / f"{args.out}.json"
        print(markdown_table(json.loads(path.read_text())))
        return 0
    load_start = os.getloadavg()
    listed = corpus.manifest()
    table: dict[str, Any] = {}
    earlier = Path(__file__).resolve().parent / "results" / f"{args.out}.json"
    if args.only and earlier.is_file():
        # --only runs again the recordings named and keeps the others' results
        table = json.loads(earlier.read_text())["recordings"]
    for recording in listed["recordings"]:
        name = recording["name"]
        if args.only and name not in args.only:
            continue
        path = corpus.locate(recording)
        entry: dict[str, Any] = {
            "commit": commit(),
            "source": recording["source"],
            "file": recording["file"],
            "stated": recording.get("stated", {}),
            "steps": [],
        }
        if path is None:
            entry["missing"] = True
            table[name] = entry
            print(f"{name}: not found in {[str(r) for r in corpus.search_roots()]}")
            continue
        for step in recording["steps"]:
            record = run_step(path, step["options"], args.timeout)
            record["why"] = step["why"]
            entry["steps"].append(record)
            print(
                f"{name}: exit {record['exit_status']} in {record['cpu_s']} s CPU: "
                f"{record['command']}",
                flush=True,
            )
        table[name] = entry
        write_results(
            args.out,
            {
                "commit": commit(),
                "load_start": load_start,
                "load_end": os.getloadavg(),
                "recordings": table,
            },
        )
    path = write_results(
        args.out,
        {
            "commit": commit(),
            "load_start": load_start,
            "load_end": os.getloadavg(),
            "recordings": table,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
