"""The fit on real signal chains: refused, covered, warned, per effect of the chain.

Each run comes from the independent simulator of ``benchmarks/_chain.py``
(``scipy.integrate.solve_ivp`` of m x'' + c x' + k x + μ_k N sign(x') = 0 with sticking
when |k x| <= μ_s N; the paper's rig, m = 0.035 kg, f = 32.6 Hz, N = 0.31 N, ζ = 0.0236,
μ_k = 0.0294, μ_s = 0.04, x₀ = 2 mm; the same motion and, for the same seed, the same
noise as ``tests/test_signal_frontend.py``) with white noise of 10 times the
vibrometer's resolution on both channels and one effect of a real signal chain:

=========  ==============================================================================
clean      0.1 s of rest before and after the motion, 10 kHz
filter     a causal 4th-order Butterworth anti-alias filter at 2 kHz on both channels
hum        50 Hz mains hum of 5 times the white noise's rms (random phase)
hum-notch  the same, fitted with ``bayestribo.fit(..., notch="auto")``
pink       1/f noise of 5 times the white noise's rms
rest-2s    2 s of rest after the stop
rest-30s   30 s of rest after the stop
1kHz       sampled at 1 kHz
100kHz     sampled at 100 kHz, through the anti-alias filter
=========  ==============================================================================

The same effects at 10x and 30x the resolution, with the laws and channels that are not
the model and the "silently wrong" count, are in ``benchmarks/misspecification.py``,
the one benchmark of "never silently wrong"; this script is the 10x chain alone.

Every run is fitted with :func:`bayestribo.fit` (exact model, small sampler settings:
16 walkers × 2 ensembles, at most ``--max-steps`` steps). Reported per effect: runs
refused (an exception, recorded with its message), covered (the 95 % interval contains
the truth, for ζ and for μ_k), warned (a :class:`~bayestribo.errors.MisfitWarning` or a
:class:`~bayestribo.errors.ConvergenceWarning`), and the standardised errors
(mean - truth)/sd.

Run (by hand, on a quiet machine)::

    nice -n 10 python benchmarks/frontend.py --runs 20 --workers 2

Writes ``benchmarks/results/frontend.json`` (``--output NAME``: ``NAME.json``) with the
machine description.
"""

from __future__ import annotations

import argparse
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

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _chain import (  # noqa: E402
    CHAIN_EFFECTS,
    MU_K,
    ZETA,
    apply_chain,
    clopper_pearson,
    metadata,
    record,
)
from _machine import niced_worker, write_results  # noqa: E402

__all__ = ["EFFECTS", "one_run", "summarise"]

#: effect -> (sample rate [Hz], rest after the stop [s], chain options, notch)
EFFECTS = CHAIN_EFFECTS
PARAMS = ("zeta", "mu_k")


