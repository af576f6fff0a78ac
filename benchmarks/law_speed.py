"""Speed of a fit with a dissipation law that has no closed form, against the default fit.

Every fit runs in a worker process of one tree (this file with ``--worker``, with
``PYTHONPATH`` on the tree), so that the current tree and an older commit
(``--baseline``, a git worktree of it, e.g. ``git worktree add /tmp/bt-base 7e2ad24``)
are timed side by side in one run, one fit at a time and alternating between the trees,
the load of a shared machine falling on both alike. Each worker fits every law once
with seed 0 first (imports, compilation and numba's cache are timed apart), then:

* runs: the bundled run ``data/runs/glycerol-N0.31-r1.csv`` and runs simulated with the
  independent simulator of ``benchmarks/_laws_sim.py`` (the cases ``viscous+quadratic``
  and ``coulomb+power`` of ``benchmarks/laws.py``, 10x the vibrometer's resolution),
  written to CSV once and read by both trees;
* laws: the default ``viscous+coulomb`` and each law of
  :func:`bayestribo.inference.comparison.auto_laws` without a closed form (``--laws``);
* seeds 1..``--seeds`` for each run and law.

Reported per fit: wall time of :func:`bayestribo.inference.fit`; ESS_min and ESS per
second; the number of log-posterior evaluations (rows with a positive prior density
through :class:`~bayestribo.inference.posterior.Posterior`, its standardized residuals,
and the walkers of each split of the compiled sampler step) and the time per evaluation (time in
those calls over their count); the time in the MAP (``maximum_a_posteriori`` and
``refine``, both frames of a reframed fit), in drawing the starting walkers, in
sampling, and in the law's Π (``Law.pi_grid``: the closed form or the compiled
integrator); the load averages before and after. Per tree, run and law: the medians over
the seeds, and the ratio of each law's median wall time to the default law's on the
same run (the accepted goal: a law without a closed form within 3x); per run and law
across the trees, the ratio of the medians and the posterior means of every sampled
parameter against each other in units of the baseline's posterior sd (mean over seeds).

``--profile``: cProfile of one fit of each law on the bundled run (current tree, in this
process, after a warm-up), the 25 functions with the most cumulative time; and the time
per parameter set of the law's Π at the MAP (the compiled kernel alone, 16 rows per
call).

Run: ``python benchmarks/law_speed.py --baseline /tmp/bt-base --profile``; writes
``benchmarks/results/law_speed.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RUN = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
DEFAULT = "viscous+coulomb"
#: The laws of auto_laws() without a closed form (as of this benchmark's writing).
LAWS = (
    "viscous+quadratic",
    "viscous+coulomb+quadratic",
    "coulomb+hysteretic",
    "coulomb+power",
)
#: Simulated runs: cases of benchmarks/laws.py.
SIMULATED = ("viscous+quadratic", "coulomb+power")
NOISE = 10.0


# -- the worker -------------------------------------------------------------------------


class _Meter:
    """Wall time and calls of the fit's stages, by wrapping the functions that do them."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.seconds: dict[str, float] = {}
        self.rows = 0
        self.eval_seconds = 0.0
        self.pi_rows = 0
        self.depth: dict[str, int] = {}

    def timed(self, key: str, func: Any) -> Any:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            outer = self.depth.get(key, 0) == 0
            self.depth[key] = self.depth.get(key, 0) + 1
            start = time.perf_counter()
            try:
                return func(*args, **kwargs)
            finally:
                self.depth[key] -= 1
                if outer:
                    self.seconds[key] = self.seconds.get(key, 0.0) + time.perf_counter() - start

        wrapper.__wrapped__ = func  # type: ignore[attr-defined]
        return wrapper


def _instrument(meter: _Meter) -> None:
    from bayestribo.inference import chains, law_frame, start
    from bayestribo.inference.posterior import Posterior
    from bayestribo.model.laws.law import Law

    for module in (chains, law_frame, start):
        for name in ("maximum_a_posteriori", "refine"):
            if hasattr(module, name):
                setattr(module, name, meter.timed("map", getattr(start, name)))
    chains.initial_walkers = meter.timed("walkers", start.initial_walkers)
    chains.run_or_failure = meter.timed("sampling", chains.run_or_failure)
    Law.pi_grid = meter.timed("pi", Law.pi_grid)

    def counted(func: Any) -> Any:
        def wrapper(self: Any, theta: Any, *args: Any, **kwargs: Any) -> Any:
            rows = np.atleast_2d(np.asarray(theta, dtype=float))
            ok = int(np.sum(np.isfinite(self.priors.logpdf(rows))))
            begin = time.perf_counter()
            try:
                return func(self, theta, *args, **kwargs)
            finally:
                meter.rows += ok
                meter.eval_seconds += time.perf_counter() - begin

        return wrapper

    Posterior.__call__ = counted(Posterior.__call__)
    Posterior.standardized_residuals = counted(Posterior.standardized_residuals)

    from bayestribo.inference import posterior as posterior_module

    step = posterior_module.grouped_step

    def stepped(fused: Any, kind: int, coords: Any, *args: Any) -> Any:
        begin = time.perf_counter()
        done = step(fused, kind, coords, *args)
        # the splits it completed (the rest go through __call__): walkers of each
        uniform = args[2]
        meter.rows += int(done) * int(uniform.shape[1]) * int(uniform.shape[2])
        meter.eval_seconds += time.perf_counter() - begin
        return done

    posterior_module.grouped_step = stepped


