"""The bundled campaign as a user runs it, side by side with an older commit.

Issue 15's last goal: ``bayestribo campaign data/ --workers 2`` (fits, population
analysis, trends, tables and figures) at least 4× faster than at commit 5cfd060.

Two trees are timed, each fixed so that nobody's edits change the code under test:

* ``--baseline`` (default ``/tmp/bt-5cfd060``): a git worktree of 5cfd060, made with
  ``git worktree add /tmp/bt-5cfd060 5cfd060`` if it does not exist;
* ``--current`` (default ``/tmp/snap-HEAD``): an exported snapshot of the current
  HEAD (``git archive HEAD | tar -x -C /tmp/snap-HEAD``), made if it does not exist;
  its commit is recorded in ``.snapshot-commit``; if an existing snapshot holds
  another commit, HEAD is exported to ``/tmp/snap-<commit>`` instead.

Each job is the whole command a user runs, ``bayestribo campaign data/ --workers 2
--out TMPDIR`` with the tree's defaults (the console script's entry point read from
the tree's ``pyproject.toml``), as a subprocess with ``PYTHONPATH=<tree>`` and its
working directory in the tree, so it reads that tree's bundled ``data/`` (the same
campaign: the run files are compared by hash). The installed package is an editable
install of the working tree, whose import hook would serve any module an old tree
lacks from the working tree: a ``sitecustomize`` on the ``PYTHONPATH`` removes it in
every process (the command and its workers), and the command's process checks that
every ``bayestribo`` module it imported comes from its tree. Wall time is measured
end to end, from starting the process to its exit; its split is read from the
command's own output as it arrives: the fits end when the progress line reaches
N/N, the population analysis when ``population.json`` is written (its modification
time), the figures with the last file in ``figures/``. The current tree's command
also times the population steps itself (its ``[ n s]`` lines, recorded).

One untimed warm-up job per tree first (imports, numba's caches), then ``--repeats``
rounds alternating the order (baseline, current; current, baseline; ...) so that the
load of a shared machine falls on both alike; the load average is recorded before
and after every job. Each job writes to a fresh folder (no catalog reuse).

Agreement: per run, the posterior means of ζ and μ_k from the two trees (the
campaign's catalog, ``catalog.sqlite``: each fit's posterior summary) differ by
|Δ mean| / sd (the baseline's posterior sd; also against the mean of the two sds),
averaged over runs; they should be within 0.1 sd on average; and the number of
converged runs must be the same. Repeated jobs of one tree must give identical
per-run posteriors (same seeds).

Run: ``nice -n 10 python benchmarks/campaign_speed.py --repeats 3``. Prints a table
and writes ``benchmarks/results/campaign_speed.json``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

REPO = Path(__file__).resolve().parents[1]
BASELINE_COMMIT = "5cfd060"
DEFAULT_BASELINE = Path("/tmp/bt-5cfd060")
DEFAULT_SNAPSHOT = Path("/tmp/snap-HEAD")
MARKER = ".snapshot-commit"
PARAMS = ("zeta", "mu_k")

#: Removes setuptools' editable-install import hook (which maps ``bayestribo`` to the
#: working tree) in every Python process of a job, so only ``PYTHONPATH``'s tree counts.
SITECUSTOMIZE = """\
import sys
sys.meta_path[:] = [
    f for f in sys.meta_path
    if "Editable" not in getattr(f, "__name__", type(f).__name__)
]
"""

#: The console script of the tree (``bayestribo = "module:function"``), with a check
#: of where the command's own process imported bayestribo's modules from.
LAUNCHER = """\
import json, os, sys
tree = os.path.realpath(sys.argv.pop(1))
module, function = sys.argv.pop(1).split(":")
sys.argv[0] = "bayestribo"
rc = 2
try:
    main = getattr(__import__(module, fromlist=[function]), function)
    rc = main()
finally:
    foreign = sorted(
        name for name, m in list(sys.modules.items())
        if name.split(".")[0] == "bayestribo" and getattr(m, "__file__", None)
        and not os.path.realpath(m.__file__).startswith(tree + os.sep)
    )
    print("@@campaign-speed " + json.dumps({"foreign_modules": foreign}), file=sys.stderr)
