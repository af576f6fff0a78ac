"""Increment variances from the observed channels against the noise-free ones, at 30x.

The white-noise variance of each Π increment (:func:`bayestribo.signal.increments.
increment_noise`) is Σ w² (y²σ_y² + y'²σ_y'² + ½(σ_y⁴ + σ_y'⁴)) with y, y' the
*observed* channels. Two consequences at 30x the vibrometer's resolution, where the
record's tail is below the displacement noise (σ_y ≈ 0.021 of ℓ):

* the observed y² has the mean y² + σ_y², so the tail's variances are about 3 times too
  large (1.5 σ_y⁴ instead of 0.5 σ_y⁴ per sample once y ≪ σ_y): χ²/n below 1;
* the weights depend on the same noise as the increments: an increment whose noise
  raised y² (and its energy) gets a larger variance, one whose noise lowered it a
  smaller one, so the weighted fit leans to low energies at small amplitude: ζ high
  and c₂ low (the sign of benchmarks/results/laws_calibration_30x_vq.json's mean z).

For each run of ``viscous+quadratic`` at 30x (the runs of ``benchmarks/laws.py``, seed
2012, in the true frame Ω) the maximum a posteriori and its Laplace sd are found twice:
with the package's variances, and with the same formula on the noise-free channels of
the simulator (the neighbour covariance kept). z = (MAP - truth) / sd.

``--exact-noise`` gives the package the simulated σ instead of the one measured on the
0.1 s rest (σ² known to ±6.7 %): the noise bias ½σ² removed from every sample is then
exact too.

This measured why the fit needed a second pass: it now computes the variances from
the law's motion at its first optimum and marginalises σ²'s error
(:mod:`bayestribo.inference.reweight`; ``laws_calibration_30x_vq_reweight.json``
holds the package's fits of the same records after it). The "observed" variances
here are the first pass's.

Run: ``python benchmarks/noise_weights.py [--runs 40] [--exact-noise --output
noise_weights_30x_exact_sigma]``; writes ``benchmarks/results/noise_weights_30x.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import laws
from _laws_sim import OMEGA, RESOLUTION_V, RESOLUTION_X
from _machine import commit, write_results

from bayestribo.inference.pipeline import build_posterior, find_optimum, prepare, reframe
from bayestribo.signal.increments import increment_noise, increment_weights

CASE, NOISE = "viscous+quadratic", 30.0


def one_run(
    index: int, seed: int, clean: tuple[np.ndarray, np.ndarray], exact_noise: bool = False
) -> dict:
    """z of ζ and c₂ at the MAP with the observed and the noise-free variances (with
    ``exact_noise``, the simulated noise's σ instead of the one measured at rest, which
    sets the noise bias removed from the increments and the variances)."""
    law, truth, _x0, _kind = laws.CASES[CASE]
    entropy = laws._entropy(CASE, NOISE, index, seed)
    run, _facts = laws.case_record(CASE, NOISE, entropy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        noise = None
        if exact_noise:
            measured = prepare(run).noise
            noise = dataclasses.replace(
                measured,
                displacement=NOISE * RESOLUTION_X,
                velocity=NOISE * RESOLUTION_V,
            )
        prepared = reframe(prepare(run, noise=noise), OMEGA / (2.0 * math.pi))
    data, decay = prepared.data, prepared.decay
    sc = decay.scaling
    idx = np.rint(decay.t * laws.FS).astype(int)
    y_clean = clean[0][idx] / sc.length_scale
    yp_clean = clean[1][idx] / (sc.length_scale * sc.omega)
    h = float(decay.tau[1] - decay.tau[0])
    edges, weights = increment_weights(decay.tau.size, h, data.increments.size)
    sig_y = prepared.noise.displacement / sc.length_scale
    sig_yp = prepared.noise.velocity / (sc.length_scale * sc.omega)
    _, v_obs = increment_noise(decay.tau, decay.y, decay.yp, edges, weights, sig_y, sig_yp)
    _, v_clean = increment_noise(decay.tau, y_clean, yp_clean, edges, weights, sig_y, sig_yp)
    neighbours = data.variance - v_obs  # the shared-sample covariance pi_data added
    truth_values = truth.dimensionless(1.0)
    out: dict = {"index": index, "entropy": entropy, "spectral": bool(data.spectral)}
    quarter = data.increments.size // 4
    out["tail_variance_ratio"] = float(np.mean(v_obs[-quarter:] / v_clean[-quarter:]))
    for label, variance in (("observed", data.variance), ("noise_free", v_clean + neighbours)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = build_posterior(dataclasses.replace(data, variance=variance), law=law)
            theta, cov, _ = find_optimum(post, decay)
        sd = np.sqrt(np.diag(cov))
        resid = post.standardized_residuals(theta[None])[0]
        out[label] = {
            "z": {
                n: float((theta[k] - truth_values[n]) / sd[k])
                for k, n in enumerate(post.names)
                if n in truth_values
            },
            "chi2_per_increment": float(resid @ resid / resid.size),
            "chi2_per_increment_last_quarter": float(resid[-quarter:] @ resid[-quarter:] / quarter),
        }
    return out


def summary(runs: list[dict]) -> dict:
    """Mean and sd of z per parameter and variance, χ²/n pooled."""
    out: dict = {}
    for label in ("observed", "noise_free"):
        rows = {}
        for name in runs[0][label]["z"]:
            z = np.array([r[label]["z"][name] for r in runs])
            rows[name] = {
                "mean_z": float(z.mean()),
                "se_mean": float(z.std(ddof=1) / math.sqrt(z.size)),
                "sd_z": float(z.std(ddof=1)),
                "covered_1.96": int(np.sum(np.abs(z) <= 1.96)),
            }
        rows["chi2_per_increment"] = float(np.mean([r[label]["chi2_per_increment"] for r in runs]))
        rows["chi2_per_increment_last_quarter"] = float(
            np.mean([r[label]["chi2_per_increment_last_quarter"] for r in runs])
        )
        out[label] = rows
    out["tail_variance_ratio"] = float(np.mean([r["tail_variance_ratio"] for r in runs]))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--seed", type=int, default=2012)
    parser.add_argument("--output", default="noise_weights_30x")
    parser.add_argument(
        "--exact-noise",
        action="store_true",
        help="the simulated σ instead of the one measured at rest",
    )
    args = parser.parse_args(argv)
    clean, _f = laws.case_record(CASE, 0.0, 0)  # the noise-free motion
    xc, vc = clean.displacement, clean.velocity
    start = time.perf_counter()
    runs = []
    for i in range(args.runs):
        runs.append(one_run(i, args.seed, (xc, vc), args.exact_noise))
        r = runs[-1]
        print(
            f"{i}: z observed {r['observed']['z']}, noise-free {r['noise_free']['z']}",
            flush=True,
        )
    result = {
        "case": CASE,
        "noise_x_resolution": NOISE,
        "seed": args.seed,
        "exact_noise": args.exact_noise,
        "source": {"commit": commit()},
        "wall_seconds": time.perf_counter() - start,
        "summary": summary(runs),
        "runs": runs,
    }
    path = write_results(args.output, result)
    print(result["summary"])
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
