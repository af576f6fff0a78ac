"""One answer per question: ``bayestribo report`` and ``bayestribo fit`` on the same run.

For every bundled run in ``data/runs/`` and every real recording in
``../shared/external-data`` (read from there, never copied), the two commands are run
as a user runs them, at the same seed and with the same reading options:

* ``bayestribo fit RUN --json --seed S [reading options]``: the posterior summary it
  prints;
* ``bayestribo report RUN --seed S [reading options] --param check_model=False
  --param summary_path=...``: the posterior summary the single-run report writes (the
  model checks, which do not change the fit, are left out to save time).

For each quantity of the fit's law (ζ, μ_k, μ_s, x_c, ... as the fit reports them),
the two posteriors agree *to the digit shown* when the report's text of the value and
its 95 % interval (:func:`bayestribo.summary.interval_text`) is the same for both; the
largest difference of the posterior means in posterior standard deviations is recorded
beside it, and whether the two summaries (mean and interval ends) are identical number
for number. The goal: agree to the digit everywhere.

The real recordings are read as the tests read them: the AppStat2020 text files with
``--columns t x --length-unit arbitrary``, the spring-and-disc CSV files with
``--columns t x v ignore``.

Run (by hand, from the repository root)::

    timeout 7200 nice -n 10 python benchmarks/report_vs_fit.py

writes ``benchmarks/results/report_vs_fit.json`` (rewritten after every run, so an
interrupted run keeps what it measured) and prints a table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's bayestribo, here and in the commands it runs
EXTERNAL = ROOT.parent / "shared" / "external-data"
RESULTS = ROOT / "benchmarks" / "results" / "report_vs_fit.json"

#: Reading options of the real recordings, by folder.
READING = {
    "appstat2020-harmonic-oscillator": ["--columns", "t", "x", "--length-unit", "arbitrary"],
    "smorzamento-spring-disc": ["--columns", "t", "x", "v", "ignore"],
}


def cases() -> list[tuple[str, Path, list[str]]]:
    """(name, file, reading options) of every bundled run and real recording."""
    out = [(p.stem, p, []) for p in sorted((ROOT / "data" / "runs").glob("*.csv"))]
    for folder, options in READING.items():
        for p in sorted((EXTERNAL / folder).glob("*")):
            if p.suffix.lower() in (".txt", ".csv"):
                out.append((p.stem, p, options))
    return out


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


def _command(args: list[str], timeout: float) -> tuple[int, str, str, float]:
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "bayestribo", *args],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=timeout,
        check=False,
    )
    return proc.returncode, proc.stdout, proc.stderr, time.perf_counter() - start


def compare(fit_params: dict[str, Any], report_params: dict[str, Any]) -> dict[str, Any]:
    """Per quantity of the fit: the shown texts of both and the mean's shift in sd."""
    from bayestribo.summary import interval_text

    out = {}
    for name, f in fit_params.items():
        if name.startswith("log10_") or name not in report_params:
            continue
        r = report_params[name]
        shown_fit = interval_text(f["mean"], *f["interval"])
        shown_report = interval_text(r["mean"], *r["interval"])
        sd = f.get("sd") or 0.0
        out[name] = {
            "fit": shown_fit,
            "report": shown_report,
            "same_digits": shown_fit == shown_report,
            "mean_shift_sd": abs(f["mean"] - r["mean"]) / sd if sd > 0 else 0.0,
            "identical": [f["mean"], *f["interval"]] == [r["mean"], *r["interval"]],
        }
    missing = sorted(set(fit_params) - set(report_params))
    if missing:
        out["_missing_in_report"] = missing
    return out


