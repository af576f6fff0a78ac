"""A seismometer's velocity alone, fading into the noise: coverage of ζ over seeds.

Each run is an independent simulation (``scipy.integrate.solve_ivp``, nothing from the
package) of a purely viscous oscillator, x'' + 2ζω x' + ω² x = 0 with ζ = 0.08 and a
15 s period, held at x₀ and released from rest at t = 10 s; the record is its velocity
alone (a coil's voltage, arbitrary units, 0.3 at its largest), 300 s at 10 Hz (150
samples a period), with white noise σ = 2e-4. Viscous damping never stops the
oscillation: it fades into the noise after about 170 s (8 σ) and stays coherent under
it until about 220 s. Cases:

======  ========================================================================
clean   the record as above
drift   the velocity's offset a random walk, 1e-4 per √s
steps   5 footstep bursts (5 samples of N(0, 3e-3) each) after t = 150 s
cubic   a hardening cubic spring, ω²x(1 + βx²), β making the frequency at the
        release swing 0.5 % higher (3/8 β x₀² = 0.005): a change of the half period
        of about 0.2 % over the analysed swings, within 1-3 of its standard errors
======  ========================================================================

Every run is fitted with :func:`bayestribo.fit` (the default law viscous + Coulomb, or
``--law``). The truth is ζ = 0.08 (no dry friction; for ``cubic`` the linear part's).
With z = (posterior mean - truth) / posterior sd, a run is *refused* (an exception,
recorded with its message), *covered* (the 95 % interval of ζ holds the truth),
*flagged* (not covered, and a :class:`~bayestribo.errors.MisfitWarning`,
``ConvergenceWarning``, ``PriorBoundWarning`` or ``ChannelCalibrationWarning`` said so),
*missed* (not covered, no such warning: 1 run in 20 by chance) or, among all fitted
runs, *silently wrong* (|z| > 3.29 and no such warning). ``false_flags`` counts covered
runs that were flagged.

Run: ``python benchmarks/seismometer.py [--runs 20] [--first-run 0] [--cases clean drift
steps cubic] [--law viscous+coulomb] [--output seismometer_fade]``; writes
``benchmarks/results/<output>.json``. A seed is the same record at any ``--runs``, so
``--first-run 10 --runs 20`` fits seeds 10-19 of a sweep of 20 alone.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import provenance, write_results

ZETA = 0.08
PERIOD_S = 15.0
RATE_HZ = 10.0
DURATION_S = 300.0
RELEASE_S = 10.0
NOISE = 2e-4
#: Velocity scale: a coil's volts per unit of velocity (0.3 at the largest swing).
GAIN = 40.0
X0 = 0.02
CASES: dict[str, dict[str, float]] = {
    "clean": {"drift": 0.0, "steps": 0.0},
    "drift": {"drift": 1e-4, "steps": 0.0},
    "steps": {"drift": 0.0, "steps": 3e-3},
    "cubic": {"cubic": 0.005},
}
#: The cases run when ``--cases`` is not given (``cubic`` is asked for by name).
DEFAULT_CASES = ("clean", "drift", "steps")
FLAGS = ("MisfitWarning", "ChannelCalibrationWarning", "ConvergenceWarning", "PriorBoundWarning")
Z_CONFIDENT = 3.2905  # two-sided 99.9 % of the normal


def record(
    seed: int,
    *,
    drift: float = 0.0,
    steps: float = 0.0,
    cubic: float = 0.0,
    duration_s: float = DURATION_S,
    rate_hz: float = RATE_HZ,
) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and velocity [arbitrary] of run ``seed``: the oscillator integrated by
    ``solve_ivp`` (rtol 1e-10), rest until :data:`RELEASE_S`, white noise, a random
    walk of ``drift`` per √s on the offset, 5 bursts of ``steps`` after 150 s and a
    cubic spring raising the frequency at the release swing by the fraction ``cubic``."""
    omega = 2.0 * math.pi / PERIOD_S
    beta = cubic / (0.375 * X0 * X0)  # Duffing: ω(A) ≈ ω(1 + 3/8 β A²)

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        spring = omega * omega * s[0] * (1.0 + beta * s[0] * s[0])
        return [s[1], -spring - 2.0 * ZETA * omega * s[1]]

    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    moving = t >= RELEASE_S - 1e-9
    solution = solve_ivp(
        rhs,
        (0.0, float(t[-1] - RELEASE_S)),
        [X0, 0.0],
        t_eval=t[moving] - RELEASE_S,
        rtol=1e-10,
        atol=1e-14,
    )
    v = np.zeros(t.size)
    v[moving] = GAIN * solution.y[1]
    rng = np.random.default_rng(seed)
    v += drift * np.cumsum(rng.normal(0.0, 1.0, t.size)) / math.sqrt(rate_hz)
    v += rng.normal(0.0, NOISE, t.size)
    first = int(np.searchsorted(t, 150.0))
    for k in rng.choice(np.arange(first, t.size - 5), 5):
        v[k : k + 5] += rng.normal(0.0, steps)
    return t, v


