"""Stribeck friction, which no registered law has: is the answer ever silently wrong?

Each record comes from the independent simulator of ``benchmarks/_laws_sim.py``
(``scipy.integrate.solve_ivp`` half cycle by half cycle, nothing from the package) on
the paper's rig (m = 0.035 kg, f = 32.6 Hz, N = 0.31 N), released from x₀ at rest
after 0.1 s of rest, sampled at 5 kHz until 0.2 s after it stops, with white noise of
10x the vibrometer's resolution on both channels (``--velocity-only``: the velocity
channel alone). The law is viscous damping and a Stribeck friction

    μ(v) = μ_k + (μ_s - μ_k) exp(-(|v|/v_s)^δ),

at a strength s = (μ_s - μ_k)/μ_k given per run (``--strengths``, 0.3, 1 and 3 by
default); the rest is drawn per record from ``numpy.random.default_rng([2039, 100 s,
seed])``: ζ ~ U(0.002, 0.006), μ_k ~ U(0.015, 0.03), δ ~ U(1, 2), x₀ ~ U(1.5, 2.5) mm
and v_s ~ U(0.02, 0.05) of the first swing's peak speed Ωx₀.

Each record is fitted with the default law and with ``law="auto"``, as the CLI's
``bayestribo fit`` does. For each fit:

* ``exit``: the CLI's exit status (1 when the fit is not usable or a
  :class:`~bayestribo.errors.MisfitWarning` or subclass was raised, else 0; 2 when
  the fit refused the record with a :class:`~bayestribo.errors.BayestriboError`);
* the chosen law, the comparison's adequacy verdict (``auto``);
* the law's 95 % ΔE(A) band and the turning points' (law-free) band against the true
  ΔE(A) (``_laws_sim.true_dissipation``: the energy the true motion loses over the
  half cycle centred on each swing, by energy balance) at the smallest, middle and
  largest analysed swing;
* the log-log slope of the law's ΔE(A) and of the turning points' ΔE(A) over the
  analysed swings (least squares over the reported swings; computed here, not taken
  from the package).

A fit is *refused* (exit 2), *flagged* (exit 1), *covered* (exit 0, the truth inside
the law's band at the three swings and the slopes within 0.5) or *silently wrong*
(exit 0 and the truth outside the band at one of the three swings, or the slopes
apart by more than 0.5); *confidently* silently wrong when the truth is beyond 3.29
sd of the band there (sd = the 95 % band's width / 3.92) or the slopes are apart. A
flagged fit's honest answer is the law-free one: whether the turning points' band
covers the truth is counted too.

``--rig creep`` simulates instead the 5 Hz record of the ``stribeck`` branches
(``benchmarks/_creep_sim.py``: 500 Hz, 6 s, noise 5e-7 m and 5e-5 m/s, no metadata)
whose friction is regularised below 0.1 mm/s, so that the mass creeps on towards the
equilibrium after its last half cycle; a_k ~ U(0.1, 0.25) m/s², a_Δ = s a_k,
ζ ~ U(0.001, 0.006), δ ~ U(1, 2), x₀ ~ U(5, 7) mm, v_s ~ U(0.02, 0.05) Ωx₀.

Run (the package imported from ``PYTHONPATH``; the results name its tree's commit)::

    PYTHONPATH=<tree> nice -n 10 timeout 7200 python benchmarks/stribeck_verdict.py \
        --seeds 20 --workers 2 --output stribeck_verdict_main

Each finished record is appended to ``results/<output>_runs.jsonl`` (``--resume``
keeps them); the summary goes to ``results/<output>.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import _creep_sim  # noqa: E402
from _laws_sim import OMEGA, Truth, metadata, simulate, true_dissipation  # noqa: E402
from _machine import RESULTS, commit, niced_worker, write_results  # noqa: E402

NAME = "stribeck_verdict"
ENTROPY = 2039
FS = 5000.0
NOISE = 10.0
SLOPE_TOLERANCE = 0.5  # issue 39's goal: log-log slopes within 0.5
Z_CONFIDENT = 3.2905  # two-sided 99.9 % of the normal
FITS = ("default", "auto")


def draw(strength: float, seed: int) -> tuple[Truth, float]:
    """The truth of record ``seed`` at ``strength`` = (μ_s - μ_k)/μ_k, and x₀ [m]."""
    rng = np.random.default_rng([ENTROPY, round(100 * strength), seed])
    zeta = float(rng.uniform(0.002, 0.006))
    mu_k = float(rng.uniform(0.015, 0.03))
    delta = float(rng.uniform(1.0, 2.0))
    x0 = float(rng.uniform(1.5e-3, 2.5e-3))
    v_s = float(rng.uniform(0.02, 0.05)) * OMEGA * x0
    truth = Truth(
        zeta=zeta,
        mu_k=mu_k,
        mu_s_stribeck=mu_k * (1.0 + strength),
        v_s=v_s,
        stribeck_exponent=delta,
    )
    return truth, x0


def _slope(amp: np.ndarray, energy: np.ndarray) -> float:
    ok = np.isfinite(amp) & np.isfinite(energy) & (amp > 0) & (energy > 0)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(amp[ok]), np.log(energy[ok]), 1)[0])


def _band(d: dict[str, Any] | None) -> tuple[np.ndarray, ...] | None:
    if not d or not d.get("amplitude"):
        return None

    def arr(v: Any) -> np.ndarray:
        return np.array([np.nan if x is None else x for x in v], dtype=float)

    return arr(d["amplitude"]), arr(d["mean"]), arr(d["interval"][0]), arr(d["interval"][1])


def check(result: Any, truth_fn: Any) -> dict[str, Any]:
    """The law's and the turning points' ΔE(A) against the truth (see the module)."""
    out: dict[str, Any] = {}
    law = _band(result.dissipation)
    tp = _band(result.turning_point_dissipation)
    if law is None:
        return out
    amp = law[0]
    order = np.argsort(amp)
    picks = [int(order[0]), int(order[len(order) // 2]), int(order[-1])]
    true = np.asarray(truth_fn(amp[picks]), dtype=float)
    out["amplitude_m"] = amp[picks].tolist()
    out["truth_J"] = true.tolist()
    out["law_interval_J"] = [[float(law[2][i]), float(law[3][i])] for i in picks]
    out["law_covered"] = [
        bool(law[2][i] <= t <= law[3][i]) for i, t in zip(picks, true, strict=True)
    ]
    out["law_slope"] = _slope(amp, law[1])
    if tp is not None:
        out["tp_interval_J"] = [[float(tp[2][i]), float(tp[3][i])] for i in picks]
        out["tp_covered"] = [
            bool(tp[2][i] <= t <= tp[3][i]) for i, t in zip(picks, true, strict=True)
        ]
        out["tp_slope"] = _slope(tp[0], tp[1])
        out["slope_gap"] = abs(out["law_slope"] - out["tp_slope"])
    return out


def _fit(run: Any, law: str | None, seed: int, truth_fn: Any) -> dict[str, Any]:
    from bayestribo import fit
    from bayestribo.errors import BayestriboError, MisfitWarning

    rec: dict[str, Any] = {"law_asked": law or "default"}
    start = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = fit(run, seed=seed) if law is None else fit(run, law=law, seed=seed)
        except BayestriboError as exc:
            rec["cpu_s"] = time.process_time() - start
            rec["exit"] = 2
            rec["refused"] = f"{type(exc).__name__}: {exc}"[:400]
            return rec
    rec["cpu_s"] = time.process_time() - start
    misfit = [w for w in caught if issubclass(w.category, MisfitWarning)]
    rec["warnings"] = sorted(
        {w.category.__name__ for w in caught if w.category.__module__.startswith("bayestribo")}
    )
    rec["misfit_messages"] = [str(w.message)[:300] for w in misfit]
    rec["exit"] = 0 if result.usable and not misfit else 1
    rec["law"] = result.law
    rec["converged"] = bool(result.converged)
    comparison = result.law_comparison or {}
    if comparison:
        rec["verdict"] = comparison.get("verdict")
        rec["adequate"] = bool(comparison.get("adequate"))
    rec["shape_agreement"] = result.shape_agreement
    rec.update(check(result, truth_fn))
    covered = rec.get("law_covered")
    gap = rec.get("slope_gap", math.nan)
    if rec["exit"] == 1:
        rec["outcome"] = "flagged"
    elif covered is None:
        rec["outcome"] = "no band"
    elif all(covered) and not gap > SLOPE_TOLERANCE:
        rec["outcome"] = "covered"
    else:
        rec["outcome"] = "silently wrong"
    return rec


def draw_creep(strength: float, seed: int) -> _creep_sim.CreepTruth:
    """The truth of record ``seed`` of the creep rig at ``strength`` = a_Δ/a_k."""
    rng = np.random.default_rng([ENTROPY, 1, round(100 * strength), seed])
    zeta = float(rng.uniform(0.001, 0.006))
    a_k = float(rng.uniform(0.1, 0.25))
    delta = float(rng.uniform(1.0, 2.0))
    x0 = float(rng.uniform(5e-3, 7e-3))
    v_s = float(rng.uniform(0.02, 0.05)) * _creep_sim.OMEGA * x0
    return _creep_sim.CreepTruth(zeta, a_k, strength * a_k, v_s, delta, x0)


def _record(rig: str, strength: float, seed: int, velocity_only: bool) -> tuple[Any, ...]:
    """The run, the true ΔE(A) as a function of the swings [m] and the truth's record."""
    from bayestribo.io.run import Run

    noise_seed = [ENTROPY, round(100 * strength), seed, 1]
    if rig == "creep":
        creep = draw_creep(strength, seed)
        t, xs, vs = _creep_sim.simulate(creep, noise_seed)
        meta: dict[str, Any] = {}
        peak = _creep_sim.OMEGA * creep.x0
        told = {**creep.__dict__, "v_s_over_peak": creep.v_s / peak}
        facts: dict[str, Any] = {}

        def truth_fn(a: Any) -> Any:
            return _creep_sim.true_dissipation(creep, a)
    else:
        truth, x0 = draw(strength, seed)
        t, xs, vs, facts = simulate(truth, x0=x0, fs=FS, noise=NOISE, seed=noise_seed)
        meta = metadata()
        told = {**truth.__dict__, "x0_m": x0, "v_s_over_peak": truth.v_s / (OMEGA * x0)}

        def truth_fn(a: Any) -> Any:
            return true_dissipation(truth, a)

    run = Run(time=t, displacement=None if velocity_only else xs, velocity=vs, metadata=meta)
    return run, truth_fn, told, facts