sys.exit(rc)
"""


def git(*args: str, cwd: Path = REPO) -> str:
    return subprocess.run(
        ["git", "-C", str(cwd), *args], capture_output=True, text=True, check=True
    ).stdout.strip()


def baseline_tree(path: Path | None) -> Path:
    """The given tree, or the worktree of 5cfd060 (made if absent)."""
    if path is not None:
        return path.resolve()
    if not (DEFAULT_BASELINE / "bayestribo").is_dir():
        git("worktree", "add", "--detach", str(DEFAULT_BASELINE), BASELINE_COMMIT)
    return DEFAULT_BASELINE


def current_tree(path: Path | None) -> Path:
    """The given tree, or a snapshot of HEAD exported with git archive (made if absent)."""
    if path is not None:
        return path.resolve()
    head = git("rev-parse", "HEAD")
    target = DEFAULT_SNAPSHOT
    if target.exists():
        marker = target / MARKER
        if not marker.exists() or marker.read_text().strip() != head:
            target = Path(f"/tmp/snap-{head[:7]}")
    if not (target / "bayestribo").is_dir():
        target.mkdir(parents=True, exist_ok=True)
        archive = subprocess.Popen(
            ["git", "-C", str(REPO), "archive", head], stdout=subprocess.PIPE
        )
        subprocess.run(["tar", "-x", "-C", str(target)], stdin=archive.stdout, check=True)
        if archive.wait() != 0:
            raise RuntimeError("git archive failed")
        (target / MARKER).write_text(head + "\n")
    return target


def tree_commit(tree: Path) -> str:
    """The tree's commit: its snapshot marker, or git's HEAD (+changes when modified)."""
    marker = tree / MARKER
    if marker.exists():
        return marker.read_text().strip()
    try:
        head = git("rev-parse", "HEAD", cwd=tree)
        dirty = git("status", "--porcelain", "--untracked-files=no", cwd=tree)
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+changes" if dirty else "")


def entry_point(tree: Path) -> str:
    """``module:function`` of the tree's ``bayestribo`` console script."""
    with open(tree / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["project"]["scripts"]["bayestribo"]


def campaign_options(tree: Path, env: dict[str, str]) -> str:
    """The tree's ``campaign --help`` (checked for the options the job uses)."""
    out = subprocess.run(
        [sys.executable, "-c", LAUNCHER, str(tree), entry_point(tree), "campaign", "--help"],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
    ).stdout
    for option in ("--workers", "--out"):
        if option not in out:
            raise RuntimeError(f"{tree}: campaign has no {option} option")
    return out


def data_fingerprint(tree: Path) -> dict[str, str]:
    """sha256 of every file of the tree's bundled campaign (runs, sidecars, manifest)."""
    return {
        str(p.relative_to(tree / "data")): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted((tree / "data").rglob("*"))
        if p.is_file()
    }


def compare_data(old: dict[str, str], new: dict[str, str]) -> dict[str, Any]:
    """Whether the run files (CSV with a JSON sidecar, as the command finds them) agree."""
    runs = sorted(k for k in new if k.endswith(".csv") and k.removesuffix(".csv") + ".json" in new)
    return {
        "run_files": len(runs),
        "same_run_files": runs
        == sorted(k for k in old if k.endswith(".csv") and k.removesuffix(".csv") + ".json" in old)
        and all(old.get(k) == new[k] for k in runs),
        "files_that_differ": sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k)),
    }


def read_outputs(out: Path) -> dict[str, Any]:
    """Per-run posterior means, sds, convergence and fit times from the catalog."""
    runs: dict[str, dict[str, Any]] = {}
    with sqlite3.connect(out / "catalog.sqlite") as conn:
        rows = conn.execute(
            "SELECT runs.run_id, fits.summary FROM fits JOIN runs ON fits.run = runs.id"
        ).fetchall()
    for run_id, text in rows:
        summary = json.loads(text)
        post = summary.get("posterior", {})
        runs[run_id] = {
            "converged": bool(summary.get("converged")),
            "fit_seconds": summary.get("elapsed_s"),
            **{
                p: {"mean": post[p]["mean"], "sd": post[p]["sd"]}
                for p in PARAMS
                if p in post and post[p].get("sd") is not None
            },
        }
    table_converged = None
    if (out / "runs.csv").exists():
        import csv

        with open(out / "runs.csv") as f:
            table_converged = sum(r.get("converged") == "True" for r in csv.DictReader(f))
    report = json.loads((out / "population.json").read_text())
    return {
        "runs": runs,
        "converged_runs": sum(r["converged"] for r in runs.values()),
        "converged_runs_in_runs_csv": table_converged,
        "failures": len(report.get("failures", [])),
        "population_converged": report.get("converged"),
    }


