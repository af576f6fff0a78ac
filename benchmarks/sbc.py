"""Simulation-based calibration of the single-run fit (Talts et al. 2018).

For each replication, the parameters are drawn from the documented prior-like box

* ζ ~ Uniform(0.01, 0.05), μ_k ~ Uniform(0.01, 0.05), μ_s/μ_k from the fit's own
  default prior (:func:`bayestribo.inference.priors.default_priors`, Uniform(1, 10)),

a run is simulated with :func:`bayestribo.simulate` (the paper's rig: m = 0.035 kg,
f = 32.6 Hz, N = 0.31 N, x₀ = 1.5 mm, 10 kHz, an ideal release, white noise on both
channels at a given multiple of the vibrometer resolution 0.15 µm, 0.015 µm/s) and
fitted by :func:`bayestribo.inference.fit` with its default priors. μ_s/μ_k is drawn from
exactly its default prior. The default priors of ζ and μ_k (uniform on [0, 0.3] and
[0, y0/4]) are flat over the box and far wider; the posteriors are narrower than the
box by a factor of 1000 or more, so the posterior under the box-restricted prior (the
one the truth is drawn from) equals the fit's to within the posterior mass that lies
outside the box, which is negligible: the condition under which SBC ranks are uniform
holds. The initial amplitude keeps its default prior and is not ranked. The rank
of the truth among L = 99 posterior draws spread evenly over the thinned chains
(post-burn-in, thinned by the fit, then every k-th draw, about one per
autocorrelation time) is uniform on 0..L when the posterior is calibrated.

Reported per noise level (the resolution, 1x, and 30x) and parameter: the number of
replications, how many converged (only those are ranked), a χ² test of the rank
histogram (20 bins of 5 ranks) against uniformity, a Kolmogorov-Smirnov test of the
randomised normalised ranks, and the rank histograms as a PNG.

Run::

    nice -n 10 python benchmarks/sbc.py --replications 500 --workers 2

Each finished replication is appended to ``benchmarks/results/sbc_replications.jsonl``
(``--resume`` continues a partial run from it; ``--report-only`` rebuilds the summary
from it). Writes ``benchmarks/results/sbc.json`` and ``benchmarks/results/sbc_ranks.png``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import RESULTS, niced_worker, write_results  # noqa: E402

__all__ = ["replicate", "summarise"]


def _mu_s_ratio_prior() -> tuple[float, float]:
    """The fit's default prior of μ_s/μ_k (a uniform's bounds), read from the package."""
    from bayestribo.inference.priors import default_priors

    prior = default_priors(1.0)["mu_s_ratio"]
    return float(prior.low), float(prior.high)


BOX = {"zeta": (0.01, 0.05), "mu_k": (0.01, 0.05), "mu_s_ratio": _mu_s_ratio_prior()}
NOISE_LEVELS = (1.0, 30.0)
RANKED = ("zeta", "mu_k", "mu_s_ratio")
N_DRAWS = 99  # L: ranks take the values 0..L
N_BINS = 20
RAW = RESULTS / "sbc_replications.jsonl"


def replicate(level: float, index: int, seed: int) -> dict[str, Any]:
    """Draw, simulate and fit one replication; rank the truth among posterior draws."""
    from bayestribo.inference import fit
    from bayestribo.synthetic import (
        DISPLACEMENT_RESOLUTION_M,
        VELOCITY_RESOLUTION_M_PER_S,
        DissipationLaw,
        Release,
        Sensor,
        simulate,
    )

    rng = np.random.default_rng([seed, index, int(level * 10)])
    truth = {name: float(rng.uniform(*box)) for name, box in BOX.items()}
    out: dict[str, Any] = {"level": level, "index": index, "truth": truth}
    start = time.perf_counter()
    try:
        run = simulate(
            DissipationLaw(
                zeta=truth["zeta"], mu_k=truth["mu_k"], mu_s=truth["mu_k"] * truth["mu_s_ratio"]
            ),
            release=Release(magnet_fade_s=0.0),
            sensor=Sensor(
                displacement_noise_m=level * DISPLACEMENT_RESOLUTION_M,
                velocity_noise_m_per_s=level * VELOCITY_RESOLUTION_M_PER_S,
            ),
            seed=int(rng.integers(2**31)),
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(run, seed=int(rng.integers(2**31)))
    except Exception as exc:  # recorded, counted, reported: never silently dropped
        out["error"] = f"{type(exc).__name__}: {exc}"
        return out
    out["seconds"] = time.perf_counter() - start
    out["converged"] = result.converged
    out["ranks"] = {}
    out["mean"] = {}
    out["sd"] = {}
    for name in RANKED:
        draws = np.asarray(result.idata.posterior[name]).reshape(-1)
        pick = np.linspace(0, draws.size - 1, N_DRAWS).round().astype(int)
        out["ranks"][name] = int(np.sum(draws[pick] < truth[name]))
        out["mean"][name] = float(np.mean(draws))
        out["sd"][name] = float(np.std(draws, ddof=1))
    return out


def _load(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per level and parameter: counts, rank histogram, χ² and KS uniformity p-values."""
    rng = np.random.default_rng(0)
    levels: dict[str, Any] = {}
    for level in sorted({r["level"] for r in records}):
        rows = [r for r in records if r["level"] == level]
        ok = [r for r in rows if "ranks" in r and r["converged"]]
        entry: dict[str, Any] = {
            "noise_factor": level,
            "replications": len(rows),
            "errors": sum("error" in r for r in rows),
            "not_converged": sum(("ranks" in r) and not r["converged"] for r in rows),
            "ranked": len(ok),
            "median_fit_seconds": float(np.median([r["seconds"] for r in rows if "seconds" in r]))
            if any("seconds" in r for r in rows)
            else None,
            "parameters": {},
        }
        for name in RANKED:
            ranks = np.array([r["ranks"][name] for r in ok], dtype=int)
            hist = np.bincount(ranks * N_BINS // (N_DRAWS + 1), minlength=N_BINS)
            chi2 = stats.chisquare(hist) if ranks.size else None
            u = (ranks + rng.uniform(size=ranks.size)) / (N_DRAWS + 1)
            ks = stats.kstest(u, "uniform") if ranks.size else None
            z = np.array([(r["mean"][name] - r["truth"][name]) / r["sd"][name] for r in ok])
            entry["parameters"][name] = {
                "histogram": hist.tolist(),
                "chi2": None if chi2 is None else float(chi2.statistic),
                "chi2_p": None if chi2 is None else float(chi2.pvalue),
                "ks_p": None if ks is None else float(ks.pvalue),
                "coverage95": float(np.mean((ranks >= 2.5) & (ranks <= N_DRAWS - 2.5)))
                if ranks.size
                else None,
                "mean_z": float(np.mean(z)) if z.size else None,
                "sd_z": float(np.std(z, ddof=1)) if z.size > 1 else None,
            }
        levels[str(level)] = entry
    return levels


def plot(levels: dict[str, Any], path: Path) -> None:
    """Rank histograms with the 99 % band of a uniform histogram."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = {"zeta": "ζ", "mu_k": "μ_k", "mu_s_ratio": "μ_s/μ_k"}
    fig, axes = plt.subplots(
        len(levels), len(RANKED), figsize=(10, 3.2 * len(levels)), squeeze=False
    )
    for i, entry in enumerate(levels.values()):
        n = entry["ranked"]
        lo, hi = stats.binom.ppf([0.005, 0.995], n, 1 / N_BINS)
        for j, name in enumerate(RANKED):
            ax = axes[i, j]
            p = entry["parameters"][name]
            width = (N_DRAWS + 1) / N_BINS
            edges = np.arange(N_BINS) * width
            ax.bar(edges, p["histogram"], width=width, align="edge", color="0.6", edgecolor="k")
            ax.axhspan(lo, hi, color="C0", alpha=0.2, zorder=0, label="99 % band (uniform)")
            ax.axhline(n / N_BINS, color="C0")
            ax.set_title(
                f"{labels[name]}, noise {entry['noise_factor']:g}× resolution\n"
                f"n = {n}, χ² p = {p['chi2_p']:.3f}",
                fontsize=9,
            )
            ax.set_xlabel(f"rank of the truth among {N_DRAWS} draws")
            ax.set_ylabel("replications")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replications", type=int, default=500, help="per noise level")
    parser.add_argument("--workers", type=int, default=2, help="processes")
    parser.add_argument("--seed", type=int, default=2018)
    parser.add_argument("--resume", action="store_true", help="continue from the raw file")
    parser.add_argument("--report-only", action="store_true", help="summarise the raw file")
    parser.add_argument("--raw", type=Path, default=RAW)
    parser.add_argument(
        "--output", default="sbc", help="name of the summary JSON and PNG under results/"
    )
    args = parser.parse_args(argv)

    records = _load(args.raw) if (args.resume or args.report_only) else []
    start = time.perf_counter()
    if not args.report_only:
        done = {(r["level"], r["index"]) for r in records}
        todo = [
            (level, i)
            for i in range(args.replications)
            for level in NOISE_LEVELS
            if (level, i) not in done
        ]
        args.raw.parent.mkdir(parents=True, exist_ok=True)
        mode = "a" if args.resume else "w"
        with (
            open(args.raw, mode) as raw,
            ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool,
        ):
            futures = [pool.submit(replicate, level, i, args.seed) for level, i in todo]
            for k, future in enumerate(as_completed(futures), 1):
                rec = future.result()
                records.append(rec)
                raw.write(json.dumps(rec) + "\n")
                raw.flush()
                if k % 20 == 0:
                    print(
                        f"{k}/{len(todo)} replications, {time.perf_counter() - start:.0f} s",
                        flush=True,
                    )
    elapsed = time.perf_counter() - start

    levels = summarise(records)
    head = f"{'noise':>6} {'param':<11}{'n':>5}{'not conv':>9}{'χ² p':>8}{'KS p':>8}{'cov95':>7}"
    print(head)
    print("-" * len(head))
    for entry in levels.values():
        for name, p in entry["parameters"].items():
            print(
                f"{entry['noise_factor']:>5g}x {name:<11}{entry['ranked']:>5}"
                f"{entry['not_converged'] + entry['errors']:>9}{p['chi2_p']:>8.3f}"
                f"{p['ks_p']:>8.3f}{p['coverage95']:>7.3f}"
            )
    png = RESULTS / f"{args.output}_ranks.png"
    plot(levels, png)
    path = write_results(
        args.output,
        {
            "benchmark": "sbc",
            "description": __doc__.split("\n\n")[1:3],
            "box": {k: list(v) for k, v in BOX.items()},
            "draws_per_rank": N_DRAWS,
            "bins": N_BINS,
            "seed": args.seed,
            "workers": args.workers,
            "elapsed_s": None if args.report_only else elapsed,
            "sum_fit_seconds": float(sum(r.get("seconds", 0.0) for r in records)),
            "levels": levels,
            "figure": png.name,
        },
    )
    print(f"wrote {path} and {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