def worker() -> int:
    """Fit one request per line of stdin, one JSON line of results per fit on stdout."""
    import bayestribo
    from bayestribo.inference import fit

    meter = _Meter()
    _instrument(meter)
    print(json.dumps({"ready": True, "module": bayestribo.__file__}), flush=True)
    for line in sys.stdin:
        request = json.loads(line)
        meter.reset()
        load_before = os.getloadavg()
        begin = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(request["path"], seed=int(request["seed"]), law=request["law"])
        seconds = time.perf_counter() - begin
        d = result.diagnostics
        names = list(d["map"])
        steps = int(d["n_steps"])
        walkers = int(d["n_walkers"]) * int(d["n_ensembles"])
        rows = meter.rows
        sampling = meter.seconds.get("sampling", 0.0)
        eval_seconds = meter.eval_seconds
        out = {
            "law": request["law"],
            "seed": request["seed"],
            "seconds": seconds,
            "converged": bool(result.converged),
            "ess_min": float(d["ess_min"]),
            "ess_per_second": float(d["ess_min"]) / seconds,
            "n_steps": steps,
            "n_walkers": walkers,
            "evaluations": rows,
            "seconds_per_evaluation": eval_seconds / rows if rows else float("nan"),
            "map_seconds": meter.seconds.get("map", 0.0),
            "walkers_seconds": meter.seconds.get("walkers", 0.0),
            "sampling_seconds": sampling,
            "pi_seconds": meter.seconds.get("pi", 0.0),
            "mean": {n: float(np.mean(result.samples(n))) for n in names},
            "sd": {n: float(np.std(result.samples(n), ddof=1)) for n in names},
            "load_before": list(load_before),
            "load_after": list(os.getloadavg()),
        }
        print(json.dumps(out), flush=True)
    return 0


class Worker:
    """A fitting process of one tree, driven line by line."""

    def __init__(self, tree: Path) -> None:
        env = {**os.environ, "PYTHONPATH": str(tree)}
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env[var] = "1"
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), "--worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
            cwd=tempfile.gettempdir(),
        )
        self.module = json.loads(self._line())["module"]
        if not self.module.startswith(str(tree)):
            raise RuntimeError(f"the worker for {tree} imported {self.module}")

    def _line(self) -> str:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"worker exited with {self.proc.wait()}")
        return line

    def fit(self, path: Path, seed: int, law: str) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps({"path": str(path), "seed": seed, "law": law}) + "\n")
        self.proc.stdin.flush()
        return json.loads(self._line())

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


# -- the runs ---------------------------------------------------------------------------


def simulated_runs(folder: Path) -> list[dict[str, Any]]:
    """The simulated runs of :data:`SIMULATED`, written as CSV into ``folder``."""
    sys.path.insert(0, str(HERE))
    from laws import case_record

    from bayestribo.io import write_run

    out = []
    for i, case in enumerate(SIMULATED):
        run, facts = case_record(case, NOISE, [2024, i])
        path = write_run(run, folder / f"sim-{case.replace('+', '_')}.csv")
        out.append({"name": f"simulated {case}", "path": str(path), "facts": facts})
    return out


def _summary(fits: list[dict[str, Any]]) -> dict[str, Any]:
    def med(key: str) -> float:
        return float(np.median([f[key] for f in fits]))

    return {
        "median_seconds": med("seconds"),
        "min_seconds": float(np.min([f["seconds"] for f in fits])),
        "median_ess_min": med("ess_min"),
        "median_ess_per_second": med("ess_per_second"),
        "median_steps": med("n_steps"),
        "median_evaluations": med("evaluations"),
        "median_seconds_per_evaluation": med("seconds_per_evaluation"),
        "median_map_seconds": med("map_seconds"),
        "median_walkers_seconds": med("walkers_seconds"),
        "median_sampling_seconds": med("sampling_seconds"),
        "median_pi_seconds": med("pi_seconds"),
        "converged": int(sum(f["converged"] for f in fits)),
        "fits": len(fits),
        "median_load_1min": float(np.median([f["load_before"][0] for f in fits])),
    }


