"""Speed of the single-run fit, and the same sampling with a solve_ivp forward model.

1. Wall time of :func:`bayestribo.inference.fit` on the bundled run
   ``data/runs/glycerol-N0.31-r1.csv`` (10 kHz, about 0.5 s of motion), exact model,
   defaults, in one process after a warm-up fit (imports and compilation are timed
   separately as the first call): the median over ``--repeats`` seeds, whether each
   converged, the smallest effective sample size over the parameters, and effective
   samples per second (ESS_min / wall time).
2. The number of log-posterior evaluations one fit makes (walker positions with a
   positive prior density, counted by wrapping the posterior in a separate fit with
   the same seed: optimisation, starting walkers and sampling).
3. The same likelihood with Π computed the direct way: the equation of motion
   integrated half cycle by half cycle with ``solve_ivp`` (DOP853, rtol 1e-9,
   atol 1e-11) and velocity-zero events (:func:`bayestribo.model.reference.ode_solve`),
   then each Π increment by Simpson's rule on the dense output (steps <= 0.02 in τ),
   for ``--ode-evals`` posterior draws,
   one evaluation per draw; the time per evaluation times the count of step 2 is the
   time the same sampling would take; its ratio to the fit's wall time is reported.
   The ODE log-likelihood is checked against the closed form's on the same draws.

Run: ``nice -n 10 python benchmarks/fit.py``; writes ``benchmarks/results/fit.json``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.integrate import simpson

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fitsetup import likelihood_of
from _machine import write_results

from bayestribo.inference import fit
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.io import read_run
from bayestribo.model.reference import ode_solve

RUN = Path(__file__).resolve().parents[1] / "data" / "runs" / "glycerol-N0.31-r1.csv"


class OdePiLikelihood(PiLikelihood):
    """The fit's likelihood with Π from solve_ivp with events, one draw at a time.

    Each increment ∫_{τ_j}^{τ_{j+1}} E dτ (to the end of motion at most) is
    integrated by Simpson's rule on the ODE's dense output with steps of at most
    ``STEP`` in τ (quadrature error about STEP⁴/180 relative, below the noise).
    """

    STEP = 0.02

    def model_pi(self, zeta, mu_k, mu_s, y0):  # type: ignore[override]
        grid = self.data.tau_grid
        ended = self.data.motion_ended
        rows = np.broadcast_arrays(*(np.ravel(a) for a in (zeta, mu_k, mu_s, y0)))
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

    Posterior.__call__ = counting
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit(RUN, seed=seed)
    finally:
        Posterior.__call__ = original
    return count


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed fits (seeds 1..n)")
    parser.add_argument("--ode-evals", type=int, default=200, help="ODE likelihood evaluations")
    args = parser.parse_args(argv)

    start = time.perf_counter()
    first = fit(RUN, seed=0)
    first_seconds = time.perf_counter() - start
    fits = []
    for seed in range(1, args.repeats + 1):
        start = time.perf_counter()
        result = fit(RUN, seed=seed)
        wall = time.perf_counter() - start
        d = result.diagnostics
        fits.append(
            {
                "seed": seed,
                "seconds": wall,
                "converged": result.converged,
                "ess_min": d["ess_min"],
                "ess_per_second": d["ess_min"] / wall,
                "n_steps": d["n_steps"],
                "autocorr_time_max": d["autocorr_time_max"],
                "acceptance_fraction": d["acceptance_fraction"],
            }
        )
    median_seconds = float(np.median([f["seconds"] for f in fits]))
    evaluations = count_evaluations(seed=1)

    run = read_run(RUN)
    ode_lik = likelihood_of(run, cls=OdePiLikelihood)
    closed_lik = likelihood_of(run)
    names = ["zeta", "mu_k", "mu_s", "y0"]
    draws = {n: first.samples(n) for n in names}
    pick = np.linspace(0, draws["zeta"].size - 1, args.ode_evals).round().astype(int)
    rows = [draws[n][pick][:, None] for n in names]
    start = time.perf_counter()
    ll_ode = np.concatenate(
        [ode_lik.log_likelihood(*(r[i : i + 1] for r in rows)) for i in range(pick.size)]
    )
    ode_per_eval = (time.perf_counter() - start) / pick.size
    ll_closed = closed_lik.log_likelihood(*rows)
    ode_fit_seconds = ode_per_eval * evaluations

    results = {
        "benchmark": "fit",
        "description": __doc__.split("\n\n")[1],
        "run": str(RUN.relative_to(RUN.parents[2])),
        "first_call_seconds": first_seconds,
        "fits": fits,
        "median_seconds": median_seconds,
        "all_converged": all(f["converged"] for f in fits),
        "ess_min": float(min(f["ess_min"] for f in fits)),
        "ess_per_second_median": float(np.median([f["ess_per_second"] for f in fits])),
        "log_posterior_evaluations": evaluations,
        "ode_evaluations_timed": int(pick.size),
        "ode_seconds_per_evaluation": ode_per_eval,
        "ode_fit_seconds_estimate": ode_fit_seconds,
        "ode_over_fit_ratio": ode_fit_seconds / median_seconds,
        "ode_vs_closed_loglik_max_abs_diff": float(np.max(np.abs(ll_ode - ll_closed))),
        "notes": "CPU shared with other jobs; the machine was not idle. Times are wall times.",
    }
    print(f"fit of {results['run']} (exact model, defaults)")
    print(f"  first call (imports, compilation): {first_seconds:8.2f} s")
    for f in fits:
        print(
            f"  seed {f['seed']}: {f['seconds']:6.2f} s, converged {f['converged']}, "
            f"ESS_min {f['ess_min']:.0f}, {f['ess_per_second']:.0f} ESS/s, "
            f"{f['n_steps']} steps"
        )
    print(f"  median wall time                  {median_seconds:8.2f} s")
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
    path = write_results("fit", results)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