def one_run(strength: float, seed: int, velocity_only: bool, rig: str = "paper") -> dict[str, Any]:
    """Simulate record ``seed`` at ``strength``, fit it both ways, check the answers."""
    run, truth_fn, told, facts = _record(rig, strength, seed, velocity_only)
    out: dict[str, Any] = {
        "rig": rig,
        "strength": strength,
        "seed": seed,
        "velocity_only": velocity_only,
        "truth": told,
        "simulation": facts,
    }
    for name, law in zip(FITS, (None, "auto"), strict=True):
        out[name] = _fit(run, law, seed, truth_fn)
    return out


def band_z(rec: dict[str, Any], key: str = "law_interval_J") -> list[float]:
    """(truth - band's centre) over the band's sd, (high - low)/3.92, at the three swings."""
    out = []
    for (lo, hi), true in zip(rec[key], rec["truth_J"], strict=True):
        sd = (hi - lo) / 3.92
        out.append((true - 0.5 * (lo + hi)) / sd if sd > 0 else math.inf)
    return out


def confidently_wrong(rec: dict[str, Any]) -> bool:
    """Silently wrong with the truth beyond 3.29 sd of the band (two-sided 99.9 %) at
    one of the three swings, or the slopes apart by more than the tolerance."""
    if rec.get("outcome") != "silently wrong":
        return False
    far = max(abs(z) for z in band_z(rec)) > Z_CONFIDENT
    return bool(far or rec.get("slope_gap", 0.0) > SLOPE_TOLERANCE)


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Counts of each outcome by strength and fit."""
    table: dict[str, Any] = {}
    for s in sorted({r["strength"] for r in runs}):
        rows = [r for r in runs if r["strength"] == s]
        for name in FITS:
            recs = [r[name] for r in rows]
            counts = {k: 0 for k in ("refused", "covered", "flagged", "silently wrong", "no band")}
            for rec in recs:
                counts["refused" if rec["exit"] == 2 else rec["outcome"]] += 1
            flagged = [rec for rec in recs if rec["exit"] == 1 and "tp_covered" in rec]
            laws: dict[str, int] = {}
            for rec in recs:
                laws[rec.get("law", "refused")] = laws.get(rec.get("law", "refused"), 0) + 1
            table[f"{s:g}/{name}"] = {
                "runs": len(recs),
                **counts,
                "flagged_law_free_covered": sum(all(rec["tp_covered"]) for rec in flagged),
                "flagged_with_law_free": len(flagged),
                "laws": laws,
                "silently_wrong_seeds": [
                    r["seed"] for r in rows if r[name].get("outcome") == "silently wrong"
                ],
                "confidently_silently_wrong_seeds": [
                    r["seed"] for r in rows if confidently_wrong(r[name])
                ],
                "max_abs_z_silently_wrong": {
                    str(r["seed"]): max(abs(z) for z in band_z(r[name]))
                    for r in rows
                    if r[name].get("outcome") == "silently wrong"
                },
                "median_cpu_s": float(np.median([rec["cpu_s"] for rec in recs])),
            }
    return table


def _package_commit() -> str:
    import bayestribo

    return commit(Path(bayestribo.__file__).resolve().parent.parent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strengths", type=float, nargs="+", default=[0.3, 1.0, 3.0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--velocity-only", action="store_true")
    parser.add_argument("--rig", choices=("paper", "creep"), default="paper")
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument("--output", default=NAME)
    args = parser.parse_args()
    raw = RESULTS / f"{args.output}_runs.jsonl"
    lines = raw.read_text().splitlines() if raw.exists() else []
    runs = [json.loads(line) for line in lines if line.strip()]
    if not (args.resume or args.report_only):
        raw.write_text("")
        runs = []
    if not args.report_only:
        done = {(r["strength"], r["seed"]) for r in runs}
        todo = [
            (s, k) for k in range(1, args.seeds + 1) for s in args.strengths if (s, k) not in done
        ]
        with ProcessPoolExecutor(args.workers, initializer=niced_worker) as pool:
            futures = [pool.submit(one_run, s, k, args.velocity_only, args.rig) for s, k in todo]
            for future in as_completed(futures):
                run = future.result()
                runs.append(run)
                with raw.open("a") as fh:
                    fh.write(json.dumps(run) + "\n")
                print(
                    run["strength"],
                    run["seed"],
                    *(
                        f"{n}: {run[n].get('law')} exit {run[n]['exit']} {run[n].get('outcome')}"
                        for n in FITS
                    ),
                    flush=True,
                )
    runs.sort(key=lambda r: (r["strength"], r["seed"]))
    results = {
        "package_commit": _package_commit(),
        "benchmark_commit": commit(),
        "settings": {
            "rate_Hz": FS,
            "noise_x_resolution": NOISE,
            "velocity_only": args.velocity_only,
            "rig": args.rig,
            "slope_tolerance": SLOPE_TOLERANCE,
            "entropy": ENTROPY,
        },
        "summary": summarise(runs),
        "runs": runs,
    }
    path = write_results(args.output, results)
    print(json.dumps(results["summary"], indent=1))
    print(path)


if __name__ == "__main__":
    main()
