"""The adequacy verdict on the bundled runs: which checks fail on records of a known law.

Every run of ``data/`` (simulated, ``data/README.md``; its law in ``data/manifest.csv``)
is checked by :func:`bayestribo.adequacy.check_adequacy` as ``bayestribo check RUN``
does (least squares, 400 draws, seed 0). The runs whose law is the linear law
(``viscous+coulomb``, μ_s/μ_k free, or ``viscous`` in air) are records of the law the
verdict judges: each "not adequate" there is a false alarm. The ``oil`` series follows
``viscous+coulomb+quadratic``: a "not adequate" there is power.

Per run: each check's outcome, its p-value where it has one (the constancy test, the
split halves, the end of motion's two-sided tail of the draws), the peaks' coverage,
the verdict, and the CPU time.

Run: ``python benchmarks/adequacy_bundled.py --out adequacy_bundled_before`` (writes
``benchmarks/results/<out>.json``).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import write_results  # noqa: E402

from bayestribo.adequacy import check_adequacy  # noqa: E402

DATA = HERE.parent / "data"
CHECKS = ("constancy", "extinction", "peaks", "halves")


def one(row: dict[str, str]) -> dict[str, Any]:
    """Every check of one bundled run."""
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = check_adequacy(str(DATA / row["file"]))
    ext = report.extinction
    q = ext.quantile_of_measured("exact")
    out: dict[str, Any] = {
        "run": row["run_id"],
        "series": row["series"],
        "law": row["law"],
        "true_law": row["law"] in ("viscous+coulomb", "viscous"),
        "adequate": report.adequate,
        "passed": {c["key"]: c["passed"] for c in report.checks},
        "p_constancy": None if report.constancy is None else report.constancy.p_value,
        "p_halves": None if report.halves is None else report.halves.p_value,
        "extinction_quantile": q,
        "extinction_measured_s": ext.measured,
        "extinction_exact_median_s": float(np.median(ext.exact[np.isfinite(ext.exact)]))
        if np.any(np.isfinite(ext.exact))
        else None,
        "peak_coverage": report.predictive.coverage,
        "verdict": report.verdict,
        "cpu_s": time.process_time() - start,
    }
    p_ext = getattr(report.extinction, "p_value", None)
    if p_ext is not None:
        out["p_extinction"] = p_ext
    return out


def main() -> None:
    """Check every bundled run, print a line each and the counts, write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="adequacy_bundled", help="results file stem")
    parser.add_argument("--series", nargs="*", default=None, help="only these series")
    args = parser.parse_args()
    with open(DATA / "manifest.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    if args.series:
        rows = [r for r in rows if r["series"] in args.series]
    runs = []
    for row in rows:
        r = one(row)
        runs.append(r)
        failed = [k for k in CHECKS if r["passed"][k] is False]
        print(
            f"{r['run']:28s} {r['law']:26s} {'adequate' if r['adequate'] else 'NOT':8s} "
            f"failed {failed} p_const {r['p_constancy']} p_halves {r['p_halves']} "
            f"q_ext {r['extinction_quantile']} cov {r['peak_coverage']:.2f}",
            flush=True,
        )
    summary: dict[str, Any] = {}
    for label, group in (
        ("true_law", [r for r in runs if r["true_law"]]),
        ("other_law", [r for r in runs if not r["true_law"]]),
    ):
        summary[label] = {
            "runs": len(group),
            "not_adequate": sum(1 for r in group if not r["adequate"]),
            "failed": {k: sum(1 for r in group if r["passed"][k] is False) for k in CHECKS},
            "made": {k: sum(1 for r in group if r["passed"][k] is not None) for k in CHECKS},
        }
        print(label, summary[label])
    path = write_results(args.out, {"summary": summary, "runs": runs})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