def one_run(case: str, seed: int, law: str) -> dict[str, Any]:
    """Simulate and fit run ``seed`` of ``case``; record refusal, ζ's interval, z and
    warnings."""
    import bayestribo

    out: dict[str, Any] = {"case": case, "seed": seed}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t, v = record(seed, **CASES[case])
            run = bayestribo.Run(time=t, velocity=v, metadata={"length_unit": "arbitrary"})
            start = time.process_time()
            result = bayestribo.fit(run, law=law, seed=seed)
            out["fit_cpu_seconds"] = time.process_time() - start
    except Exception as exc:  # recorded and reported, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    ours = [w for w in caught if w.category.__module__.startswith("bayestribo")]
    flag = [w for w in ours if any(c.__name__ in FLAGS for c in w.category.__mro__)]
    out["warnings"] = sorted({w.category.__name__ for w in flag})
    out["other_warnings"] = sorted({w.category.__name__ for w in ours if w not in flag})
    out["warning_messages"] = {w.category.__name__: str(w.message)[:400] for w in ours}
    lo, hi = (float(b) for b in result.interval("zeta", 0.95))
    draws = np.asarray(result.samples("zeta"))
    out["interval"] = [lo, hi]
    out["mean"] = float(draws.mean())
    out["sd"] = float(draws.std(ddof=1))
    out["z"] = (out["mean"] - ZETA) / out["sd"]
    out["covered"] = bool(lo <= ZETA <= hi)
    return out


def summarise(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Per case: refused, covered, flagged, missed, silently wrong, false flags, and
    z's mean and sd with their standard errors."""
    from scipy.stats import beta

    table: dict[str, Any] = {}
    for case in CASES:
        rows = [r for r in records if r["case"] == case]
        if not rows:
            continue
        fitted = [r for r in rows if "refused" not in r]
        covered = [r for r in fitted if r["covered"]]
        flagged = [r for r in fitted if not r["covered"] and r["warnings"]]
        missed = [r for r in fitted if not r["covered"] and not r["warnings"]]
        silent = [r for r in fitted if abs(r["z"]) > Z_CONFIDENT and not r["warnings"]]
        z = np.array([r["z"] for r in fitted])
        n, k = len(fitted), len(covered)
        table[case] = {
            "runs": len(rows),
            "refused": len(rows) - n,
            "covered": k,
            "flagged": len(flagged),
            "missed": len(missed),
            "silently_wrong": len(silent),
            "false_flags": sum(1 for r in covered if r["warnings"]),
            "coverage": k / n if n else None,
            "coverage_clopper_pearson": [
                float(beta.ppf(0.025, k, n - k + 1)) if k else 0.0,
                float(beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0,
            ]
            if n
            else None,
            "z_mean": float(z.mean()) if n else None,
            "z_mean_se": float(z.std(ddof=1) / math.sqrt(n)) if n > 1 else None,
            "z_sd": float(z.std(ddof=1)) if n > 1 else None,
            "z_sd_se": float(z.std(ddof=1) / math.sqrt(2 * (n - 1))) if n > 1 else None,
            "median_fit_cpu_seconds": float(np.median([r["fit_cpu_seconds"] for r in fitted]))
            if n
            else None,
        }
    return table


def main(argv: list[str] | None = None) -> None:
    """Run the cases, print the table and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="seeds per case (default 20)")
    parser.add_argument(
        "--first-run",
        type=int,
        default=0,
        help="the first seed of every case (seeds FIRST to RUNS-1): a sweep's later seeds",
    )
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(DEFAULT_CASES))
    parser.add_argument("--law", default="viscous+coulomb", help="the law fitted")
    parser.add_argument("--output", default="seismometer_fade", help="results/<output>.json")
    args = parser.parse_args(argv)
    load = os.getloadavg()
    records = []
    for case in args.cases:
        for seed in range(args.first_run, args.runs):
            r = one_run(case, seed, args.law)
            records.append(r)
            said = r.get("refused") or (
                f"[{r['interval'][0]:.5f}, {r['interval'][1]:.5f}] z = {r['z']:+.2f} "
                f"{r['warnings']}"
            )
            print(case, seed, said, flush=True)
    table = summarise(records)
    for case, row in table.items():
        print(case, {k: v for k, v in row.items() if k != "coverage_clopper_pearson"})
    settings = {
        "runs": args.runs,
        "first_run": args.first_run,
        "cases": args.cases,
        "law": args.law,
        "truth_zeta": ZETA,
    }
    path = write_results(
        args.output,
        {**provenance("bayestribo.fit", settings, load), "table": table, "runs": records},
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
