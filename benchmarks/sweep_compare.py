"""Run by run: a misspecification sweep's results beside a committed sweep of the same records.

A run of ``benchmarks/misspecification.py`` is the record of its case, noise level and
index (its noise drawn from ``[seed, crc32(case), noise, index]``, its fit seeded from
the same), so two sweeps hold the same runs whatever their ``--runs`` or
``--first-run``. For every case and noise level the runs held in both are compared:
refused / covered / flagged / missed / silently wrong (``misspecification.summarise``),
z's mean and sd for ζ and μ_k, the runs whose z moved (by more than 1e-9) and the
largest move; and, listed by index, every run newly refused, newly silently wrong,
newly missed or newly flagged, or that changed sides at an interval's edge.

Run::

    python benchmarks/sweep_compare.py misspecification_sweep_chain \
        misspecification_again_chain [--markdown]

(names of files in ``benchmarks/results/``, ``.json`` optional; several may be given to
each side as ``a,b``: their runs pooled, a later file's run over an earlier one's).
Prints the comparison; writes nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from misspecification import CASES, PARAMS, Z_CONFIDENT, summarise  # noqa: E402

RESULTS = HERE / "results"
#: Two runs' z closer than this are the same.
SAME = 1e-9

__all__ = ["compare", "load_runs", "outcome"]


def load_runs(names: str) -> dict[tuple[str, float, int], dict[str, Any]]:
    """The runs of the comma-separated results ``names``, keyed by (case, noise, index)."""
    runs: dict[tuple[str, float, int], dict[str, Any]] = {}
    for name in names.split(","):
        path = RESULTS / (name if name.endswith(".json") else f"{name}.json")
        for r in json.loads(path.read_text())["runs"]:
            runs[(r["case"], float(r["noise"]), int(r["index"]))] = r
    return runs


def outcome(r: dict[str, Any]) -> str:
    """One run's outcome: refused, covered, flagged, missed; ``silent`` where it is
    also silently wrong (|z| > 3.29 with no flag)."""
    if "refused" in r:
        return "refused"
    if any(abs(r["z"][p]) > Z_CONFIDENT for p in PARAMS) and not r["warnings"]:
        return "silent"
    if all(r["covered"].values()):
        return "covered"
    return "flagged" if r["warnings"] else "missed"


def _cell(row: dict[str, Any]) -> str:
    return " / ".join(
        str(row[k]) for k in ("refused", "covered", "flagged", "missed", "silently_wrong")
    )


def _z(row: dict[str, Any], key: str) -> str:
    values = [row[f"z_{p}"] for p in PARAMS]
    if any(v is None for v in values):
        return "-"
    fmt = "{:+.2f}" if key == "mean" else "{:.2f}"
    return " / ".join(fmt.format(v[key]) for v in values)


def compare(before: dict, after: dict) -> list[dict[str, Any]]:
    """Per case and noise level, the runs in both: the two sides' summaries, the runs
    moved, the largest move of a run's z, and every run whose outcome changed."""
    keys = sorted(set(before) & set(after), key=lambda k: (k[1], list(CASES).index(k[0]), k[2]))
    groups: dict[tuple[str, float], list[tuple[str, float, int]]] = {}
    for k in keys:
        groups.setdefault((k[0], k[1]), []).append(k)
    rows = []
    for (case, noise), ks in groups.items():
        one = summarise([before[k] for k in ks])[f"{case}@{noise:g}x"]
        two = summarise([after[k] for k in ks])[f"{case}@{noise:g}x"]
        moves = [
            max(abs(after[k]["z"][p] - before[k]["z"][p]) for p in PARAMS)
            for k in ks
            if "refused" not in before[k] and "refused" not in after[k]
        ]
        changed = []
        for k in ks:
            a, b = outcome(before[k]), outcome(after[k])
            if a != b:
                z = {
                    p: [before[k].get("z", {}).get(p), after[k].get("z", {}).get(p)] for p in PARAMS
                }
                changed.append({"index": k[2], "before": a, "after": b, "z": z})
        rows.append(
            {
                "case": case,
                "noise": noise,
                "runs": len(ks),
                "indices": [ks[0][2], ks[-1][2]],
                "before": one,
                "after": two,
                "runs_moved": sum(m > SAME for m in moves),
                "largest_dz": max(moves) if moves else None,
                "median_dz": float(np.median(moves)) if moves else None,
                "changed": changed,
            }
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", help="committed results (NAME or NAME1,NAME2)")
    parser.add_argument("after", help="the new results (NAME or NAME1,NAME2)")
    parser.add_argument("--markdown", action="store_true", help="print a README table")
    args = parser.parse_args(argv)
    rows = compare(load_runs(args.before), load_runs(args.after))
    if args.markdown:
        print(
            "| case | runs | r / c / f / m / sw | z mean ζ / μ<sub>k</sub> "
            "| sd(z) ζ / μ<sub>k</sub> | runs moved | largest Δz |"
        )
        print("|---|---|---|---|---|---|---|")
    for r in rows:
        b, a = r["before"], r["after"]
        name = r["case"] + ("" if r["noise"] == 10 else f" ({r['noise']:g}×)")
        span = f"{r['indices'][0]}-{r['indices'][1]}"
        dz = "-" if r["largest_dz"] is None else f"{r['largest_dz']:.3g}"
        cells = [
            name,
            span,
            f"{_cell(b)} → {_cell(a)}",
            f"{_z(b, 'mean')} → {_z(a, 'mean')}",
            f"{_z(b, 'sd')} → {_z(a, 'sd')}",
            str(r["runs_moved"]),
            dz,
        ]
        print("| " + " | ".join(cells) + " |" if args.markdown else "  ".join(cells))
        for c in r["changed"]:
            z = ", ".join(
                f"{p} {'-' if v[0] is None else f'{v[0]:+.2f}'} → "
                f"{'-' if v[1] is None else f'{v[1]:+.2f}'}"
                for p, v in c["z"].items()
            )
            print(f"    run {c['index']}: {c['before']} → {c['after']} ({z})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