def one_run(effect: str, index: int, seed: int, max_steps: int) -> dict[str, Any]:
    """Simulate one run with ``effect``, fit it, record refusal, coverage and warnings."""
    from bayestribo.errors import ConvergenceWarning, MisfitWarning
    from bayestribo.inference import fit
    from bayestribo.io.run import Run

    fs, rest_after, chain, notch = EFFECTS[effect]
    truth = {"zeta": ZETA, "mu_k": MU_K}
    out: dict[str, Any] = {"effect": effect, "index": index}
    start = time.perf_counter()
    try:
        t, x, v = record(fs, 0.1, rest_after)
        xs, vs = apply_chain(t, x, v, fs, seed=seed * 1000 + index, noise=10.0, **chain)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(
                Run(time=t, displacement=xs, velocity=vs, metadata=metadata()),
                seed=seed * 1000 + index,
                n_walkers=16,
                n_ensembles=2,
                max_steps=max_steps,
                notch=notch,
            )
    except Exception as exc:  # recorded and reported, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    out["seconds"] = time.perf_counter() - start
    out["converged"] = bool(result.converged)
    if notch:
        out["notch_Hz"] = result.settings.get("notch_Hz")
    out["warnings"] = sorted(
        {
            w.category.__name__
            for w in caught
            if issubclass(w.category, (MisfitWarning, ConvergenceWarning))
        }
    )
    out["interval"] = {n: [float(b) for b in result.interval(n, 0.95)] for n in PARAMS}
    out["mean"] = {n: float(np.mean(result.samples(n))) for n in PARAMS}
    out["sd"] = {n: float(np.std(result.samples(n), ddof=1)) for n in PARAMS}
    out["covered"] = {
        n: bool(out["interval"][n][0] <= truth[n] <= out["interval"][n][1]) for n in PARAMS
    }
    out["z"] = {n: (out["mean"][n] - truth[n]) / out["sd"][n] for n in PARAMS}
    return out


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per effect: refused, covered (ζ, μ_k, both, with 95 % intervals), warned, z."""
    table: dict[str, Any] = {}
    for effect in EFFECTS:
        rows = [r for r in records if r["effect"] == effect]
        if not rows:
            continue
        fitted = [r for r in rows if "covered" in r]
        row: dict[str, Any] = {
            "runs": len(rows),
            "refused": len(rows) - len(fitted),
            "refusals": sorted({r["refused"] for r in rows if "refused" in r}),
            "warned": sum(bool(r["warnings"]) for r in fitted),
            "not_converged": sum(not r["converged"] for r in fitted),
        }
        for n in PARAMS:
            k = sum(r["covered"][n] for r in fitted)
            row[f"covered_{n}"] = k
            row[f"covered_{n}_ci95"] = clopper_pearson(k, len(fitted))
            z = np.array([r["z"][n] for r in fitted])
            row[f"z_{n}"] = (
                {"mean": float(z.mean()), "sd": float(z.std(ddof=1))} if z.size > 1 else None
            )
        row["covered_both"] = sum(all(r["covered"].values()) for r in fitted)
        row["silently_wrong"] = sum(
            (not all(r["covered"].values())) and not r["warnings"] for r in fitted
        )
        row["median_fit_seconds"] = (
            float(np.median([r["seconds"] for r in fitted])) if fitted else None
        )
        table[effect] = row
    return table


def _print_table(table: dict[str, Any]) -> None:
    head = (
        f"{'effect':10s} {'runs':>4s} {'refused':>7s} {'cov ζ':>6s} {'cov μk':>6s} "
        f"{'warned':>6s} {'silent':>6s} {'z ζ (mean±sd)':>16s} {'z μk (mean±sd)':>16s}"
    )
    print(head)
    for effect, r in table.items():
        fitted = r["runs"] - r["refused"]

        def z(name: str, r: dict = r) -> str:
            v = r[f"z_{name}"]
            return f"{v['mean']:+.2f}±{v['sd']:.2f}" if v else "-"

        print(
            f"{effect:10s} {r['runs']:4d} {r['refused']:7d} {r['covered_zeta']:3d}/{fitted:<2d} "
            f"{r['covered_mu_k']:3d}/{fitted:<2d} {r['warned']:6d} {r['silently_wrong']:6d} "
            f"{z('zeta'):>16s} {z('mu_k'):>16s}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per effect")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=13)
    parser.add_argument("--max-steps", type=int, default=6000)
    parser.add_argument("--effects", nargs="*", default=list(EFFECTS), choices=list(EFFECTS))
    parser.add_argument("--output", default="frontend", help="results/NAME.json")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    records: list[dict[str, Any]] = []
    jobs = [(e, i) for e in args.effects for i in range(args.runs)]
    with ProcessPoolExecutor(max_workers=args.workers, initializer=niced_worker) as pool:
        futures = [pool.submit(one_run, e, i, args.seed, args.max_steps) for e, i in jobs]
        for k, future in enumerate(as_completed(futures), 1):
            records.append(future.result())
            if k % 10 == 0:
                print(f"{k}/{len(jobs)} runs, {time.perf_counter() - start:.0f} s", flush=True)
    table = summarise(records)
    _print_table(table)
    path = write_results(
        args.output,
        {
            "settings": {
                "runs_per_effect": args.runs,
                "seed": args.seed,
                "max_steps": args.max_steps,
                "n_walkers": 16,
                "n_ensembles": 2,
                "effects": {
                    e: {
                        "sample_rate_Hz": EFFECTS[e][0],
                        "rest_after_s": EFFECTS[e][1],
                        "chain": EFFECTS[e][2],
                        "notch": EFFECTS[e][3],
                    }
                    for e in args.effects
                },
                "white_noise": "10x the resolution (1.5 µm, 0.15 µm/s)",
            },
            "wall_seconds": time.perf_counter() - start,
            "table": table,
            "runs": sorted(records, key=lambda r: (r["effect"], r["index"])),
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
