"""Speed of the single-run fit, side by side with an older commit, and with solve_ivp.

0. Side by side with an older version (``--baseline``, a git worktree of that commit,
   e.g. ``git worktree add /tmp/bt-5cfd060 5cfd060``): the current tree and the old
   one each fit in their own process (``_fit_worker.py`` with ``PYTHONPATH`` on the
   tree), one fit at a time and alternating between them, so that the load of a
   shared machine falls on both alike: the bundled run for seeds 1..``--repeats``
   (after a warm-up fit of seed 0 each) and ``--realistic`` simulated runs like the
   coverage benchmark's (2 and 10 kHz, 10× and 50× the vibrometer resolution, the
   magnet pull, an offset and rest segments; written to CSV once and read by both)
   for ``--realistic-seeds`` seeds each. Reported per version: median wall and
   process CPU time, ESS_min and ESS per second, convergence; the ratio of the
   medians; posterior means of ζ, μ_k, μ_s/μ_k and y0 against each other in units
   of the posterior sd (mean over seeds); the load average (1 min) before each fit.
1. Wall time of :func:`bayestribo.inference.fit` on the bundled run
   ``data/runs/glycerol-N0.31-r1.csv`` (10 kHz, about 0.5 s of motion), exact model,
   defaults, in one process after a warm-up fit (imports and compilation are timed
   separately as the first call): the median over ``--repeats`` seeds, whether each
   converged, the smallest effective sample size over the parameters, and effective
   samples per second (ESS_min / wall time).
2. The number of log-posterior evaluations one fit makes (walker positions with a
   positive prior density, counted by wrapping the posterior in a separate fit with
   the same seed, its compiled sampler step off: optimisation, starting walkers and
   sampling).
3. The same likelihood with Π computed the direct way: the equation of motion
   integrated half cycle by half cycle with ``solve_ivp`` (DOP853, rtol 1e-9,
   atol 1e-11) and velocity-zero events (:func:`bayestribo.model.reference.ode_solve`),
   then each Π increment by Simpson's rule on the dense output (steps <= 0.02 in τ),
   for ``--ode-evals`` posterior draws,
   one evaluation per draw; the time per evaluation times the count of step 2 is the
   time the same sampling would take; its ratio to the fit's wall time is reported.
   The ODE log-likelihood is checked against the closed form's on the same draws.
4. ``--sweep``: walkers per ensemble × ensembles on the bundled run (current tree,
   in this process): median wall time, ESS_min and ESS per second.

Run: ``python benchmarks/fit.py --baseline /tmp/bt-5cfd060``; writes
``benchmarks/results/fit.json``.
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
from scipy.integrate import simpson

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fitsetup import likelihood_of
from _machine import commit, write_results

from bayestribo.inference import fit
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.io import read_run
from bayestribo.model.reference import ode_solve

ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
WORKER = Path(__file__).resolve().parent / "_fit_worker.py"
#: (sample rate [Hz], noise in units of the vibrometer resolution) of the realistic runs.
REALISTIC = ((2000.0, 10.0), (2000.0, 50.0), (10000.0, 10.0), (10000.0, 50.0))
COMPARED = ("zeta", "mu_k", "mu_s_ratio", "y0")


class Worker:
    """A fitting process of one tree (``_fit_worker.py``), driven line by line."""

    def __init__(self, tree: Path) -> None:
        env = {**os.environ, "PYTHONPATH": str(tree)}
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env[var] = "1"
        self.proc = subprocess.Popen(
            [sys.executable, str(WORKER)],
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

    def fit(self, path: Path, seed: int) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps({"path": str(path), "seed": seed}) + "\n")
        self.proc.stdin.flush()
        return json.loads(self._line())

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


def realistic_runs(folder: Path, seed: int = 2024) -> list[dict[str, Any]]:
    """Simulate the realistic runs (as the coverage benchmark's) into ``folder``."""
    from bayestribo.io import write_run
    from bayestribo.synthetic import (
        DISPLACEMENT_RESOLUTION_M,
        VELOCITY_RESOLUTION_M_PER_S,
        DissipationLaw,
        Release,
        Sensor,
        simulate,
    )

    out = []
    rng = np.random.default_rng(seed)
    for i, (rate, noise) in enumerate(REALISTIC):
        truth = {
            "zeta": float(rng.uniform(0.01, 0.05)),
            "mu_k": float(rng.uniform(0.01, 0.05)),
            "mu_s_ratio": float(rng.uniform(1.0, 3.0)),
        }
        run = simulate(
            DissipationLaw(
                zeta=truth["zeta"], mu_k=truth["mu_k"], mu_s=truth["mu_k"] * truth["mu_s_ratio"]
            ),
            release=Release(
                initial_displacement_m=float(rng.uniform(1e-3, 2e-3)),
                offset_m=float(rng.uniform(0.0, 5e-4)),
            ),
            sensor=Sensor(
                sample_rate_Hz=rate,
                displacement_noise_m=noise * DISPLACEMENT_RESOLUTION_M,
                velocity_noise_m_per_s=noise * VELOCITY_RESOLUTION_M_PER_S,
                quantise=True,
            ),
            seed=int(rng.integers(2**31)),
        )
        path = write_run(run, folder / f"realistic-{i}-{rate / 1000:g}kHz-{noise:g}x.csv")
        out.append({"path": path, "sample_rate_Hz": rate, "noise_factor": noise, "truth": truth})
    return out


def _summary(fits: list[dict[str, Any]]) -> dict[str, Any]:
    seconds = [f["seconds"] for f in fits]
    cpu = [f.get("cpu_seconds", np.nan) for f in fits]
    return {
        "median_seconds": float(np.median(seconds)),
        "median_cpu_seconds": float(np.median(cpu)),
        "min_cpu_seconds": float(np.min(cpu)),
        "min_seconds": float(np.min(seconds)),
        "max_seconds": float(np.max(seconds)),
        "median_ess_min": float(np.median([f["ess_min"] for f in fits])),
        "smallest_ess_min": float(np.min([f["ess_min"] for f in fits])),
        "median_ess_per_second": float(np.median([f["ess_per_second"] for f in fits])),
        "median_steps": float(np.median([f["n_steps"] for f in fits])),
        "all_converged": all(f["converged"] for f in fits),
        "median_load_1min": float(np.median([f["load_before"][0] for f in fits])),
    }


def _agreement(old: list[dict[str, Any]], new: list[dict[str, Any]]) -> dict[str, float]:
    """|mean over seeds of the new posterior means − the old| in old posterior sds."""
    out = {}
    for p in COMPARED:
        sd = float(np.mean([f["sd"][p] for f in old]))
        diff = np.mean([f["mean"][p] for f in new]) - np.mean([f["mean"][p] for f in old])
        out[p] = float(abs(diff) / sd)
    return out


def side_by_side(baseline: Path, repeats: int, realistic: int, seeds: int) -> dict[str, Any]:
    """Section 0 of the module notes."""
    trees = {"baseline": baseline, "current": ROOT}
    workers = {name: Worker(tree) for name, tree in trees.items()}
    fits: dict[str, dict[str, list[dict[str, Any]]]] = {"bundled": {}, "realistic": {}}
    try:
        first = {name: w.fit(RUN, 0) for name, w in workers.items()}

        def both(path: Path, seed: int, key: str, turn: int) -> None:
            order = list(workers) if turn % 2 else list(workers)[::-1]
            for name in order:
                fit = workers[name].fit(path, seed)
                fits[key].setdefault(name, []).append({**fit, "path": Path(path).name})
                print(
                    f"  {key:9s} {Path(path).name[:28]:28s} seed {seed} {name:8s} "
                    f"{fit['seconds']:6.3f} s (CPU {fit['cpu_seconds']:6.3f} s) "
                    f"ESS {fit['ess_min']:5.0f} "
                    f"steps {fit['n_steps']:5d} load {fit['load_before'][0]:.2f}",
                    flush=True,
                )

        for seed in range(1, repeats + 1):
            both(RUN, seed, "bundled", seed)
        with tempfile.TemporaryDirectory() as tmp:
            runs = realistic_runs(Path(tmp))[:realistic]
            turn = 0
            for run in runs:
                for seed in range(1, seeds + 1):
                    turn += 1
                    both(run["path"], seed, "realistic", turn)
            for run in runs:
                run["path"] = Path(run["path"]).name
    finally:
        for w in workers.values():
            w.close()

    out: dict[str, Any] = {
        "baseline_tree": str(baseline),
        "commits": {
            name: commit(tree, short=True, unknown="unknown") for name, tree in trees.items()
        },
        "modules": {name: w.module for name, w in workers.items()},
        "first_call_seconds": {name: f["seconds"] for name, f in first.items()},
    }
    for key in ("bundled", "realistic"):
        if not fits[key]:
            continue  # --realistic 0
        per = {name: _summary(f) for name, f in fits[key].items()}
        ratio = per["baseline"]["median_seconds"] / per["current"]["median_seconds"]
        cpu_ratio = per["baseline"]["median_cpu_seconds"] / per["current"]["median_cpu_seconds"]
        out[key] = {
            "fits": fits[key],
            "summary": per,
            "speedup_of_medians": ratio,
            "cpu_speedup_of_medians": cpu_ratio,
            "ess_per_second_ratio": per["current"]["median_ess_per_second"]
            / per["baseline"]["median_ess_per_second"],
        }
    out["bundled"]["posterior_mean_difference_in_sd"] = _agreement(
        fits["bundled"]["baseline"], fits["bundled"]["current"]
    )
    if not runs:
        return out
    by_run: dict[str, Any] = {}
    for run in runs:
        name = run["path"]
        old = [f for f in fits["realistic"]["baseline"] if f["path"] == name]
        new = [f for f in fits["realistic"]["current"] if f["path"] == name]
        by_run[name] = {
            **run,
            "baseline_median_seconds": float(np.median([f["seconds"] for f in old])),
            "current_median_seconds": float(np.median([f["seconds"] for f in new])),
            "posterior_mean_difference_in_sd": _agreement(old, new),
        }
    out["realistic"]["runs"] = by_run
    # Per-run ratios of the medians: the runs differ far more than the versions.
    out["realistic"]["median_of_per_run_speedups"] = float(
        np.median(
            [r["baseline_median_seconds"] / r["current_median_seconds"] for r in by_run.values()]
        )
    )
    return out


def walker_sweep(seeds: int) -> list[dict[str, Any]]:
    """Section 4 of the module notes."""
    rows = []
    for walkers, ensembles in ((8, 2), (12, 2), (16, 2), (8, 4), (24, 2), (32, 2), (16, 4)):
        fits = []
        for seed in range(1, seeds + 1):
            start = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = fit(RUN, seed=seed, n_walkers=walkers, n_ensembles=ensembles)
            wall = time.perf_counter() - start
            d = result.diagnostics
            fits.append((wall, d["ess_min"], d["n_steps"], result.converged))
        a = np.array(fits, dtype=float)
        row = {
            "n_walkers": walkers,
            "n_ensembles": ensembles,
            "median_seconds": float(np.median(a[:, 0])),
            "median_ess_min": float(np.median(a[:, 1])),
            "median_ess_per_second": float(np.median(a[:, 1] / a[:, 0])),
            "median_steps": float(np.median(a[:, 2])),
            "converged": int(a[:, 3].sum()),
            "fits": seeds,
            "load_1min": os.getloadavg()[0],
        }
        print(
            f"  {walkers:3d} walkers × {ensembles} ensembles: {row['median_seconds']:.3f} s, "
            f"ESS {row['median_ess_min']:.0f}, {row['median_ess_per_second']:.0f} ESS/s, "
            f"{row['converged']}/{seeds} converged",
            flush=True,
        )
        rows.append(row)
    return rows


class OdePiLikelihood(PiLikelihood):
    """The fit's likelihood with Π from solve_ivp with events, one draw at a time.

    Each increment ∫_{τ_j}^{τ_{j+1}} E dτ (to the end of motion at most) is
    integrated by Simpson's rule on the ODE's dense output with steps of at most
    ``STEP`` in τ (quadrature error about STEP⁴/180 relative, below the noise).
    """

    STEP = 0.02

    def model_pi(self, params):  # type: ignore[override]
        grid = self.data.tau_grid
        ended = self.data.motion_ended
        mu_k = np.ravel(params["mu_k"])
        mu_s = mu_k * np.ravel(params["mu_s_ratio"])
        rows = np.broadcast_arrays(
            *(np.ravel(a) for a in (params["zeta"], mu_k, mu_s, params["y0"]))
        )
        out = np.empty((rows[0].size, grid.size - 1))
        for i, (z, m, s, y) in enumerate(zip(*rows, strict=True)):
            sol = ode_solve(
                float(y),
                float(z),
                float(m),
                float(s),
                self.data.yp0,
                tau_max=np.inf if ended else float(grid[-1]),
                rtol=1e-10,
                atol=1e-12,
            )
            edges = grid.copy()
            if ended:
                edges[-1] = max(sol.stop_time, edges[-2])  # the model's own end of motion
            edges = np.minimum(edges, sol.stop_time)
            n = 2 * np.maximum(1, np.ceil(np.diff(edges) / (2 * self.STEP)).astype(int))
            increments = np.array(
                [
                    simpson(sol.energy(np.linspace(a, b, k + 1)), dx=(b - a) / k) if b > a else 0.0
                    for a, b, k in zip(edges[:-1], edges[1:], n, strict=True)
                ]
            )
            out[i] = np.cumsum(increments[::-1])[::-1]
        return out


def count_evaluations(seed: int) -> int:
    """Walker positions with a positive prior density evaluated by one fit."""
    original = Posterior.__call__
    count = 0

    def counting(self, theta):
        nonlocal count
        theta2 = np.atleast_2d(np.asarray(theta, dtype=float))
        count += int(np.sum(np.isfinite(self.priors.logpdf(theta2))))
        return original(self, theta)

    # Without the compiled sampler step every split goes through __call__ (the chains
    # are the same to the bit, tests/test_inference_fused_step.py).
    step = Posterior.grouped_step
    Posterior.__call__ = counting
    Posterior.grouped_step = property(lambda self: None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit(RUN, seed=seed)
    finally:
        Posterior.__call__ = original
        Posterior.grouped_step = step
    return count


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7, help="timed fits (seeds 1..n)")
    parser.add_argument("--ode-evals", type=int, default=200, help="ODE likelihood evaluations")
    parser.add_argument("--baseline", type=Path, help="worktree of the commit to compare with")
    parser.add_argument("--realistic", type=int, default=4, help="realistic runs (at most 4)")
    parser.add_argument("--realistic-seeds", type=int, default=3, help="fits per realistic run")
    parser.add_argument("--sweep", type=int, default=0, help="seeds per walker setting (0: none)")
    parser.add_argument("--output", default="fit", help="results/<output>.json (default fit)")
    args = parser.parse_args(argv)
    load_start = os.getloadavg()
    compared = None
    if args.baseline is not None:
        print(f"side by side with {args.baseline}")
        compared = side_by_side(args.baseline, args.repeats, args.realistic, args.realistic_seeds)

    start = time.perf_counter()
    first = fit(RUN, seed=0)
    first_seconds = time.perf_counter() - start
    fits = []
    for seed in range(1, args.repeats + 1):
        start, cpu = time.perf_counter(), time.process_time()
        result = fit(RUN, seed=seed)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        d = result.diagnostics
        fits.append(
            {
                "seed": seed,
                "seconds": wall,
                "cpu_seconds": cpu,
                "converged": result.converged,
                "ess_min": d["ess_min"],
                "ess_per_second": d["ess_min"] / wall,
                "n_steps": d["n_steps"],
                "autocorr_time_max": d["autocorr_time_max"],
                "acceptance_fraction": d["acceptance_fraction"],
            }
        )
    median_seconds = float(np.median([f["seconds"] for f in fits]))
    median_cpu_seconds = float(np.median([f["cpu_seconds"] for f in fits]))
    evaluations = count_evaluations(seed=1)

    run = read_run(RUN)
    ode_lik = likelihood_of(run, cls=OdePiLikelihood)
    closed_lik = likelihood_of(run)
    names = ["zeta", "mu_k", "mu_s_ratio", "y0"]
    draws = {n: first.samples(n) for n in names}
    pick = np.linspace(0, draws["zeta"].size - 1, args.ode_evals).round().astype(int)
    rows = {n: draws[n][pick] for n in names}
    start = time.perf_counter()
    ll_ode = np.concatenate(
        [
            ode_lik.log_likelihood({n: v[i : i + 1] for n, v in rows.items()})
            for i in range(pick.size)
        ]
    )
    ode_per_eval = (time.perf_counter() - start) / pick.size
    ll_closed = closed_lik.log_likelihood(rows)
    ode_fit_seconds = ode_per_eval * evaluations

    sweep = walker_sweep(args.sweep) if args.sweep else None
    results = {
        "benchmark": "fit",
        "description": __doc__.split("\n\n")[1],
        "load_average_at_start": list(load_start),
        "load_average_at_end": list(os.getloadavg()),
        "side_by_side": compared,
        "walker_sweep": sweep,
        "run": str(RUN.relative_to(RUN.parents[2])),
        "first_call_seconds": first_seconds,
        "fits": fits,
        "median_seconds": median_seconds,
        "median_cpu_seconds": median_cpu_seconds,
        "all_converged": all(f["converged"] for f in fits),
        "ess_min": float(min(f["ess_min"] for f in fits)),
        "ess_per_second_median": float(np.median([f["ess_per_second"] for f in fits])),
        "log_posterior_evaluations": evaluations,
        "ode_evaluations_timed": int(pick.size),
        "ode_seconds_per_evaluation": ode_per_eval,
        "ode_fit_seconds_estimate": ode_fit_seconds,
        "ode_over_fit_ratio": ode_fit_seconds / median_seconds,
        "ode_vs_closed_loglik_max_abs_diff": float(np.max(np.abs(ll_ode - ll_closed))),
        "notes": (
            "Medians over seeds; 'seconds' are wall times and 'cpu_seconds' this "
            "process's CPU time (on a shared machine the CPU time is the one to "
            "compare; the load averages at start and end say how busy it was). Side by "
            "side, the two versions fit alternately, one at a time, in separate processes."
        ),
    }
    if compared is not None:
        for key in ("bundled", "realistic"):
            c = compared.get(key)
            if c is None:  # --realistic 0
                continue
            for name, v in c["summary"].items():
                print(
                    f"{key:9s} {name:8s} median {v['median_seconds']:6.3f} s "
                    f"(CPU {v['median_cpu_seconds']:6.3f} s), ESS_min median "
                    f"{v['median_ess_min']:.0f} (smallest {v['smallest_ess_min']:.0f}), "
                    f"{v['median_ess_per_second']:.0f} ESS/s, converged {v['all_converged']}, "
                    f"load {v['median_load_1min']:.2f}"
                )
            print(
                f"{key:9s} speedup of medians {c['speedup_of_medians']:.2f}x "
                f"(CPU {c['cpu_speedup_of_medians']:.2f}x), "
                f"ESS/s ratio {c['ess_per_second_ratio']:.2f}x"
            )
        print(
            "posterior means, |new - old| in sd:",
            {
                k: round(v, 3)
                for k, v in compared["bundled"]["posterior_mean_difference_in_sd"].items()
            },
        )
        for name, r in compared.get("realistic", {}).get("runs", {}).items():
            print(
                f"  {name}: {r['baseline_median_seconds']:.2f} s -> "
                f"{r['current_median_seconds']:.2f} s, means in sd "
                f"{ {k: round(v, 3) for k, v in r['posterior_mean_difference_in_sd'].items()} }"
            )
    print(f"fit of {results['run']} (exact model, defaults)")
    print(f"  first call (imports, compilation): {first_seconds:8.2f} s")
    for f in fits:
        print(
            f"  seed {f['seed']}: {f['seconds']:6.3f} s (CPU {f['cpu_seconds']:.3f} s), "
            f"converged {f['converged']}, "
            f"ESS_min {f['ess_min']:.0f}, {f['ess_per_second']:.0f} ESS/s, "
            f"{f['n_steps']} steps"
        )
    print(f"  median wall time                  {median_seconds:8.3f} s")
    print(f"  median CPU time                   {median_cpu_seconds:8.3f} s")
    print(f"  log-posterior evaluations / fit   {evaluations:8d}")
    print(
        f"  solve_ivp likelihood / evaluation {1e3 * ode_per_eval:8.1f} ms "
        f"({pick.size} timed; max |Δ log L| vs closed form "
        f"{results['ode_vs_closed_loglik_max_abs_diff']:.2e})"
    )
    print(
        f"  same sampling with solve_ivp      {ode_fit_seconds:8.0f} s "
        f"= {results['ode_over_fit_ratio']:.0f}x the fit"
    )
    path = write_results(args.output, results)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
