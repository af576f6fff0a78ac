"""Every real recording, the command a user types, the answer and how close the best law came.

Each recording in ``../shared/external-data`` (read from there, never copied) is fitted
by the command line, as a user would run it on a file the package has never seen::

    bayestribo fit FILE [the options its README implies] --law auto --json

and the table the README shows is printed from what each command wrote: its exit
status, the law it answers with (exit 0) or the law-free answer (the turning points'
ΔE(A), exit 1, when no law holds), the law that came closest and how far it departs
from the turning points' ΔE(A) over the analysed amplitudes (largest departure in
percent, and the log-log slopes of ΔE(A): the law's and the turning points', with its
standard error), and the seconds it took. Its last column is issue 39's shape test on
the law the command answers with, or fitted last when it gives the law-free answer:
the log-log slopes of that law's ΔE(A) and of the turning points' (least squares of
the means over the analysed amplitudes, :func:`real.slope_check`) may differ by at most
0.5 where the command exits 0.

Run (in the background; ``auto`` compares every candidate law)::

    timeout 7200 python benchmarks/real_table.py

Writes ``benchmarks/results/real_table.json`` and prints the Markdown table.
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

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import commit, machine
from real import SLOPE_GOAL, slope_check

RESULTS = Path(__file__).resolve().parent / "results"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "external-data"
APPSTAT = "appstat2020-harmonic-oscillator"
DISC = "smorzamento-spring-disc"

#: name: (folder, file, options its README implies, what a physicist would expect)
RECORDINGS: dict[str, tuple[str, str, list[str], str]] = {
    "HarmOsc1": (
        APPSTAT,
        "HarmOsc1.txt",
        ["--columns", "t", "x", "--length-unit", "arbitrary"],
        "dry friction on a metal plate",
    ),
    "HarmOsc2": (
        APPSTAT,
        "HarmOsc2.txt",
        ["--columns", "t", "x", "--length-unit", "arbitrary"],
        "a cardboard disc adds air drag",
    ),
    "HarmOsc3": (
        APPSTAT,
        "HarmOsc3.txt",
        ["--columns", "t", "x", "--length-unit", "arbitrary"],
        "dry friction",
    ),
    "spring and disc 1": (
        DISC,
        "molla_durissima_discopieno_14.91945_0.2016_1.csv",
        ["--columns", "t", "x", "v", "ignore"],
        "air drag on a disc",
    ),
    "spring and disc 2": (
        DISC,
        "molla_durissima_discopieno_14.91945_0.2016_2.csv",
        ["--columns", "t", "x", "v", "ignore"],
        "air drag on a disc",
    ),
}


def one(name: str, shared: Path) -> dict[str, Any]:
    """Run the command on one recording; what it wrote and how it ended."""
    folder, file, options, expected = RECORDINGS[name]
    path = shared / folder / file
    shown = f"bayestribo fit ../shared/external-data/{folder}/{file} {' '.join(options)} --law auto"
    argv = [sys.executable, "-m", "bayestribo", "fit", str(path), *options, "--law", "auto"]
    start = time.perf_counter()
    done = subprocess.run([*argv, "--json"], capture_output=True, text=True, env=os.environ)
    row: dict[str, Any] = {
        "recording": name,
        "expected": expected,
        "command": shown,
        "exit": done.returncode,
        "seconds": time.perf_counter() - start,
        "stderr": done.stderr[-4000:],
    }
    if done.returncode not in (0, 1):
        return row
    out = json.loads(done.stdout)
    comparison = out.get("law_comparison") or {}
    best = comparison.get("best") or out["law"]
    departure = (comparison.get("departures") or {}).get(best, {})
    row.update(
        law=out["law"],
        adequate=comparison.get("adequate"),
        best=best,
        converged=out["diagnostics"].get("converged"),
        max_percent=departure.get("max_percent"),
        law_slope=departure.get("law_slope"),
        measured_slope=departure.get("measured_slope"),
        measured_slope_se=departure.get("measured_slope_se"),
        same_shape=departure.get("same_shape"),
    )
    # the goal's shape test on the law the command answers with (exit 0) or fitted
    # last (exit 1): its ΔE(A) and the turning points' log-log slopes over the
    # analysed amplitudes, which may differ by at most SLOPE_GOAL when the law holds
    slopes = slope_check(out.get("dissipation") or {}, out.get("turning_point_dissipation"))
    row["slopes"] = slopes
    row["answer_has_band"] = bool(
        out.get("dissipation") if done.returncode == 0 else out.get("turning_point_dissipation")
    )
    row["shape_goal_met"] = done.returncode != 0 or bool(slopes and slopes.get("within_goal"))
    return row


def table(rows: list[dict[str, Any]]) -> str:
    """The README's table."""
    lines = [
        "| recording (what a physicist expects) | command | exit | answer | the closest law, "
        "and how far its ΔE(A) is from the turning points' | sampler; the answering "
        f"law's log-log slope against the turning points' (goal ≤ {SLOPE_GOAL} at exit 0) |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["exit"] not in (0, 1):
            lines.append(f"| {r['recording']} | `{r['command']}` | {r['exit']} | refused | | |")
            continue
        answer = f"`{r['law']}`" if r["exit"] == 0 else "the turning points' ΔE(A) (law-free)"
        slopes = (
            f"ΔE ∝ A^{r['law_slope']:.2f} against A^{r['measured_slope']:.2f} "
            f"± {r['measured_slope_se']:.2f}"
            if r.get("law_slope") is not None
            else ""
        )
        close = f"`{r['best']}`: up to {r['max_percent']:.3g} % off; {slopes}"
        sl = r.get("slopes") or {}
        check = (
            f"`{r['law']}` Δslope {sl['difference']:.2f}"
            + ("" if r["shape_goal_met"] else " (**over the goal**)")
            if sl.get("difference") is not None
            else "no slope"
        )
        sampler = "converged" if r.get("converged") else "**not converged**"
        lines.append(
            f"| {r['recording']} ({r['expected']}) | `{r['command']}` | {r['exit']} | "
            f"{answer} | {close} | {sampler}; {check} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=SHARED, help="the external-data folder")
    parser.add_argument("--recordings", nargs="*", default=list(RECORDINGS))
    parser.add_argument("--output", default="real_table", help="results/NAME.json")
    args = parser.parse_args(argv)
    rows = []
    for name in args.recordings:
        rows.append(one(name, args.shared))
        r = rows[-1]
        print(f"{name}: exit {r['exit']}, {r.get('law')}, {r['seconds']:.0f} s", flush=True)
    RESULTS.mkdir(exist_ok=True)
    record = {"machine": machine(), "commit": commit(), "rows": rows, "table": table(rows)}
    (RESULTS / f"{args.output}.json").write_text(json.dumps(record, indent=1) + "\n")
    print(record["table"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