def one(name: str, path: Path, reading: list[str], seed: int, timeout: float) -> dict[str, Any]:
    """Fit and report one run; the comparison of their posteriors."""
    row: dict[str, Any] = {"run": name, "file": str(path.relative_to(path.parents[1]))}
    code, out, err, seconds = _command(
        ["fit", str(path), "--json", "--seed", str(seed), *reading], timeout
    )
    row["fit_exit"], row["fit_seconds"] = code, round(seconds, 1)
    try:
        fitted = json.loads(out)
    except json.JSONDecodeError:
        row["error"] = "fit: " + (err.strip().splitlines() or ["no output"])[-1]
        return row
    with tempfile.TemporaryDirectory() as tmp:
        summary = Path(tmp) / "summary.json"
        args = ["report", str(path), "--out", str(Path(tmp) / "r.html"), "--seed", str(seed)]
        args += [*reading, "--figure-format", "png", "--param", "check_model=False"]
        args += ["--param", f"summary_path={summary}"]
        code, out, err, seconds = _command(args, timeout)
        row["report_exit"], row["report_seconds"] = code, round(seconds, 1)
        if not summary.is_file():
            row["error"] = "report: " + (err.strip().splitlines() or ["no output"])[-1]
            return row
        reported = json.loads(summary.read_text())["fit"]
    row["law"] = fitted["law"]
    row["quantities"] = compare(fitted["parameters"], reported["parameters"])
    shown = [q for k, q in row["quantities"].items() if not k.startswith("_")]
    row["agree_to_the_digit"] = bool(shown) and all(q["same_digits"] for q in shown)
    row["largest_mean_shift_sd"] = max((q["mean_shift_sd"] for q in shown), default=None)
    row["identical"] = bool(shown) and all(q["identical"] for q in shown)
    row["same_exit_status"] = row["fit_exit"] == row["report_exit"]
    return row


def table(rows: list[dict[str, Any]]) -> str:
    """The results as a fixed-width table."""
    lines = [f"{'run':<48} {'law':<18} {'digits':<8} {'shift/sd':>9} {'exit f/r':>9}"]
    for r in rows:
        if "error" in r:
            lines.append(f"{r['run']:<48} error: {r['error'][:60]}")
            continue
        shift = r["largest_mean_shift_sd"]
        lines.append(
            f"{r['run'][:48]:<48} {r['law'][:18]:<18} "
            f"{'same' if r['agree_to_the_digit'] else 'DIFFER':<8} "
            f"{'-' if shift is None else f'{shift:.2g}':>9} "
            f"{r['fit_exit']}/{r['report_exit']:>7}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="seed of both commands")
    parser.add_argument("--only", nargs="*", help="runs to do (names), default all")
    parser.add_argument("--timeout", type=float, default=1800, help="per command [s]")
    parser.add_argument(
        "--update",
        action="store_true",
        help="redo the --only runs and keep the other rows of the existing results",
    )
    args = parser.parse_args(argv)
    todo = [c for c in cases() if not args.only or c[0] in args.only]
    kept: list[dict[str, Any]] = []
    if args.update and RESULTS.is_file():
        redo = {c[0] for c in todo}
        kept = [r for r in json.loads(RESULTS.read_text())["rows"] if r["run"] not in redo]
        todo_names = [c[0] for c in cases()]
        order = {name: i for i, name in enumerate(todo_names)}
    rows: list[dict[str, Any]] = []
    start = time.perf_counter()
    for name, path, reading in todo:
        try:
            rows.append(one(name, path, reading, args.seed, args.timeout))
        except subprocess.TimeoutExpired:
            rows.append({"run": name, "error": f"a command took over {args.timeout:.0f} s"})
        print(table(rows[-1:]).splitlines()[-1], flush=True)
        if args.update:  # the kept rows and the redone ones, in the order of the cases
            rows = sorted([*kept, *rows], key=lambda r: order.get(r["run"], len(order)))
            kept = []
        done = [r for r in rows if "error" not in r]
        record = {
            "benchmark": "benchmarks/report_vs_fit.py",
            "seed": args.seed,
            "runs": len(rows),
            "of": len(cases()) if args.update else len(todo),
            "agree_to_the_digit": sum(r["agree_to_the_digit"] for r in done),
            "same_exit_status": sum(r["same_exit_status"] for r in done),
            "identical_posterior_summaries": sum(r["identical"] for r in done),
            "errors": len(rows) - len(done),
            "largest_mean_shift_sd": max(
                (r["largest_mean_shift_sd"] or 0.0 for r in done), default=None
            ),
            "seconds": round(time.perf_counter() - start),
            "command_seconds": round(
                sum(r.get("fit_seconds", 0) + r.get("report_seconds", 0) for r in rows)
            ),
            "rows": rows,
        }
        RESULTS.write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n")
    print(table(rows))
    print(
        f"agree to the digit: {record['agree_to_the_digit']} of {len(done)} "
        f"({record['errors']} errors); same exit status: {record['same_exit_status']}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
