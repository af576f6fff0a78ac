"""Start-up of the command line: ``bayestribo fit RUN`` and ``--help`` in fresh processes.

Measured side by side, in rounds: each round runs, in a new random order each round
and each in a fresh interpreter,

* ``bayestribo --help`` and ``bayestribo SUB --help`` for every sub-command;
* ``python -c "import numpy"``, the yardstick of ``--help`` (goal: at most 1.3×);
* ``bayestribo fit RUN``, the README's command (a table on standard output), on the
  bundled run ``data/runs/glycerol-N0.31-r1.csv`` by default;
* ``python -c "import numpy, numba, scipy.optimize, scipy.signal, emcee"``: the
  third-party libraries the fit needs (its floor, whatever the package does);
* ``python -c "import numpy, numba, scipy.optimize, emcee"``: the same without
  scipy.signal (the floor of a fit that would not use it: emcee imports scipy.stats
  all the same);
* the same floor imported as the command imports its machinery, the cyclic collector
  paused and what the imports made frozen (``gc.disable(); import ...; gc.freeze()``,
  :mod:`bayestribo.cli._imports`): the floor of any command that needs these libraries;
* ``import bayestribo.inference.fitting, bayestribo.cli.fit`` in that way: everything a
  fit imports, numba's first load of the cached integrator included (it runs at import);
* the floor import by import (:data:`BREAKDOWN`): numba, SciPy's parts a fit computes
  with, then scipy.stats, scipy.signal, emcee, and the first call of a cached kernel;

and asks a long-lived worker process (in the same shuffled order) for one in-process
warm fit of the same run (:func:`bayestribo.fit` on the file, the command's defaults,
after a warm-up fit): the yardstick of ``fit`` (goal: at most 4×). Each is timed in CPU
time (user + system, of the fresh process, or of the worker during its fit), which the
load of other users of a shared machine disturbs less than wall time; the wall times are
kept beside them. With ``--baseline TREE`` (a git
worktree of an older commit, e.g. ``git -C /work/main worktree add --detach
/tmp/startup-base 9540bc4``)
every command also runs on that tree within the same round, so that the load of a
shared machine falls on both alike.

``bayestribo`` is run as its console script runs it (``from bayestribo.cli import
main``), with ``PYTHONPATH`` on the tree and the working directory outside the
repository (a ``python -c`` worker started inside it would import the tree it stands
in). Before the rounds each tree's byte code is compiled (as ``pip install`` does:
this machine may set ``PYTHONDONTWRITEBYTECODE``) and each command runs once, so that
numba's caches are warm. Reported: the median over ``--repeats`` rounds of each
command, the ratios fit / warm fit and help / import numpy (also as the median of the
ratios within each round), and whether the two trees print the same fit.

Run: ``python benchmarks/cli_startup.py --baseline /tmp/startup-base``; writes
``benchmarks/results/cli_startup.json``. ``--run FILE --fit-args "OPTIONS"``: another
recording and the fit command's options (``--law``, ``--columns``, ...); the warm fit is
then the command itself, run in the worker with its text discarded.
"""

from __future__ import annotations

import argparse
import compileall
import os
import random
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
from bayestribo.cli.main import COMMANDS  # noqa: E402  (light: argparse and the package's)

RUN = REPO / "data" / "runs" / "glycerol-N0.31-r1.csv"

