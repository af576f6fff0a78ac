"""Where ``fit(law="auto")`` spends its CPU time on the paper's rig sticking after a few
oscillations (``short_checks.py``'s ``stop-<mu>`` records).

Each record is fitted twice with the default law and ``--repeats`` times with
``law="auto"`` (seed 0) in one process, each timed in process CPU time (the first
``auto`` fit of a process also imports ArviZ and compiles its numba functions); the
comparison's progress lines are stamped with the CPU time since the fit began. With
``--stats PATH`` each ``auto`` fit runs under :mod:`cProfile` and its profile is
written to ``PATH-<mu>-<repeat>.prof`` (the profiler inflates Python-heavy stages).

Run: ``python benchmarks/auto_stop_profile.py --mu 0.3 0.1 0.2 [--output NAME]``;
writes ``benchmarks/results/<output>.json`` (with the commit of the package imported,
so that ``PYTHONPATH`` on another tree times that tree): per record the CPU times, the verdict, its
adequacy and the chosen law's posterior mean and sd of each parameter.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
import warnings
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import commit, write_results  # noqa: E402
from short_checks import stop  # noqa: E402


def profile_one(mu: float, stats_path: str | None, repeats: int = 2) -> dict[str, Any]:
    """Profile ``auto`` and time the default fit on ``stop(mu)``."""
    from bayestribo import fit

    run = stop(mu)
    lines: list[tuple[float, str]] = []
    t0 = time.process_time()

    def progress(text: str) -> None:
        lines.append((round(time.process_time() - t0, 2), text))
        print(f"[{lines[-1][0]:8.2f} s CPU] {text}", flush=True)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        default_cpu = []
        for _ in range(2):
            c0 = time.process_time()
            fit(run, seed=0)
            default_cpu.append(time.process_time() - c0)
        auto_cpu, progress_lines = [], []
        for repeat in range(repeats):
            lines = []
            profiler = cProfile.Profile(time.process_time) if stats_path else None
            t0 = time.process_time()
            if profiler is not None:
                result = profiler.runcall(fit, run, law="auto", seed=0, law_progress=progress)
            else:
                result = fit(run, law="auto", seed=0, law_progress=progress)
            auto_cpu.append(time.process_time() - t0)
            progress_lines.append(lines)
            if profiler is not None:
                pstats.Stats(profiler).dump_stats(f"{stats_path}-{repeat}.prof")
    comparison = result.law_comparison or {}
    return {
        "mu_k": mu,
        "default_cpu_s": [round(c, 3) for c in default_cpu],
        "auto_cpu_s": [round(c, 2) for c in auto_cpu],
        "auto_over_default": [round(c / default_cpu[-1], 1) for c in auto_cpu],
        "verdict": comparison.get("verdict"),
        "adequate": comparison.get("adequate"),
        "posterior": {
            n: [float(result.samples(n).mean()), float(result.samples(n).std())]
            for n in result.parameter_names
        },
        "progress": progress_lines,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mu", type=float, nargs="+", default=[0.3])
    parser.add_argument("--stats", default=None, help="write the raw profile here")
    parser.add_argument("--repeats", type=int, default=2, help="auto fits per record")
    parser.add_argument("--output", default=None, help="results/NAME.json")
    args = parser.parse_args(argv)
    rows = []
    for mu in args.mu:
        stats = f"{args.stats}-{mu:g}" if args.stats else None
        rows.append(profile_one(mu, stats, args.repeats))
        print({k: v for k, v in rows[-1].items() if k != "progress"}, flush=True)
    if args.output:
        import bayestribo

        tree = Path(bayestribo.__file__).resolve().parents[1]
        source = {"package": commit(tree), "benchmark": commit()}
        print("wrote", write_results(args.output, {"source": source, "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
