"""The CPU of test runs on fresh checkouts, commits side by side.

For each round and each commit of ``--commits`` (alternating, so that the load of a
shared machine falls on all alike): the commit's tree is exported (``git archive``)
into a new folder, so that numba's cache beside the sources is empty, and run with a
new, empty law cache (``BAYESTRIBO_CACHE_DIR``), as on a fresh CI machine; then

    python -m pytest -q -n JOBS -p no:cacheprovider MODULES

under ``/usr/bin/time`` (the run's CPU: the controller and every process it waited
for). A ``sitecustomize.py`` (``benchmarks/_suite_cpu/``) on the ``PYTHONPATH`` of
every process of the run records, at the process's exit, its CPU and the CPU numba
spent compiling (numba's ``numba:compile`` events, outermost only), so that the
compilation can be told from the rest; processes ended by a signal are not recorded.

Reported per run: CPU (user + system) and wall time, the load averages at start and
end, pytest's summary line, and the recorded processes' CPU and compilation, with the
kernels compiled in more than one process. Medians per commit.

Run: ``python benchmarks/suite_cpu.py --modules tests/test_inference_pipeline.py
tests/test_inference_modes.py --rounds 2 --output suite_cpu_warm_up``; writes
``benchmarks/results/<output>.json``. ``--collect DIR`` summarises the run folders
already under DIR (named ``<label>-<commit>-<round>``) instead of running.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

from _machine import ROOT, write_results

INSTRUMENT = Path(__file__).resolve().parent / "_suite_cpu"


def run_one(folder: Path, commit: str, modules: list[str], jobs: int) -> None:
    """Export ``commit`` into ``folder/tree`` and run the modules there (see above)."""
    tree, log, laws = folder / "tree", folder / "log", folder / "laws"
    for path in (tree, log, laws):
        path.mkdir(parents=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", commit], capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    shared = ROOT.parent / "shared"
    if shared.is_dir():  # the real recordings, beside the tree as beside a checkout
        (folder / "shared").symlink_to(shared.resolve())
    env = {
        **os.environ,
        "SUITECUT_LOG": str(log),
        "BAYESTRIBO_CACHE_DIR": str(laws),
        "PYTHONPATH": f"{INSTRUMENT}{os.pathsep}{tree}",
    }
    (folder / "uptime").write_text(str(os.getloadavg()) + "\n")
    argv = ["/usr/bin/time", "-f", "%U %S %e", "-o", str(folder / "time")]
    argv += [sys.executable, "-m", "pytest", "-q", "-n", str(jobs), "-p", "no:cacheprovider"]
    with open(folder / "out.txt", "w") as out:
        subprocess.run([*argv, *modules], cwd=tree, env=env, stdout=out, stderr=out)
    with open(folder / "uptime", "a") as fh:
        fh.write(str(os.getloadavg()) + "\n")


def summarise(folder: Path) -> dict[str, Any]:
    """One run's figures, from its folder."""
    user, system, wall = (float(x) for x in (folder / "time").read_text().split()[-3:])
    loads = [
        [float(x) for x in re.findall(r"\d+\.\d+", line)[-3:]]
        for line in (folder / "uptime").read_text().splitlines()
    ]
    text = (folder / "out.txt").read_text(errors="replace")
    summary = [line for line in text.splitlines() if re.search(r"\d+ (passed|failed)", line)]
    processes = [json.loads(p.read_text()) for p in sorted((folder / "log").glob("*.json"))]
    kernels: Counter[str] = Counter()
    for process in processes:
        kernels.update(process["funcs"].keys())
    # a process forked by a test before this instrument reset a child's record holds its
    # parent's compilations too: each (function, CPU) pair is counted once
    distinct = {(name, round(cpu, 6)) for p in processes for name, cpu in p["funcs"].items()}
    laws: dict[str, list[float]] = {}  # a generated law module: its compilation per process
    for name, cpu in distinct:
        if name.startswith("bayestribo_law_"):
            laws.setdefault(name.split(".")[0], []).append(cpu)
    laws = {k: [round(sum(v), 2)] for k, v in laws.items()}
    repeated = Counter(name for name, cpu in distinct if cpu > 0.5)
    notebooks = [p for p in processes if any("ipykernel" in a for a in p["argv"])]
    return {
        "cpu_s": user + system,
        "wall_s": wall,
        "load_start": loads[0],
        "load_end": loads[-1] if len(loads) > 1 else None,
        "pytest": summary[-1].strip("= ") if summary else None,
        "processes_recorded": len(processes),
        "recorded_cpu_s": sum(p["cpu"] for p in processes),
        "compile_cpu_s": sum(p["compile"] for p in processes),
        "compiling_processes": sum(1 for p in processes if p["compile"] > 1.0),
        "kernels_compiled_more_than_once": sorted(k for k, n in kernels.items() if n > 1),
        "law_modules_compiled": len(laws),
        "law_compile_cpu_s": round(sum(sum(v) for v in laws.values()), 1),
        "distinct_compile_cpu_s": round(sum(cpu for _, cpu in distinct), 1),
        "functions_compiled_in_more_than_one_process": {
            name: sorted(round(c, 1) for f, c in distinct if f == name)
            for name, n in repeated.items()
            if n > 1
        },
        # notebook kernels and the processes they start (their argv is the kernel's)
        "kernel_processes": len(notebooks),
        "kernel_cpu_s": round(sum(p["cpu"] for p in notebooks), 1),
        "kernels_started_by_test": sorted({p.get("started_in") or "" for p in notebooks} - {""}),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--commits", nargs="+", default=["main", "HEAD"])
    parser.add_argument("--modules", nargs="+", default=[])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--collect", type=Path, help="summarise the run folders under it")
    parser.add_argument("--label", default="run")
    parser.add_argument("--output", default="suite_cpu")
    parser.add_argument("--note", default="", help="how the collected runs were made")
    args = parser.parse_args()
    work = args.collect or Path(tempfile.mkdtemp(prefix="suite-cpu-"))
    if args.collect is None:
        for round_ in range(1, args.rounds + 1):
            for commit in args.commits:
                folder = work / f"{args.label}-{commit.replace('/', '_')}-{round_}"
                run_one(folder, commit, args.modules, args.jobs)
    runs: dict[str, list[dict[str, Any]]] = {}
    for folder in sorted(p for p in work.iterdir() if (p / "time").is_file()):
        commit = folder.name.split("-", 1)[1].rsplit("-", 1)[0]
        runs.setdefault(commit, []).append({"folder": folder.name, **summarise(folder)})
    medians = {
        commit: {
            key: statistics.median(r[key] for r in rows)
            for key in ("cpu_s", "wall_s", "compile_cpu_s", "recorded_cpu_s")
        }
        for commit, rows in runs.items()
    }
    resolved = {
        c: subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", c], capture_output=True, text=True
        ).stdout.strip()
        for c in runs
    }
    path = write_results(
        args.output,
        {
            "benchmark": "suite_cpu",
            "description": __doc__,
            "settings": {"modules": args.modules, "jobs": args.jobs, "commits": resolved},
            "note": args.note,
            "runs": runs,
            "medians": medians,
        },
    )
    print(path)
    print(json.dumps(medians, indent=2))


if __name__ == "__main__":
    main()