class Job:
    """One ``bayestribo campaign`` process, its stderr timestamped as it arrives."""

    def __init__(self, tree: Path, env: dict[str, str], workers: int, out: Path) -> None:
        self.cmd = [
            sys.executable,
            "-c",
            LAUNCHER,
            str(tree),
            entry_point(tree),
            "campaign",
            "data/",
            "--workers",
            str(workers),
            "--out",
            str(out),
        ]
        self.tree, self.env, self.out = tree, env, out
        self.chunks: list[tuple[float, str]] = []

    def _read(self, stream: Any, start: float) -> None:
        fd = stream.fileno()
        while chunk := os.read(fd, 65536):
            self.chunks.append((time.perf_counter() - start, chunk.decode(errors="replace")))

    def run(self) -> dict[str, Any]:
        load_before = os.getloadavg()
        epoch = time.time()
        start = time.perf_counter()
        with open(self.out.parent / "stdout.txt", "w") as stdout:
            proc = subprocess.Popen(
                self.cmd, cwd=self.tree, env=self.env, stdout=stdout, stderr=subprocess.PIPE
            )
            reader = threading.Thread(target=self._read, args=(proc.stderr, start))
            reader.start()
            rc = proc.wait()
            wall = time.perf_counter() - start
            reader.join()
        load_after = os.getloadavg()
        return {
            "exit_status": rc,
            "wall_s": wall,
            "load_before": list(load_before),
            "load_after": list(load_after),
            **self._split(epoch, wall),
        }

    def _split(self, epoch: float, wall: float) -> dict[str, Any]:
        text, fits_done, fits_start = "", None, None
        for t, chunk in self.chunks:
            text += chunk
            if fits_start is None and "fit runs [" in text:
                fits_start = t
            if fits_done is None:
                done = re.findall(r"fit runs \[[#.]*\] (\d+)/(\d+)", text)
                if done and done[-1][0] == done[-1][1]:
                    fits_done = t
        population = self.out / "population.json"
        analysis_done = population.stat().st_mtime - epoch if population.exists() else None
        figures = list((self.out / "figures").glob("*")) if (self.out / "figures").is_dir() else []
        figures_done = max(p.stat().st_mtime for p in figures) - epoch if figures else None
        marker = re.search(r"@@campaign-speed (.*)", text)
        own = [
            (t, line)
            for t, chunk in self.chunks
            for line in chunk.splitlines()
            if line.startswith("bayestribo campaign: [")
        ]
        split = {
            "startup_s": fits_start,
            "fitting_s": None if fits_done is None else fits_done - (fits_start or 0.0),
            "population_analysis_s": (
                None if analysis_done is None or fits_done is None else analysis_done - fits_done
            ),
            "figures_s": (
                None
                if figures_done is None or analysis_done is None
                else figures_done - analysis_done
            ),
            "exit_s": None if figures_done is None else wall - figures_done,
            "command_population_messages": [
                {"at_s": round(t, 2), "message": line} for t, line in own
            ],
            "foreign_modules": json.loads(marker.group(1))["foreign_modules"] if marker else None,
        }
        if fits_done is None or split["foreign_modules"] is None:
            split["stderr_tail"] = text[-3000:]
        return split


def timed_job(name: str, tree: Path, env: dict[str, str], workers: int) -> dict[str, Any]:
    """Run one campaign in a fresh folder; its times and per-run posteriors."""
    folder = Path(tempfile.mkdtemp(prefix=f"campaign-speed-{name}-"))
    try:
        job = Job(tree, env, workers, folder / "out")
        result = job.run()
        if result.get("foreign_modules"):
            foreign = result["foreign_modules"]
            raise RuntimeError(f"{name} imported modules from elsewhere: {foreign}")
        result["outputs"] = read_outputs(folder / "out")
        result["stdout_tail"] = (folder / "stdout.txt").read_text()[-2000:]
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return result


