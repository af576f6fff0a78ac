"""Memory of a campaign's main process against the number of runs, side by side.

A campaign of ``--small`` runs (default 54, the bundled campaign's size) and one of
``--large`` runs (default 540) are simulated once (the bundled campaign's plan with
other seeds, one folder per seed, the files renamed ``s<seed>-<run>`` so that every
version reads them as distinct runs). ``bayestribo campaign`` then runs on each, in a
fresh process per campaign (``_campaign_memory_worker``), for the current tree and,
with ``--baseline PATH`` (a git worktree of an older commit), for that one, alternating;
each process reports its own peak resident memory (``ru_maxrss`` of the main process:
the fitting workers are other processes) and its wall time. Fits are short
(``--max-steps``, ``--population-steps``): the benchmark is about what the main process
holds, not about the posteriors.

Goal: the current tree's peak memory at ``--large`` runs within 10 % of that at
``--small`` runs.

Run: ``python benchmarks/campaign_memory.py --baseline /tmp/bt-base``; prints a table
and writes ``benchmarks/results/campaign_memory.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

HERE = Path(__file__).resolve().parent
TREE = HERE.parent


def simulate(folder: Path, n_runs: int) -> int:
    """Simulate whole campaigns of the bundled plan into ``folder`` until ``n_runs``."""
    from bayestribo.io import read_run, write_run
    from bayestribo.synthetic.campaign import write_campaign

    written = 0
    seed = 1
    while written < n_runs:
        scratch = folder / f".seed{seed}"
        write_campaign(scratch, seed=1000 + seed)
        for csv in sorted((scratch / "runs").glob("*.csv")):
            if written >= n_runs:
                break
            name = f"s{seed}-{csv.stem}"
            run = read_run(csv, validate=False)
            metadata = {**run.metadata, "run_id": name}
            target = folder / f"seed{seed}" / f"{name}.csv"
            target.parent.mkdir(parents=True, exist_ok=True)
            write_run(type(run)(run.time, run.displacement, run.velocity, metadata), target)
            written += 1
        shutil.rmtree(scratch)
        seed += 1
    return written


def measure(tree: Path, folder: Path, out: Path, args: argparse.Namespace) -> dict:
    """One campaign in a fresh process on ``tree``: peak memory and wall time."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    command = [
        sys.executable,
        str(HERE / "_campaign_memory_worker.py"),
        str(folder),
        "--out",
        str(out),
        "--workers",
        str(args.workers),
        "--max-steps",
        str(args.max_steps),
        "--population-steps",
        str(args.population_steps),
        "--no-figures",
        "--quiet",
        "--json",
    ]
    start = time.perf_counter()
    proc = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    lines = [line for line in proc.stderr.splitlines() if line.startswith("MEMORY ")]
    if not lines:
        raise RuntimeError(f"campaign on {tree} failed:\n{proc.stderr[-3000:]}")
    peak = json.loads(lines[-1][len("MEMORY ") :])
    report = json.loads(proc.stdout) if proc.stdout.strip() else {}
    return {
        "exit_status": proc.returncode,
        "peak_rss_MB": peak["maxrss_kB"] / 1024,
        "rss_after_fits_MB": peak.get("rss_after_fits_kB", 0) / 1024 or None,
        "wall_s": wall,
        "n_runs": report.get("n_runs"),
        "failures": len(report.get("failures", [])),
        "load_average": list(os.getloadavg()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--small", type=int, default=54)
    parser.add_argument("--large", type=int, default=540)
    parser.add_argument("--baseline", type=Path, help="a git worktree of an older commit")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--max-steps", type=int, default=300)
    parser.add_argument("--population-steps", type=int, default=300)
    parser.add_argument("--output", default="campaign_memory")
    args = parser.parse_args()

    trees = {"current": TREE}
    if args.baseline is not None:
        trees["baseline"] = args.baseline.resolve()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp)
        folders = {}
        for size in (args.small, args.large):
            folders[size] = data / f"runs{size}"
            simulate(folders[size], size)
        for size in (args.small, args.large):
            for version, tree in trees.items():
                out = data / f"out-{version}-{size}"
                result = measure(tree, folders[size], out, args)
                rows.append({"version": version, "runs": size, **result})
                print(
                    f"{version:9s} {size:4d} runs: peak {result['peak_rss_MB']:7.1f} MB, "
                    f"{result['wall_s']:6.0f} s, exit {result['exit_status']}, "
                    f"failures {result['failures']}",
                    flush=True,
                )
    growth = {}
    for version in trees:
        small = next(r for r in rows if r["version"] == version and r["runs"] == args.small)
        large = next(r for r in rows if r["version"] == version and r["runs"] == args.large)
        growth[version] = large["peak_rss_MB"] / small["peak_rss_MB"]
    print()
    print(
        f"{'version':9s} {'peak at ' + str(args.small):>14s} {'peak at ' + str(args.large):>14s}"
        f" {'ratio':>7s}"
    )
    for version in trees:
        small = next(r for r in rows if r["version"] == version and r["runs"] == args.small)
        large = next(r for r in rows if r["version"] == version and r["runs"] == args.large)
        print(
            f"{version:9s} {small['peak_rss_MB']:11.1f} MB {large['peak_rss_MB']:11.1f} MB "
            f"{growth[version]:7.3f}"
        )
    commit = subprocess.run(
        ["git", "-C", str(TREE), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    write_results(
        args.output,
        {
            "benchmark": "campaign_memory",
            "description": __doc__,
            "commit": commit,
            "baseline": str(args.baseline) if args.baseline else None,
            "settings": vars(args) | {"baseline": str(args.baseline) if args.baseline else None},
            "rows": rows,
            "peak_ratio_large_over_small": growth,
            "goal": "current tree: ratio <= 1.10",
        },
    )


if __name__ == "__main__":
    main()
