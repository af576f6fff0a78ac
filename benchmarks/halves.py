"""Split-half check calibration: false-alarm and detection rates, and the real recordings.

Simulated tribometer runs (:func:`bayestribo.synthetic.recording.simulate`, the paper's
rig: m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236, μ_k = 0.0294, x₀ = 1.5 mm,
10 kHz, noise at the vibrometer's resolution unless said), checked by
:func:`bayestribo.adequacy.halves.split_halves` at α = 0.05:

* constant law (false alarm, nominal at most 5 %), at the resolution and at 10x the
  noise, with the Kolmogorov-Smirnov p-value of the χ² p-values against uniform and
  the sd of the z of each parameter (1 for an exact test, below 1 for a conservative one);
* a 20 % change of ζ over the decay, ζ(a) = ζ_end (1 + 0.2 a/x₀) (as
  ``benchmarks/adequacy.py``), and the damping ζ(a) = 0.01 + 20 a of
  ``tests/test_inference_fitting.py::test_misfit_is_flagged`` (2 kHz, 10x noise): detection;
* the whole :func:`~bayestribo.adequacy.check_adequacy` verdict on clean runs (its
  false-alarm rate with the four checks together);
* the Bayesian halves (``--bayes-runs``, default 40 per case);
* the AppStat2020 recordings HarmOsc1-3 (position only, arbitrary unit): least
  squares, the Bayesian fit, and the Bayesian fit with the discrepancy term.

Run: ``python benchmarks/halves.py [--runs N] [--bayes-runs M] [--no-real]``; writes
``benchmarks/results/halves.json`` and prints a table.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.stats

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import write_results

from bayestribo.adequacy import check_adequacy
from bayestribo.adequacy.halves import split_halves
from bayestribo.adequacy.windows import BayesianWindows, LeastSquaresWindows
from bayestribo.synthetic import DissipationLaw, Sensor
from bayestribo.synthetic.recording import simulate

ZETA = 0.0236
X0 = 1.5e-3
ALPHA = 0.05
APPSTAT = (
    Path(__file__).resolve().parents[2] / "shared/external-data/appstat2020-harmonic-oscillator"
)


def _interval(k: int, n: int) -> list[float]:
    """Clopper-Pearson 95 % interval of a binomial proportion."""
    lo = 0.0 if k == 0 else float(scipy.stats.beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(scipy.stats.beta.ppf(0.975, k + 1, n - k))
    return [lo, hi]


def _run(kind: str, noise: float, seed: int):
    sensor = Sensor(displacement_noise_m=0.15e-6 * noise, velocity_noise_m_per_s=0.015e-6 * noise)
    if kind == "constant":
        return simulate(DissipationLaw(zeta=ZETA), sensor=sensor, seed=seed)
    if kind == "20%":
        zeta_end = ZETA / 1.1
        return simulate(
            DissipationLaw(zeta=lambda a: zeta_end * (1.0 + 0.2 * a / X0)), sensor=sensor, seed=seed
        )
    return simulate(  # "steep": the misfit test's law
        DissipationLaw(zeta=lambda a: 0.01 + 20.0 * a, mu_k=0.0294),
        sensor=Sensor(
            sample_rate_Hz=2000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=seed,
    )


def _case(name: str, kind: str, noise: float, runs: int, seed0: int, method: str) -> dict:
    flagged, failed = 0, 0
    p_values, z_zeta, z_mu, modes = [], [], [], []
    t0 = time.perf_counter()
    for i in range(runs):
        run = _run(kind, noise, seed0 + i)
        try:
            if method == "verdict":
                report = check_adequacy(run, seed=i)
                flagged += int(not report.adequate)
                continue
            fitter = BayesianWindows() if method == "bayes" else LeastSquaresWindows()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                h = split_halves(run, fitter=fitter, alpha=ALPHA, seed=i)
        except Exception as exc:  # counted and reported, never hidden
            failed += 1
            print(f"  {name} run {i}: {type(exc).__name__}: {exc}", file=sys.stderr)
            continue
        flagged += int(not h.consistent)
        p_values.append(h.p_value)
        z_zeta.append(h.z["zeta"])
        if "mu" in h.z:
            z_mu.append(h.z["mu"])
        modes.append(h.friction_mode)
    done = runs - failed
    return {
        "case": name,
        "method": method,
        "runs": runs,
        "analysed": done,
        "failed": failed,
        "flagged": flagged,
        "rate": flagged / done if done else None,
        "rate_interval_95": _interval(flagged, done) if done else None,
        "ks_p_uniform": float(scipy.stats.kstest(p_values, "uniform").pvalue)
        if len(p_values) > 5
        else None,
        "sd_z_zeta": float(np.std(z_zeta)) if z_zeta else None,
        "sd_z_mu": float(np.std(z_mu)) if z_mu else None,
        "friction_held_fraction": float(np.mean([m == "fixed" for m in modes])) if modes else None,
        "seconds_per_run": (time.perf_counter() - t0) / runs,
    }


def _real(name: str) -> list[dict]:
    from bayestribo import fit, read_run

    path = APPSTAT / name
    if not path.exists():
        print(f"  {name}: not found at {path}", file=sys.stderr)
        return []
    run = read_run(
        path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
    )
    fitters = {
        "least_squares": LeastSquaresWindows(),
        "bayes": BayesianWindows(),
        "bayes+discrepancy": BayesianWindows(
            fit=lambda sub: fit(sub, seed=0, skip_oscillations=0, discrepancy=True)
        ),
    }
    out = []
    for label, fitter in fitters.items():
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                h = split_halves(run, fitter=fitter, alpha=ALPHA)
        except Exception as exc:
            out.append(
                {"recording": name, "method": label, "error": f"{type(exc).__name__}: {exc}"}
            )
            continue
        out.append(
            {
                "recording": name,
                "method": label,
                "consistent": h.consistent,
                "max_abs_z": h.max_abs_z,
                "z": h.z,
                "p_value": h.p_value,
                "friction_mode": h.friction_mode,
                "statement": h.statement,
                "seconds": time.perf_counter() - t0,
            }
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=400)
    parser.add_argument("--verdict-runs", type=int, default=100)
    parser.add_argument("--bayes-runs", type=int, default=40)
    parser.add_argument("--no-real", action="store_true")
    args = parser.parse_args()
    n = args.runs
    cases = [
        _case("constant law, resolution noise (false alarm)", "constant", 1, n, 70_000, "ls"),
        _case("constant law, 10x noise (false alarm)", "constant", 10, n, 71_000, "ls"),
        _case("20 % change of zeta, resolution noise (detection)", "20%", 1, n, 72_000, "ls"),
        _case("20 % change of zeta, 10x noise (detection)", "20%", 10, n, 73_000, "ls"),
        _case("zeta = 0.01 + 20 a, 2 kHz (detection)", "steep", 1, n, 74_000, "ls"),
    ]
    if args.verdict_runs > 0:
        cases.append(
            _case(
                "check_adequacy verdict, constant law (false alarm)",
                "constant",
                1,
                args.verdict_runs,
                75_000,
                "verdict",
            )
        )
    if args.bayes_runs > 0:
        b = args.bayes_runs
        cases += [
            _case("Bayesian halves, constant law (false alarm)", "constant", 1, b, 76_000, "bayes"),
            _case("Bayesian halves, 20 % change of zeta (detection)", "20%", 1, b, 77_000, "bayes"),
        ]
    print(
        f"{'case':55s} {'meth':>7s} {'runs':>5s} {'flag':>5s} {'rate':>6s} {'95 % interval':>15s}"
        f" {'KS p':>8s} {'sd z_ζ':>7s} {'s/run':>6s}"
    )
    for c in cases:
        lo, hi = c["rate_interval_95"] or (float("nan"), float("nan"))
        ks = "-" if c["ks_p_uniform"] is None else f"{c['ks_p_uniform']:.1e}"
        sdz = "-" if c["sd_z_zeta"] is None else f"{c['sd_z_zeta']:.2f}"
        print(
            f"{c['case']:55s} {c['method']:>7s} {c['analysed']:5d} {c['flagged']:5d} "
            f"{c['rate']:6.3f} {lo:6.3f}-{hi:<8.3f} {ks:>8s} {sdz:>7s} {c['seconds_per_run']:6.2f}"
        )
    real = []
    if not args.no_real:
        for name in ("HarmOsc1.txt", "HarmOsc2.txt", "HarmOsc3.txt"):
            real += _real(name)
        for r in real:
            if "error" in r:
                print(f"{r['recording']:14s} {r['method']:18s} {r['error']}")
            else:
                print(
                    f"{r['recording']:14s} {r['method']:18s} "
                    f"{'agree' if r['consistent'] else 'DISAGREE':9s} max|z| {r['max_abs_z']:7.1f}"
                    f"  p {r['p_value']:.2g}  friction {r['friction_mode']}"
                )
    path = write_results(
        "halves",
        {
            "alpha": ALPHA,
            "zeta": ZETA,
            "mu_k": 0.0294,
            "laws": {
                "20%": "zeta(a) = zeta_end (1 + 0.2 a / x0), zeta_end = 0.0236/1.1",
                "steep": "zeta(a) = 0.01 + 20 a, 2 kHz, noise 1.5 µm and 0.15 mm/s",
            },
            "cases": cases,
            "real": real,
        },
    )
    print(f"written {path}")


if __name__ == "__main__":
    main()