#: The console script's body (``[project.scripts]``): ``bayestribo ARGS``.
CONSOLE = (
    "import sys; from bayestribo.cli import main; sys.argv[0] = 'bayestribo'; sys.exit(main())"
)
#: The third-party imports of a fit: its floor.
FLOOR = "import numpy, numba, scipy.optimize, scipy.signal, emcee"
#: The same without scipy.signal.
FLOOR_NO_SIGNAL = "import numpy, numba, scipy.optimize, emcee"
#: The floor imported with the collector paused and its objects frozen after.
FLOOR_FROZEN = f"import gc; gc.disable(); {FLOOR_NO_SIGNAL}; gc.enable(); gc.freeze()"
#: Everything a fit imports (numba's first load of a cached kernel runs at import), in
#: the same way: the modules that run the fit and the command (``bayestribo.inference``
#: itself imports its names on first use).
FIT_IMPORTS = (
    "import gc; gc.disable(); import bayestribo.inference.fitting, bayestribo.cli.fit; "
    "gc.enable(); gc.freeze()"
)
#: Where the floor's time goes, import by import (each a fresh process, the collector
#: paused): numba; SciPy's parts a fit computes with; those and scipy.stats (which
#: emcee imports for its KDE move, and the package's checks for their p-values); those
#: and scipy.signal (which imports scipy.stats and scipy.ndimage itself); all of them
#: and emcee; and the same with the first call of a kernel compiled before (numba's
#: code generator set up and the kernel loaded from its cache, as a fit's first
#: compiled call does).
_PAUSED = "import gc; gc.disable(); "
_SCIPY_CORE = "import numpy, numba, scipy.optimize, scipy.linalg, scipy.fft, scipy.special"
BREAKDOWN = {
    "import_numba": _PAUSED + "import numpy, numba",
    "import_scipy_core": _PAUSED + _SCIPY_CORE,
    "import_scipy_core_stats": _PAUSED + _SCIPY_CORE + ", scipy.stats",
    "import_scipy_core_signal": _PAUSED + _SCIPY_CORE + ", scipy.signal",
    "import_scipy_core_stats_signal_emcee": (
        _PAUSED + _SCIPY_CORE + ", scipy.stats, scipy.signal, emcee"
    ),
    "import_libraries_first_cached_call": (
        _PAUSED
        + _SCIPY_CORE
        + ", scipy.stats, scipy.signal, emcee; import numpy as np; "
        + "from bayestribo.model._kernel import _one; "
        + "_one(np.array([0.0, 1.0, 2.0]), 1.0, 0.01, 0.01, 0.02, 0.0, np.inf, np.empty(3))"
    ),
}

#: A long-lived worker: one warm fit of the run per line read, its CPU and wall times
#: printed.
WORKER = """
import contextlib, io, sys, time, warnings
warnings.simplefilter("ignore")
import bayestribo
run, options = sys.argv[1], sys.argv[2:]
def once():
    if not options:
        return bayestribo.fit(run)
    # the command's options (--fit-args): the command itself, in process, its text
    # discarded
    from bayestribo.cli import main
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        main(["fit", run, *options])
once()  # warm-up: imports, numba caches, first-call work
print("ready", flush=True)
for line in sys.stdin:
    cpu, wall = time.process_time(), time.perf_counter()
    once()
    print(time.process_time() - cpu, time.perf_counter() - wall, flush=True)
"""


def _env(tree: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree)}


def _cpu_of_children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _timed(
    argv: list[str], tree: Path, cwd: str
) -> tuple[float, float, subprocess.CompletedProcess]:
    """CPU time (user + system) and wall time of one fresh process (start to exit), and
    what it printed."""
    cpu, start = _cpu_of_children(), time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, cwd=cwd, env=_env(tree))
    return _cpu_of_children() - cpu, time.perf_counter() - start, done


class WarmFit:
    """A worker process on ``tree`` that fits ``run`` in process on request."""

    def __init__(self, tree: Path, run: Path, cwd: str, options: list[str] | None = None) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-c", WORKER, str(run), *(options or [])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=cwd,
            env=_env(tree),
        )
        assert self.proc.stdout is not None and self.proc.stdout.readline().strip() == "ready"

    def once(self) -> tuple[float, float]:
        """CPU and wall time of one warm fit [s]."""
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write("fit\n")
        self.proc.stdin.flush()
        cpu, wall = self.proc.stdout.readline().split()
        return float(cpu), float(wall)

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


def commands(run: Path, options: list[str] | None = None) -> dict[str, list[str]]:
    """The fresh-process commands of a round, by name (``options``: the fit's)."""
    py = sys.executable
    return {
        "help": [py, "-c", CONSOLE, "--help"],
        **{f"help_{sub}": [py, "-c", CONSOLE, sub, "--help"] for sub in COMMANDS},
        "import_numpy": [py, "-c", "import numpy"],
        "fit": [py, "-c", CONSOLE, "fit", str(run), *(options or [])],
        "import_fit_libraries": [py, "-c", FLOOR],
        "import_floor": [py, "-c", FLOOR_NO_SIGNAL],
        "import_floor_frozen": [py, "-c", FLOOR_FROZEN],
        "import_fit": [py, "-c", FIT_IMPORTS],
        **{name: [py, "-c", code] for name, code in BREAKDOWN.items()},
    }