def _agreement(old: list[dict[str, Any]], new: list[dict[str, Any]]) -> dict[str, float]:
    """|mean over seeds of the new posterior means − the old| in the old posterior sd."""
    out = {}
    for p in old[0]["mean"]:
        if not all(p in f["mean"] for f in new):
            continue
        sd = float(np.mean([f["sd"][p] for f in old]))
        diff = np.mean([f["mean"][p] for f in new]) - np.mean([f["mean"][p] for f in old])
        out[p] = float(abs(diff) / sd) if sd > 0 else float("nan")
    return out


def side_by_side(
    trees: dict[str, Path], runs: list[dict[str, Any]], laws: list[str], seeds: int
) -> dict[str, Any]:
    """Every (tree, run, law, seed) fit, alternating between the trees."""
    workers = {name: Worker(tree) for name, tree in trees.items()}
    fits: dict[str, dict[str, dict[str, list]]] = {name: {} for name in trees}
    first: dict[str, dict[str, float]] = {name: {} for name in trees}
    try:
        for name, w in workers.items():
            for law in laws:
                first[name][law] = w.fit(RUN, 0, law)["seconds"]
        turn = 0
        for run in runs:
            for seed in range(1, seeds + 1):
                for law in laws:
                    turn += 1
                    order = list(workers) if turn % 2 else list(workers)[::-1]
                    for name in order:
                        f = workers[name].fit(Path(run["path"]), seed, law)
                        fits[name].setdefault(run["name"], {}).setdefault(law, []).append(f)
                        print(
                            f"  {run['name'][:30]:30s} {law:26s} seed {seed} {name:8s} "
                            f"{f['seconds']:7.2f} s  ESS {f['ess_min']:5.0f}  evals "
                            f"{f['evaluations']:7d}  {1e6 * f['seconds_per_evaluation']:7.1f} "
                            f"us/eval  MAP {f['map_seconds']:6.2f} s  load "
                            f"{f['load_before'][0]:.2f}",
                            flush=True,
                        )
    finally:
        for w in workers.values():
            w.close()
    from _machine import commit

    out: dict[str, Any] = {
        "trees": {name: str(tree) for name, tree in trees.items()},
        "modules": {name: w.module for name, w in workers.items()},
        "commits": {
            name: commit(tree, short=True, unknown="unknown") for name, tree in trees.items()
        },
        "first_call_seconds": first,
        "fits": fits,
        "summary": {},
    }
    for name in trees:
        per_run = {}
        for run in runs:
            by_law = {law: _summary(fits[name][run["name"]][law]) for law in laws}
            default = by_law[DEFAULT]["median_seconds"] if DEFAULT in by_law else float("nan")
            for row in by_law.values():
                row["ratio_to_default"] = row["median_seconds"] / default
            per_run[run["name"]] = by_law
        out["summary"][name] = per_run
    if "baseline" in trees:
        compare: dict[str, Any] = {}
        for run in runs:
            for law in laws:
                old = fits["baseline"][run["name"]][law]
                new = fits["current"][run["name"]][law]
                compare.setdefault(run["name"], {})[law] = {
                    "speedup_of_medians": float(
                        np.median([f["seconds"] for f in old])
                        / np.median([f["seconds"] for f in new])
                    ),
                    "posterior_mean_difference_in_sd": _agreement(old, new),
                }
        out["current_vs_baseline"] = compare
    return out


# -- profiles ---------------------------------------------------------------------------