def agreement(old: dict[str, Any], new: dict[str, Any]) -> dict[str, Any]:
    """|Δ posterior mean| in posterior sds per run and parameter, and their averages."""
    per_run: dict[str, dict[str, float]] = {}
    for run_id, o in old["runs"].items():
        n = new["runs"].get(run_id)
        if n is None:
            continue
        for p in PARAMS:
            if p in o and p in n and o[p]["sd"] > 0:
                diff = abs(n[p]["mean"] - o[p]["mean"])
                both = ((o[p]["sd"] ** 2 + n[p]["sd"] ** 2) / 2) ** 0.5
                per_run.setdefault(run_id, {})[p] = diff / o[p]["sd"]
                per_run[run_id][f"{p}_in_mean_sd"] = diff / both
                per_run[run_id][f"{p}_sd_ratio"] = n[p]["sd"] / o[p]["sd"]
    summary: dict[str, Any] = {}
    for p in PARAMS:
        values = [r[p] for r in per_run.values() if p in r]
        both = [r[f"{p}_in_mean_sd"] for r in per_run.values() if p in r]
        ratio = [r[f"{p}_sd_ratio"] for r in per_run.values() if p in r]
        summary[p] = {
            "runs": len(values),
            "mean_abs_diff_in_baseline_sd": statistics.fmean(values),
            "median_abs_diff_in_baseline_sd": statistics.median(values),
            "max_abs_diff_in_baseline_sd": max(values),
            "mean_abs_diff_in_mean_sd": statistics.fmean(both),
            "median_sd_ratio_current_over_baseline": statistics.median(ratio),
        }
    return {
        "runs_compared": len(per_run),
        "runs_only_in_one": sorted(set(old["runs"]) ^ set(new["runs"])),
        "by_parameter": summary,
        "within_0.1_sd_on_average": all(
            s["mean_abs_diff_in_baseline_sd"] < 0.1 for s in summary.values()
        ),
        "converged_runs": {"baseline": old["converged_runs"], "current": new["converged_runs"]},
        "same_converged_count": old["converged_runs"] == new["converged_runs"],
        "per_run": per_run,
    }


def fingerprint(outputs: dict[str, Any]) -> dict[str, Any]:
    return {
        run_id: {p: r[p]["mean"] for p in PARAMS if p in r} for run_id, r in outputs["runs"].items()
    }


