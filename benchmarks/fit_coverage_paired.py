"""Two versions' 95 % intervals on the same realistic simulated runs, paired.

``benchmarks/fit_coverage.py`` run on each tree with the same ``--seed`` simulates the
same runs (run ``i`` from the seed sequence ``[seed, i]``) and fits them with each
tree's defaults; this script pairs their raw records (``--raw`` of each) by run and
reports, over the runs both fitted and converged: the coverage of ζ and μ_k by each
(with its 95 % Clopper-Pearson interval), how often the two disagree on a run, the
ratio of the interval widths (the new over the old; median, mean and its standard
error), and the difference of the posterior means in units of the old posterior sd.

Coverage on a few dozen runs cannot show a change of 3 points (the binomial standard
error of a rate near 0.95 on n runs is 0.22/√n); the widths can: for a Gaussian
posterior, a 95 % interval that covers 92 % is 0.89 times as wide, so a mean width
ratio within a few standard errors of 1 rules such a drop out, with the means
unmoved.

Run::

    python benchmarks/fit_coverage_paired.py --new NEW.jsonl --old OLD.jsonl \
        --output fit_coverage_independence
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results
from fit_coverage import PARAMS, _clopper_pearson


def _records(path: Path) -> dict[int, dict[str, Any]]:
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return {r["index"]: r for r in rows if "error" not in r and r.get("converged")}


def paired(new: dict[int, dict], old: dict[int, dict]) -> dict[str, Any]:
    """Coverage, widths and means of the runs both versions fitted and converged."""
    both = sorted(set(new) & set(old))
    out: dict[str, Any] = {"runs_paired": len(both)}
    for name in PARAMS:
        hits_new = [new[i]["covered"][name] for i in both]
        hits_old = [old[i]["covered"][name] for i in both]
        width = np.array(
            [
                np.diff(new[i]["interval"][name])[0] / np.diff(old[i]["interval"][name])[0]
                for i in both
            ]
        )
        shift = np.array(
            [(new[i]["mean"][name] - old[i]["mean"][name]) / old[i]["sd"][name] for i in both]
        )
        out[name] = {
            "covered_new": int(np.sum(hits_new)),
            "covered_old": int(np.sum(hits_old)),
            "ci95_new": _clopper_pearson(int(np.sum(hits_new)), len(both)),
            "ci95_old": _clopper_pearson(int(np.sum(hits_old)), len(both)),
            "disagree": int(np.sum(np.array(hits_new) != np.array(hits_old))),
            "width_ratio_median": float(np.median(width)),
            "width_ratio_mean": float(np.mean(width)),
            "width_ratio_se": float(np.std(width, ddof=1) / np.sqrt(width.size)),
            "mean_shift_sd_mean": float(np.mean(shift)),
            "mean_shift_sd_rms": float(np.sqrt(np.mean(shift**2))),
            "mean_shift_sd_max": float(np.max(np.abs(shift))),
        }
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--new", type=Path, required=True, help="raw records of the new tree")
    parser.add_argument("--old", type=Path, required=True, help="raw records of the old tree")
    parser.add_argument("--note", default="", help="what the two trees are")
    parser.add_argument("--output", default="fit_coverage_paired")
    args = parser.parse_args(argv)
    new, old = _records(args.new), _records(args.old)
    result = paired(new, old)
    for name in PARAMS:
        r = result[name]
        print(
            f"{name:6s} covered {r['covered_new']}/{result['runs_paired']} (old "
            f"{r['covered_old']}), width ratio {r['width_ratio_mean']:.4f} ± "
            f"{r['width_ratio_se']:.4f}, means moved {r['mean_shift_sd_rms']:.3f} sd rms"
        )
    path = write_results(
        args.output,
        {
            "benchmark": "fit_coverage_paired",
            "description": __doc__.split("\n\n")[1],
            "note": args.note,
            "converged_new": len(new),
            "converged_old": len(old),
            **result,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
