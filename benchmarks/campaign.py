"""Campaign benchmark: the bundled campaign fitted with 1 and 2 processes and on Dask.

Fits every run of ``data/runs`` (or an evenly spaced subset, ``--runs N``) with
:func:`bayestribo.campaign.fitting.fit_many` and the default single-run fit, side by side in one
session:

* a process pool with 1 worker, then with 2 workers (speed-up = ratio of wall times);
* a Dask ``LocalCluster`` of 2 single-threaded worker processes through
  ``Client.get_executor()`` (if ``dask.distributed`` is installed).

Reported: wall time, speed-up, median per-run fit time inside the workers (to set
against ``benchmarks/fit.py``'s single-run time), failures, converged fits, whether
every configuration gave identical posteriors (same seeds per run), the time of the
population analysis, and how often the per-run 95 % intervals of ζ and μ_k contain the
manifest's true values. Wall times include starting the workers (imports and the
compiled kernels' first call) as a user would see them.

Workers import bayestribo when they start, so every configuration must see the same
code: run it on a tree nobody is editing, e.g. an exported snapshot
(``git archive HEAD | tar -x -C /tmp/snap; cd /tmp/snap; PYTHONPATH=. python
benchmarks/campaign.py``), and copy ``benchmarks/results/campaign.json`` back.

Run: ``python benchmarks/campaign.py [--runs N]``. Prints a table and writes
``benchmarks/results/campaign.json``.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

from bayestribo.campaign.analysis import analyse_campaign
from bayestribo.campaign.fitting import fit_many
from bayestribo.errors import ConvergenceWarning

DATA = Path(__file__).resolve().parents[1] / "data"


def _manifest() -> dict[str, dict[str, float]]:
    with open(DATA / "manifest.csv") as f:
        return {
            r["run_id"]: {"zeta": float(r["zeta"]), "mu_k": float(r["mu_k"])}
            for r in csv.DictReader(f)
        }


def _fingerprint(outcomes) -> dict[str, tuple[float, ...]]:
    """Posterior medians per run: equal across executors when the seeds are."""
    out = {}
    for o in outcomes:
        names = o.result.parameter_names if o.ok else []
        out[o.name] = tuple(float(np.median(o.result.samples(p))) for p in names)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--runs", type=int, help="evenly spaced subset of the runs")
    parser.add_argument("--seed", type=int, default=20100320)
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args()
    warnings.simplefilter("ignore", ConvergenceWarning)
    paths = sorted((DATA / "runs").glob("*.csv"))
    if args.runs:
        paths = [paths[i] for i in np.linspace(0, len(paths) - 1, args.runs).round().astype(int)]
    configs: list[tuple[str, object, int | None]] = [
        ("process pool, 1 worker", None, 1),
        ("process pool, 2 workers", None, 2),
    ]
    rows, results = [], {}
    for label, executor, workers in configs:
        t0 = time.perf_counter()
        outcomes = fit_many(
            paths, executor, campaign_seed=args.seed, max_workers=workers, progress=True
        )
        rows.append((label, time.perf_counter() - t0, outcomes))
        results[label] = outcomes
    if not args.no_dask:
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            print("dask.distributed not installed: Dask configuration skipped")
        else:
            t0 = time.perf_counter()
            with (
                LocalCluster(
                    n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
                ) as cluster,
                Client(cluster) as client,
            ):
                outcomes = fit_many(
                    paths, client.get_executor(), campaign_seed=args.seed, progress=True
                )
            rows.append(("dask LocalCluster, 2 workers", time.perf_counter() - t0, outcomes))
            results["dask"] = outcomes
    reference = _fingerprint(rows[0][2])
    truth = _manifest()
    base = rows[0][1]
    table = []
    print(f"\n{len(paths)} runs")
    print(
        f"{'configuration':32s} {'wall [s]':>9s} {'speed-up':>8s} {'run [s]':>8s} "
        f"{'failed':>6s} {'conv.':>5s} {'same':>5s}"
    )
    for label, wall, outcomes in rows:
        ok = [o for o in outcomes if o.ok]
        per_run = statistics.median(o.elapsed_s for o in ok) if ok else float("nan")
        same = _fingerprint(outcomes) == reference
        conv = sum(bool(o.result.converged) for o in ok)
        table.append(
            {
                "configuration": label,
                "wall_s": wall,
                "speed_up": base / wall,
                "median_fit_s": per_run,
                "failed": len(outcomes) - len(ok),
                "converged": conv,
                "identical_to_first": same,
                "errors": {o.name: o.error for o in outcomes if not o.ok},
            }
        )
        print(
            f"{label:32s} {wall:9.1f} {base / wall:8.2f} {per_run:8.2f} "
            f"{len(outcomes) - len(ok):6d} {conv:5d} {same!s:>5s}"
        )
    fitted = [o.result for o in rows[-1][2] if o.ok]
    t0 = time.perf_counter()
    analysis = analyse_campaign(fitted, seed=args.seed)
    t_analysis = time.perf_counter() - t0
    cover = {"zeta": [0, 0], "mu_k": [0, 0]}
    for o in rows[-1][2]:
        if not o.ok:
            continue
        for p in cover:
            if p in o.result.parameter_names and truth[o.name][p] > 0:
                lo, hi = np.quantile(o.result.samples(p), [0.025, 0.975])
                cover[p][0] += int(lo <= truth[o.name][p] <= hi)
                cover[p][1] += 1
    n_groups = len(analysis.contact.groups) if analysis.contact else 0
    print(f"population analysis: {t_analysis:.1f} s; groups: {n_groups}")
    for p, (hit, n) in cover.items():
        print(f"per-run 95 % intervals containing the true {p}: {hit}/{n}")
    path = write_results(
        "campaign",
        {
            "runs": len(paths),
            "seed": args.seed,
            "configurations": table,
            "population_analysis_s": t_analysis,
            "per_run_coverage_95": {p: {"hits": h, "runs": n} for p, (h, n) in cover.items()},
            "single_run_benchmark": "benchmarks/results/fit.json",
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