def _fmt(v: float | None, spec: str = "6.1f") -> str:
    return "     -" if v is None else format(v, spec)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--baseline", type=Path, help=f"tree of the old commit ({DEFAULT_BASELINE})"
    )
    parser.add_argument("--current", type=Path, help=f"tree of the new code ({DEFAULT_SNAPSHOT})")
    parser.add_argument("--repeats", type=int, default=3, help="timed rounds")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default="campaign_speed", help="results/<output>.json")
    args = parser.parse_args(argv)
    began = time.perf_counter()
    load_start = os.getloadavg()
    trees = {"baseline": baseline_tree(args.baseline), "current": current_tree(args.current)}
    guard = Path(tempfile.mkdtemp(prefix="campaign-speed-site-"))
    (guard / "sitecustomize.py").write_text(SITECUSTOMIZE)
    envs = {
        name: {**os.environ, "PYTHONPATH": f"{tree}{os.pathsep}{guard}"}
        for name, tree in trees.items()
    }
    commits = {name: tree_commit(tree) for name, tree in trees.items()}
    for name, tree in trees.items():
        campaign_options(tree, envs[name])
        print(f"{name:8s} {commits[name][:12]} {tree} ({entry_point(tree)})", flush=True)
    data = {name: data_fingerprint(tree) for name, tree in trees.items()}
    same_data = compare_data(data["baseline"], data["current"])
    print(
        f"same run files (CSV) in both trees' data/: {same_data['same_run_files']} "
        f"({same_data['run_files']} runs); files that differ: {same_data['files_that_differ']}"
    )

    warm_up = {}
    for name, tree in trees.items():
        print(f"warm-up {name} ...", flush=True)
        job = timed_job(name, tree, envs[name], args.workers)
        warm_up[name] = {k: v for k, v in job.items() if k != "outputs"}
        print(f"  {job['wall_s']:.1f} s, exit {job['exit_status']}", flush=True)

    rounds: list[dict[str, Any]] = []
    outputs: dict[str, list[dict[str, Any]]] = {"baseline": [], "current": []}
    for r in range(args.repeats):
        order = ["baseline", "current"] if r % 2 == 0 else ["current", "baseline"]
        row: dict[str, Any] = {"round": r + 1, "order": order}
        for name in order:
            job = timed_job(name, trees[name], envs[name], args.workers)
            outputs[name].append(job.pop("outputs"))
            row[name] = job
            print(
                f"  round {r + 1} {name:8s} {job['wall_s']:7.1f} s (fits {_fmt(job['fitting_s'])}"
                f", population {_fmt(job['population_analysis_s'])}, figures "
                f"{_fmt(job['figures_s'])}) load {job['load_before'][0]:.2f} "
                f"exit {job['exit_status']}",
                flush=True,
            )
        row["ratio"] = row["baseline"]["wall_s"] / row["current"]["wall_s"]
        rounds.append(row)

    med = {n: statistics.median(row[n]["wall_s"] for row in rounds) for n in trees}
    ratios = [row["ratio"] for row in rounds]
    median_ratio = statistics.median(ratios)
    phases = ("startup_s", "fitting_s", "population_analysis_s", "figures_s", "exit_s")
    split = {
        n: {
            p: statistics.median(row[n][p] for row in rounds)
            if all(row[n][p] is not None for row in rounds)
            else None
            for p in phases
        }
        for n in trees
    }
    fit_seconds = {
        n: statistics.median(
            sum(r["fit_seconds"] or 0.0 for r in o["runs"].values()) for o in outputs[n]
        )
        for n in trees
    }
    agree = agreement(outputs["baseline"][0], outputs["current"][0])
    reproducible = {
        n: all(fingerprint(o) == fingerprint(outputs[n][0]) for o in outputs[n]) for n in trees
    }

    print(
        f"\n{'round':>5s} {'order':18s} {'baseline s':>10s} {'load':>5s} "
        f"{'current s':>10s} {'load':>5s} {'ratio':>6s}"
    )
    for row in rounds:
        print(
            f"{row['round']:5d} {' → '.join(row['order']):18s} "
            f"{row['baseline']['wall_s']:10.1f} {row['baseline']['load_before'][0]:5.2f} "
            f"{row['current']['wall_s']:10.1f} {row['current']['load_before'][0]:5.2f} "
            f"{row['ratio']:6.2f}"
        )
    print(
        f"median: baseline {med['baseline']:.1f} s, current {med['current']:.1f} s; "
        f"median of per-round ratios {median_ratio:.2f}x, ratio of medians "
        f"{med['baseline'] / med['current']:.2f}x (goal ≥ 4x: {median_ratio >= 4})"
    )
    print(f"{'phase (median s)':24s} {'baseline':>9s} {'current':>9s} {'ratio':>6s}")
    for p in phases:
        b, c = split["baseline"][p], split["current"][p]
        ratio = f"{b / c:6.2f}" if b is not None and c else "     -"
        print(f"{p:24s} {_fmt(b, '9.1f')} {_fmt(c, '9.1f')} {ratio}")
    print(
        f"sum of per-run fit times in the workers: baseline {fit_seconds['baseline']:.1f} s, "
        f"current {fit_seconds['current']:.1f} s"
    )
    for p, s in agree["by_parameter"].items():
        print(
            f"{p:5s}: |Δ mean| / sd over {s['runs']} runs: mean "
            f"{s['mean_abs_diff_in_baseline_sd']:.3f}"
            f", median {s['median_abs_diff_in_baseline_sd']:.3f}, max "
            f"{s['max_abs_diff_in_baseline_sd']:.3f}; sd current/baseline "
            f"{s['median_sd_ratio_current_over_baseline']:.2f}"
        )
    print(
        f"converged runs: {agree['converged_runs']}; within 0.1 sd on average: "
        f"{agree['within_0.1_sd_on_average']}; repeated jobs identical: {reproducible}"
    )
    wall_total = time.perf_counter() - began
    print(f"benchmark wall time {wall_total / 60:.1f} min")
    path = write_results(
        args.output,
        {
            "benchmark": "campaign_speed",
            "description": __doc__.split("\n\n")[1],
            "command": f"bayestribo campaign data/ --workers {args.workers} --out TMPDIR",
            "trees": {n: str(t) for n, t in trees.items()},
            "commits": commits,
            "entry_points": {n: entry_point(t) for n, t in trees.items()},
            "data": same_data,
            "workers": args.workers,
            "repeats": args.repeats,
            "load_average_at_start": list(load_start),
            "load_average_at_end": list(os.getloadavg()),
            "warm_up": warm_up,
            "rounds": rounds,
            "median_wall_s": med,
            "per_round_ratios": ratios,
            "median_ratio": median_ratio,
            "ratio_of_medians": med["baseline"] / med["current"],
            "goal_4x_met": median_ratio >= 4,
            "median_split_s": split,
            "sum_of_fit_seconds_in_workers": fit_seconds,
            "agreement": agree,
            "repeated_jobs_identical": reproducible,
            "benchmark_wall_s": wall_total,
            "notes": (
                "Wall times of the whole command, from starting the process to its exit, on a "
                "shared 2-core machine (load averages recorded before and after each job). "
                "Phases from the command's output as it arrived: startup until the first "
                "progress line, fitting until the line reached N/N, population analysis "
                "until population.json was written, figures until the last figure file, "
                "exit the rest. Each tree's own defaults (the old command samples every "
                "population for a fixed 2500 steps; the current one up to 10000, stopping "
                "once converged)."
            ),
        },
    )
    shutil.rmtree(guard, ignore_errors=True)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
