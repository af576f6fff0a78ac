"""A 1 MHz record: reading and preparing it for the fit, side by side with an older tree.

A simulated record of the paper's rig sampled at ``--rate`` (default 1 MHz) for about
``--seconds`` (default 1 s: release, motion and rests) is written once as a canonical
CSV. Each version (the current tree and ``--baseline PATH``, a git worktree of an older
commit) then reads it with ``read_run`` and prepares it with
``bayestribo.inference.pipeline.prepare`` (everything a fit does before its first
likelihood evaluation) in a fresh process, ``--repeats`` times, alternating between the
versions so that the load of a shared machine falls on both alike. Reported per
version: median read and prepare times (wall clock, and the process's CPU time, which
a threaded BLAS waiting for a busy core inflates), their sum against the sampling time, and the
process's peak resident memory (VmHWM: ``ru_maxrss`` keeps the parent's peak across
fork and exec on Linux, and the benchmark's own process holds the simulated record,
390 MB, so every worker read at least that).

Each worker records whether it read with pyarrow (the ``large`` extra; ``--site DIR``
puts a folder of packages installed apart on both versions' path) and whether it
imported pandas.

Goal: read + prepare within 2x the sampling time, peak memory under 400 MB, and at
least 5x faster than the baseline side by side.

Run: ``python benchmarks/large_record.py --baseline /tmp/bt-base``; prints a table and
writes ``benchmarks/results/large_record.json``. A threaded BLAS makes the comparison
depend on the machine's load (a busy second core held the baseline's prepare at 4 s
instead of 0.8 s); ``OPENBLAS_NUM_THREADS=1 python benchmarks/large_record.py
--baseline /tmp/bt-base --output large_record_1thread`` measures both on one core.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

TREE = Path(__file__).resolve().parent.parent

WORKER = """
import json, resource, sys, time
def peak_MB():
    # the process's own peak (VmHWM): ru_maxrss keeps the parent's peak across fork and
    # exec on Linux, which here is the benchmark's own (the simulated record, 390 MB)
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t0 = time.perf_counter()
import bayestribo
from bayestribo.io import read_run
from bayestribo.inference.pipeline import prepare
t1 = time.perf_counter()
c1 = time.process_time()
run = read_run(sys.argv[1])
t2 = time.perf_counter()
c2 = time.process_time()
prepared = prepare(run, seed=0)
t3 = time.perf_counter()
c3 = time.process_time()
print(json.dumps({
    "import_s": t1 - t0, "read_s": t2 - t1, "prepare_s": t3 - t2,
    "read_cpu_s": c2 - c1, "prepare_cpu_s": c3 - c2,
    "peak_MB": peak_MB(),
    "module": bayestribo.__file__,
    "pyarrow": sys.modules["pyarrow"].__version__ if "pyarrow" in sys.modules else None,
    "pandas": "pandas" in sys.modules,
    "samples": int(run.time.size), "increments": int(len(prepared.data.dpi))
    if hasattr(prepared, "data") and hasattr(prepared.data, "dpi") else None,
}))
"""


def measure(tree: Path, path: Path, site: Path | None = None) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree) + ("" if site is None else f"{os.pathsep}{site}")}
    # run from the record's folder: "python -c" puts the working directory first on
    # sys.path, which would import the tree the command was started in
    proc = subprocess.run(
        [sys.executable, "-c", WORKER, str(path)],
        env=env,
        capture_output=True,
        text=True,
        cwd=path.parent,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{tree}: {proc.stderr[-2000:]}")
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(result["module"]).resolve().is_relative_to(tree.resolve()):
        raise RuntimeError(f"{tree}: the worker imported {result['module']}")
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rate", type=float, default=1e6, help="sample rate [Hz]")
    parser.add_argument("--seconds", type=float, default=1.0, help="record length [s]")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--baseline", type=Path)
    parser.add_argument("--output", default="large_record")
    parser.add_argument(
        "--site",
        type=Path,
        help="a folder put on the path of both versions after the tree (packages installed "
        "apart, e.g. pip install --target DIR pyarrow, the large extra)",
    )
    args = parser.parse_args()
    from bayestribo.io import write_run
    from bayestribo.synthetic import Release, Sensor, simulate

    trees = {"current": TREE}
    if args.baseline is not None:
        trees["baseline"] = args.baseline.resolve()
    rest = 0.05
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "record.csv"
        run = simulate(
            seed=1,
            sensor=Sensor(sample_rate_Hz=args.rate),
            release=Release(
                motion_duration_s=args.seconds - 2 * rest, rest_before_s=rest, rest_after_s=rest
            ),
        )
        write_run(run, path)
        sampling_s = float(run.time[-1] - run.time[0])
        size_MB = path.stat().st_size / 1e6
        rows: dict[str, list[dict]] = {name: [] for name in trees}
        for _ in range(args.repeats):
            for name, tree in trees.items():
                result = measure(tree, path, args.site)
                result["load_average"] = list(os.getloadavg())
                rows[name].append(result)
    summary = {}
    for name, results in rows.items():
        read = statistics.median(r["read_s"] for r in results)
        prep = statistics.median(r["prepare_s"] for r in results)
        summary[name] = {
            "read_s": read,
            "prepare_s": prep,
            "read_plus_prepare_s": read + prep,
            "read_plus_prepare_cpu_s": statistics.median(
                r["read_cpu_s"] + r["prepare_cpu_s"] for r in results
            ),
            "over_sampling_time": (read + prep) / sampling_s,
            "peak_MB": max(r["peak_MB"] for r in results),
        }
    if "baseline" in summary:
        summary["speedup"] = (
            summary["baseline"]["read_plus_prepare_s"] / summary["current"]["read_plus_prepare_s"]
        )
    print(f"record: {run.time.size} samples, {sampling_s:.3f} s, {size_MB:.1f} MB of CSV")
    print(
        f"{'version':9s} {'read [s]':>9s} {'prepare [s]':>12s} {'sum/sampling':>13s} "
        f"{'peak [MB]':>10s}"
    )
    for name in trees:
        s = summary[name]
        print(
            f"{name:9s} {s['read_s']:9.2f} {s['prepare_s']:12.2f} "
            f"{s['over_sampling_time']:13.2f} {s['peak_MB']:10.0f}"
        )
    if "speedup" in summary:
        print(f"speed-up, side by side: {summary['speedup']:.1f}x")
    commit = subprocess.run(
        ["git", "-C", str(TREE), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    write_results(
        args.output,
        {
            "benchmark": "large_record",
            "description": __doc__,
            "commit": commit,
            "baseline": str(args.baseline) if args.baseline else None,
            "settings": {k: str(v) for k, v in vars(args).items()},
            "record": {"samples": int(run.time.size), "sampling_s": sampling_s, "csv_MB": size_MB},
            "runs": rows,
            "summary": summary,
            "goal": "read + prepare <= 2x sampling time, peak < 400 MB, >= 5x the baseline",
        },
    )


if __name__ == "__main__":
    main()
