"""Constancy test calibration: false-alarm and detection rates on simulated runs.

Simulated tribometer runs (:func:`bayestribo.synthetic.recording.simulate`, the paper's rig:
m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236, μ_k = 0.0294, x₀ = 1.5 mm, 10 kHz,
noise at the vibrometer's resolution), analysed by
:func:`bayestribo.adequacy.windowed_fits` (windows of 2 oscillations, least squares)
and :func:`bayestribo.adequacy.constancy_test` at α = 0.05:

* constant law: the fraction of runs flagged "not constant" (false-alarm rate,
  nominal 5 %), with its binomial 95 % interval;
* amplitude-dependent damping: ζ(a) = ζ_end (1 + 0.2 a/x₀), a 20 % change of ζ from
  the initial amplitude to the end of the decay (mean ζ as the paper's): the
  fraction of runs flagged (detection rate, target >= 90 %);
* the same at 10x the noise;
* the peak-by-peak predictive check of the same runs (median fraction of peaks
  inside their 95 % interval, draws from the least-squares covariance);
* a smaller set with the Bayesian fit on windows of 3 oscillations
  (``--bayes-runs``, default 20 per case: a few seconds per window).

Run: ``python benchmarks/adequacy.py [--runs N]`` (least squares, default 120 runs per
case, writes ``benchmarks/results/adequacy.json``) or ``python benchmarks/adequacy.py
--part bayes [--bayes-runs M]`` (writes ``benchmarks/results/adequacy_bayes.json``);
each prints a table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.stats

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import write_results

from bayestribo.adequacy.constancy import constancy_test
from bayestribo.adequacy.draws import draws_from_least_squares
from bayestribo.adequacy.predictive import predictive_check
from bayestribo.adequacy.segments import whole_decay_fit
from bayestribo.adequacy.windows import (
    BayesianWindows,
    LeastSquaresWindows,
    analysed_decay,
    windowed_fits,
)
from bayestribo.synthetic import DissipationLaw, Sensor
from bayestribo.synthetic.recording import simulate

ZETA = 0.0236
X0 = 1.5e-3


def _interval(k: int, n: int) -> list[float]:
    """Clopper-Pearson 95 % interval of a binomial proportion."""
    lo = 0.0 if k == 0 else float(scipy.stats.beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(scipy.stats.beta.ppf(0.975, k + 1, n - k))
    return [lo, hi]


def _case(
    name: str,
    runs: int,
    noise_factor: float,
    dependent: bool,
    seed0: int,
    method: str = "least_squares",
    window: int = 2,
) -> dict:
    flagged = 0
    failed = 0
    changes = []
    coverage = []
    t0 = time.perf_counter()
    zeta_end = ZETA / 1.1  # mean over the amplitudes ≈ the paper's ζ

    def law(a: float) -> float:
        return zeta_end * (1.0 + 0.2 * a / X0)

    for i in range(runs):
        run = simulate(
            DissipationLaw(zeta=law if dependent else ZETA),
            sensor=Sensor(
                displacement_noise_m=0.15e-6 * noise_factor,
                velocity_noise_m_per_s=0.015e-6 * noise_factor,
            ),
            seed=seed0 + i,
        )
        try:
            fitter = BayesianWindows() if method == "bayes" else LeastSquaresWindows()
            test = constancy_test(windowed_fits(run, window=window, fitter=fitter, seed=i))
            if method == "least_squares":
                decay = analysed_decay(run)
                draws = draws_from_least_squares(whole_decay_fit(decay), 200, seed=i)
                coverage.append(predictive_check(decay, draws, seed=i).coverage)
        except Exception as exc:  # counted and reported, never hidden
            failed += 1
            print(f"  {name} run {i}: {type(exc).__name__}: {exc}", file=sys.stderr)
            continue
        flagged += int(not test.constant)
        if test.zeta.relative_change is not None:
            changes.append(test.zeta.relative_change)
    done = runs - failed
    return {
        "case": name,
        "runs": runs,
        "analysed": done,
        "failed": failed,
        "flagged": flagged,
        "rate": flagged / done if done else None,
        "rate_interval_95": _interval(flagged, done) if done else None,
        "median_relative_change_zeta": float(np.median(changes)) if changes else None,
        "method": method,
        "window_oscillations": window,
        "predictive_coverage_median": float(np.median(coverage)) if coverage else None,
        "predictive_coverage_at_least_0.8": float(np.mean(np.array(coverage) >= 0.8))
        if coverage
        else None,
        "seconds_per_run": (time.perf_counter() - t0) / runs,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=120)
    parser.add_argument("--bayes-runs", type=int, default=20)
    parser.add_argument(
        "--part",
        choices=("least_squares", "bayes"),
        default="least_squares",
        help="least-squares windows (adequacy.json) or Bayesian windows (adequacy_bayes.json)",
    )
    args = parser.parse_args()
    if args.part == "bayes":
        args.runs = 0
    else:
        args.bayes_runs = 0
    cases = (
        []
        if args.runs <= 0
        else [
            _case("constant law, resolution noise (false alarm)", args.runs, 1.0, False, 10_000),
            _case(
                "20 % change of zeta, resolution noise (detection)", args.runs, 1.0, True, 20_000
            ),
            _case("constant law, 10x noise (false alarm)", args.runs, 10.0, False, 30_000),
            _case("20 % change of zeta, 10x noise (detection)", args.runs, 10.0, True, 40_000),
        ]
    )
    if args.bayes_runs > 0:
        cases += [
            _case(
                "Bayesian windows of 3, constant law (false alarm)",
                args.bayes_runs,
                1.0,
                False,
                50_000,
                "bayes",
                3,
            ),
            _case(
                "Bayesian windows of 3, 20 % change of zeta (detection)",
                args.bayes_runs,
                1.0,
                True,
                60_000,
                "bayes",
                3,
            ),
        ]
    print(
        f"{'case':55s} {'runs':>5s} {'flagged':>8s} {'rate':>7s} "
        f"{'95 % interval':>16s} {'peaks in 95 %':>14s} {'s/run':>6s}"
    )
    for c in cases:
        if c["rate"] is None:
            print(f"{c['case']:55s} {c['analysed']:5d} (no run analysed: see the errors above)")
            continue
        lo, hi = c["rate_interval_95"]
        cov = c["predictive_coverage_median"]
        cov_text = "-" if cov is None else f"{cov:.2f}"
        print(
            f"{c['case']:55s} {c['analysed']:5d} {c['flagged']:8d} {c['rate']:7.3f} "
            f"{lo:7.3f}-{hi:<8.3f} {cov_text:>14s} {c['seconds_per_run']:6.2f}"
        )
    path = write_results(
        "adequacy" if args.part == "least_squares" else "adequacy_bayes",
        {
            "alpha": 0.05,
            "window_oscillations": 2 if args.part == "least_squares" else 3,
            "zeta": ZETA,
            "mu_k": 0.0294,
            "dependent_law": "zeta(a) = zeta_end (1 + 0.2 a / x0), zeta_end = 0.0236/1.1",
            "cases": cases,
        },
    )
    print(f"written {path}")


if __name__ == "__main__":
    main()