def _ratios(times: dict[str, list[float]], warm: list[float]) -> dict[str, Any]:
    """Median times and the goals' ratios of one tree (CPU times)."""
    med = {c: statistics.median(v) for c, v in times.items()}
    med["warm_fit"] = statistics.median(warm)
    helps = {c: med[c] / med["import_numpy"] for c in med if c.startswith("help")}
    per_round_help = [h / n for h, n in zip(times["help"], times["import_numpy"], strict=True)]
    per_round_fit = [f / w for f, w in zip(times["fit"], warm, strict=True)]
    return {
        "median_cpu_s": med,
        "help_over_import_numpy": helps["help"],
        "every_help_over_import_numpy": helps,
        "worst_help_over_import_numpy": max(helps.values()),
        "fit_over_warm_fit": med["fit"] / med["warm_fit"],
        # the same ratios round by round (each round's runs close in time)
        "help_over_import_numpy_median_of_rounds": statistics.median(per_round_help),
        "fit_over_warm_fit_median_of_rounds": statistics.median(per_round_fit),
        # what no change of the package's start-up can remove, over the warm fit
        "import_floor_over_warm_fit": med["import_floor"] / med["warm_fit"],
        "import_floor_frozen_over_warm_fit": med["import_floor_frozen"] / med["warm_fit"],
        "import_fit_over_warm_fit": med["import_fit"] / med["warm_fit"],
        # where the floor's time goes (BREAKDOWN), each over the warm fit
        "breakdown_over_warm_fit": {name: med[name] / med["warm_fit"] for name in BREAKDOWN},
        "goal_every_help_within_1_3x": max(helps.values()) <= 1.3,
        "goal_fit_within_4x": med["fit"] / med["warm_fit"] <= 4.0,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="rounds (median over them)")
    parser.add_argument("--run", type=Path, default=RUN, help="the run to fit")
    parser.add_argument("--baseline", type=Path, help="a worktree of an older commit")
    parser.add_argument("--output", default="cli_startup", help="results/<OUTPUT>.json")
    parser.add_argument(
        "--fit-args",
        default="",
        help='options of the fit command (one string, e.g. "--law coulomb+quadratic"); '
        "the warm fit is then the command itself run in the worker",
    )
    args = parser.parse_args()
    options = shlex.split(args.fit_args)

    trees = {"current": REPO}
    if args.baseline is not None:
        trees["baseline"] = args.baseline.resolve()
    run = args.run.resolve()
    cmds = commands(run, options)
    cpu: dict[str, dict[str, list[float]]] = {t: {c: [] for c in cmds} for t in trees}
    wall: dict[str, dict[str, list[float]]] = {t: {c: [] for c in cmds} for t in trees}
    warm_cpu: dict[str, list[float]] = {t: [] for t in trees}
    warm_wall: dict[str, list[float]] = {t: [] for t in trees}
    outputs: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as cwd:
        for name, tree in trees.items():
            compileall.compile_dir(str(tree / "bayestribo"), quiet=1)
            for cmd in cmds.values():  # warm numba's caches, check the commands work
                _, _, done = _timed(cmd, tree, cwd)
                if done.returncode not in (0, 1):
                    raise SystemExit(f"{name}: {cmd[3:]} failed:\n{done.stderr}")
            _, _, done = _timed(cmds["fit"], tree, cwd)
            outputs[name] = done.stdout
        workers = {name: WarmFit(tree, run, cwd, options) for name, tree in trees.items()}
        load = []
        try:
            order = random.Random(0)
            for _ in range(args.repeats):
                load.append(os.getloadavg()[0])
                # every command of every tree once, in a new random order each round:
                # no command always runs first, after the fits, or next to another
                jobs = [(c, t) for c in [*cmds, "warm_fit"] for t in trees]
                order.shuffle(jobs)
                for cmd_name, name in jobs:
                    if cmd_name == "warm_fit":
                        seconds, wall_s = workers[name].once()
                        warm_cpu[name].append(seconds)
                        warm_wall[name].append(wall_s)
                    else:
                        seconds, wall_s, _ = _timed(cmds[cmd_name], trees[name], cwd)
                        cpu[name][cmd_name].append(seconds)
                        wall[name][cmd_name].append(wall_s)
        finally:
            for worker in workers.values():
                worker.close()

    results: dict[str, Any] = {
        "run": str(run.relative_to(REPO)) if run.is_relative_to(REPO) else str(run),
        "repeats": args.repeats,
        "timing": "CPU time (user + system) of each fresh process, and of the worker during "
        "a warm fit; ratios from the medians of CPU times; wall times kept beside them",
        "commands": {
            "help": "bayestribo --help",
            **{f"help_{sub}": f"bayestribo {sub} --help" for sub in COMMANDS},
            "import_numpy": 'python -c "import numpy"',
            "fit": " ".join(["bayestribo fit", run.name, *options]),
            "import_fit_libraries": f'python -c "{FLOOR}"',
            "import_floor": f'python -c "{FLOOR_NO_SIGNAL}"',
            "import_floor_frozen": f'python -c "{FLOOR_FROZEN}"',
            "import_fit": f'python -c "{FIT_IMPORTS}"',
            **{name: f'python -c "{code}"' for name, code in BREAKDOWN.items()},
            "warm_fit": (
                "bayestribo.fit(RUN) in a process that fitted it before"
                if not options
                else "the fit command run in a process that ran it before, its text discarded"
            ),
        },
        "bytecode": "compiled before the rounds (compileall); PYTHONDONTWRITEBYTECODE="
        + os.environ.get("PYTHONDONTWRITEBYTECODE", ""),
        "load_average_1min": {"min": min(load), "max": max(load)},
        "trees": {},
    }
    print(f"median CPU time of {args.repeats} rounds [s]; run {run.name}")
    header = f"{'':10}{'--help':>9}{'worst':>7}{'numpy':>9}{'ratio':>7}{'fit':>9}{'warm fit':>10}"
    print(header + f"{'ratio':>7}{'fit libs':>10}{'floor':>8}{'frozen':>8}{'fit imp':>9}")
    for name, tree in trees.items():
        out = _ratios(cpu[name], warm_cpu[name])
        med = out["median_cpu_s"]
        results["trees"][name] = {
            "path": str(tree),
            "commit": subprocess.run(
                ["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                capture_output=True,
                text=True,
            ).stdout.strip(),
            **out,
            "samples_cpu_s": {**cpu[name], "warm_fit": warm_cpu[name]},
            "median_wall_s": {
                **{c: statistics.median(v) for c, v in wall[name].items()},
                "warm_fit": statistics.median(warm_wall[name]),
            },
            "samples_wall_s": {**wall[name], "warm_fit": warm_wall[name]},
        }
        print(
            f"{name:10}{med['help']:9.3f}{out['worst_help_over_import_numpy']:7.2f}"
            f"{med['import_numpy']:9.3f}{out['help_over_import_numpy']:7.2f}"
            f"{med['fit']:9.3f}{med['warm_fit']:10.3f}{out['fit_over_warm_fit']:7.2f}"
            f"{med['import_fit_libraries']:10.3f}{med['import_floor']:8.3f}"
            f"{med['import_floor_frozen']:8.3f}{med['import_fit']:9.3f}"
        )
        print(
            "  breakdown [s]: "
            + ", ".join(f"{n.removeprefix('import_')} {med[n]:.3f}" for n in BREAKDOWN)
        )
    if "baseline" in trees:
        cur, base = results["trees"]["current"], results["trees"]["baseline"]
        results["baseline_over_current"] = {
            c: base["median_cpu_s"][c] / cur["median_cpu_s"][c] for c in cur["median_cpu_s"]
        }
        results["same_fit_output"] = outputs["current"] == outputs["baseline"]
        print(
            f"baseline / current: --help {results['baseline_over_current']['help']:.2f}×, "
            f"fit {results['baseline_over_current']['fit']:.2f}×; "
            f"same fit output: {results['same_fit_output']}"
        )
    path = write_results(args.output, results)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
