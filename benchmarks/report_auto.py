"""``bayestribo report FOLDER --law auto`` on every folder of real recordings.

Each folder of ``../shared/external-data`` is reported with ``--law auto`` (the
real-data notebook: every recording fitted as ``bayestribo fit --law auto`` fits it),
and the result records, per folder: the exit status, the time, the law each recording
came out with and whether it holds, every section of the report present (by its
heading), the ΔE(A) figure written, and no error in the page. The report must exit as
``fit --law auto`` would (1 where a recording has no law that holds or a fit did not
converge, else 0), never 2.

Run by hand (minutes per recording: ``auto`` fits every candidate law)::

    python benchmarks/report_auto.py [FOLDER ...]

Writes ``benchmarks/results/report_auto.json``.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import ROOT, provenance, write_results

EXTERNAL = ROOT.parent / "shared" / "external-data"

#: How each folder's files are read (the README of each says so).
READING = {
    "appstat2020-harmonic-oscillator": ["--columns", "t", "x", "--length-unit", "arbitrary"],
    "smorzamento-spring-disc": ["--columns", "t", "x", "v", "ignore"],
}

#: The real-data report's sections, by their headings.
SECTIONS = (
    "The answer",
    "1. The recordings",
    "2. Energy decay and classical estimates",
    "3. Bayesian fits",
    "4. Friction or drag?",
    "5. Is a constant",
)


def report(folder: Path, out: Path) -> dict:
    """Run the report on ``folder`` in a fresh interpreter; what it did."""
    summary = out / "summary.json"
    argv = [sys.executable, "-m", "bayestribo", "report", str(folder), "--law", "auto"]
    argv += [*READING.get(folder.name, []), "--out", str(out / "report.html")]
    argv += ["--figure-format", "png", "--param", f"summary_path={summary}"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - start
    page = (
        (out / "report.html").read_text(encoding="utf-8") if (out / "report.html").is_file() else ""
    )
    record = json.loads(summary.read_text()) if summary.is_file() else {}
    fits = {
        name: {
            "law": fit.get("law"),
            "converged": (fit.get("diagnostics") or {}).get("converged"),
            "adequate": (fit.get("law_comparison") or {}).get("adequate"),
            "parameters": sorted(fit.get("parameters") or {}),
        }
        for name, fit in (record.get("fits") or {}).items()
    }
    figures = out / "report-figures"
    return {
        "exit": done.returncode,
        "seconds": seconds,
        "sections": {s: bool(re.search(rf"<h2[^>]*>{re.escape(s)}", page)) for s in SECTIONS},
        "dissipation_figure": (figures / "dissipation.png").is_file(),
        "traceback": "Traceback" in page or "Traceback" in done.stderr,
        "fits": fits,
        "stderr_tail": done.stderr.strip().splitlines()[-6:],
    }


def main(folders: list[str]) -> None:
    load = os.getloadavg()
    paths = [Path(f) for f in folders] or sorted(p for p in EXTERNAL.iterdir() if p.is_dir())
    results = {}
    for folder in paths:
        with tempfile.TemporaryDirectory() as tmp:
            results[folder.name] = report(folder.resolve(), Path(tmp))
        print(folder.name, json.dumps(results[folder.name], indent=1), flush=True)
    path = write_results(
        "report_auto",
        {
            "source": provenance(
                "bayestribo", {"law": "auto", "folders": [p.name for p in paths]}, load
            ),
            "folders": results,
        },
    )
    print(f"written to {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