def profiles(laws: list[str]) -> dict[str, Any]:
    """cProfile of one fit per law and the compiled Π's time per parameter set."""
    import cProfile
    import io
    import pstats

    from bayestribo.inference import fit
    from bayestribo.inference.pipeline import build_posterior, prepare
    from bayestribo.inference.start import maximum_a_posteriori

    out: dict[str, Any] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(RUN)
        for law in laws:
            fit(RUN, seed=0, law=law)
            prof = cProfile.Profile()
            prof.enable()
            begin = time.perf_counter()
            fit(RUN, seed=1, law=law)
            wall = time.perf_counter() - begin
            prof.disable()
            text = io.StringIO()
            pstats.Stats(prof, stream=text).sort_stats("cumulative").print_stats(25)
            top = [
                line.strip()
                for line in text.getvalue().splitlines()
                if line.strip() and line.strip()[0].isdigit()
            ]
            posterior = build_posterior(prepared.data, law=law, friction=prepared.contact)
            theta = maximum_a_posteriori(posterior, prepared.decay)[0]
            lik = posterior.likelihood
            params = posterior.physical(np.repeat(theta[None], 16, axis=0))["params"]
            values, y0 = lik.law_values(params)
            tau = lik.data.tau_grid[:-1]
            end = None if lik.data.motion_ended else lik.data.tau_end
            args = (tau, values, y0, lik.data.yp0, end)
            lik.law.pi_grid(*args, reference=lik.reference_amplitude)
            calls = 0
            begin = time.perf_counter()
            while time.perf_counter() - begin < 1.0:
                lik.law.pi_grid(*args, reference=lik.reference_amplitude)
                calls += 1
            per_row = (time.perf_counter() - begin) / calls / 16
            rows_per_s = 0.0
            begin = time.perf_counter()
            n = 0
            while time.perf_counter() - begin < 1.0:
                posterior(np.repeat(theta[None], 16, axis=0))
                n += 16
            rows_per_s = n / (time.perf_counter() - begin)
            out[law] = {
                "fit_seconds": wall,
                "cumulative_top25": top,
                "pi_microseconds_per_set": 1e6 * per_row,
                "log_posterior_microseconds_per_set": 1e6 / rows_per_s,
                "map": dict(zip(posterior.names, map(float, theta), strict=True)),
            }
            print(
                f"  {law:26s} fit {wall:7.2f} s  Π {1e6 * per_row:8.1f} us/set  "
                f"log p {1e6 / rows_per_s:8.1f} us/set",
                flush=True,
            )
    return out


def _table(result: dict[str, Any]) -> None:
    for name, per_run in result["summary"].items():
        print(f"\n{name}: median over seeds")
        print(
            f"  {'run':30s} {'law':26s} {'wall s':>8s} {'x default':>9s} {'ESS':>6s} "
            f"{'ESS/s':>8s} {'evals':>8s} {'us/eval':>8s} {'MAP s':>7s} {'walk s':>7s} "
            f"{'samp s':>7s} {'Π s':>7s}"
        )
        for run, by_law in per_run.items():
            for law, r in by_law.items():
                print(
                    f"  {run[:30]:30s} {law:26s} {r['median_seconds']:8.2f} "
                    f"{r['ratio_to_default']:9.1f} {r['median_ess_min']:6.0f} "
                    f"{r['median_ess_per_second']:8.0f} {r['median_evaluations']:8.0f} "
                    f"{1e6 * r['median_seconds_per_evaluation']:8.1f} "
                    f"{r['median_map_seconds']:7.2f} {r['median_walkers_seconds']:7.2f} "
                    f"{r['median_sampling_seconds']:7.2f} {r['median_pi_seconds']:7.2f}"
                )
    for run, by_law in result.get("current_vs_baseline", {}).items():
        print(f"\ncurrent against baseline, {run}")
        for law, r in by_law.items():
            worst = max(r["posterior_mean_difference_in_sd"].values(), default=float("nan"))
            print(
                f"  {law:26s} speed-up {r['speedup_of_medians']:6.2f}x  posterior means "
                f"within {worst:.2f} sd"
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--baseline", type=Path, help="worktree of the commit to compare with")
    parser.add_argument("--seeds", type=int, default=3, help="timed fits per run and law")
    parser.add_argument("--laws", nargs="*", default=list(LAWS), help="laws besides the default")
    parser.add_argument("--no-simulated", action="store_true", help="the bundled run only")
    parser.add_argument("--profile", action="store_true", help="cProfile and kernel timing")
    parser.add_argument("--output", default="law_speed", help="results/<output>.json")
    args = parser.parse_args(argv)
    if args.worker:
        return worker()
    sys.path.insert(0, str(HERE))
    from _machine import write_results

    laws = [DEFAULT, *[law for law in args.laws if law != DEFAULT]]
    trees = {"current": ROOT}
    if args.baseline is not None:
        trees = {"baseline": args.baseline.resolve(), "current": ROOT}
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        runs = [{"name": "bundled glycerol-N0.31-r1", "path": str(RUN)}]
        if not args.no_simulated:
            runs += simulated_runs(Path(tmp))
        result = side_by_side(trees, runs, laws, args.seeds)
        for run in runs:
            run["path"] = Path(run["path"]).name
    result["runs"] = runs
    if args.profile:
        print("\nprofiles (current tree, bundled run)")
        result["profiles"] = profiles(laws)
    result["load_average_start"] = list(load_start)
    result["load_average_end"] = list(os.getloadavg())
    result["settings"] = {"seeds": args.seeds, "laws": laws, "noise": NOISE}
    _table(result)
    path = write_results(args.output, result)
    print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
