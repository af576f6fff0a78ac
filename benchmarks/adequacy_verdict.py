"""The adequacy verdict's false alarms on records of the law, and its power on others.

Records drawn as the bundled runs are (:func:`bayestribo.synthetic.campaign.campaign_plan`
with other seeds than the bundled campaign's: new parameters, releases, offsets and
noise; ``data/README.md``), each checked by :func:`bayestribo.adequacy.check_adequacy`
as ``bayestribo check RUN`` does (least squares, α = 0.05, 400 draws, seed 0):

==================  =========================================================================
law                 the glycerol and glycerol-water runs of the plan (viscous damping and
                    Coulomb friction, μ_s = 1.2 μ_k; 10 and 2 kHz): records of the law the
                    verdict judges, so each "not adequate" is a false alarm
air                 the plan's runs in air (viscous damping alone): the same
oil                 the plan's oil runs (quadratic drag as well): power
zeta+20%            the law's runs with ζ growing with the amplitude, ζ(a) = ζ_end (1 + 0.2
                    a/x₀) (benchmarks/adequacy.py's case): power
zeta+20%, 10x       the same with ten times the vibrometer's noise on both channels
zeta+0.2%, 10x      ζ(a) = ζ_end (1 + 0.002 a/x₀), ten times the noise: a departure the
                    checks find in most records, not all
zeta+0.1%, 10x      ζ(a) = ζ_end (1 + 0.001 a/x₀), ten times the noise: about half
==================  =========================================================================

Per record each check's outcome, the constancy test's and the halves' p-values, the end
of motion's quantile among the draws, the peaks' coverage and the verdict. Run with the
package to measure on ``PYTHONPATH`` (its report's level is read when it has one).

Run: ``python benchmarks/adequacy_verdict.py --plans 2 --power-runs 40 --out NAME``
(writes ``benchmarks/results/NAME.json``).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.stats

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import write_results  # noqa: E402

from bayestribo.adequacy import check_adequacy  # noqa: E402
from bayestribo.synthetic import DissipationLaw  # noqa: E402
from bayestribo.synthetic.campaign import campaign_plan  # noqa: E402

CHECKS = ("constancy", "extinction", "peaks", "halves")
#: First campaign seed of the plans (the bundled campaign's is 20100320).
SEED0 = 1


def _interval(k: int, n: int) -> list[float]:
    """Clopper-Pearson 95 % interval of a binomial proportion."""
    lo = 0.0 if k == 0 else float(scipy.stats.beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(scipy.stats.beta.ppf(0.975, k + 1, n - k))
    return [lo, hi]


def _growing(planned: Any, change: float, noise: float) -> Any:
    """The planned run with ζ growing by ``change`` from the end to the release's
    amplitude, and ``noise`` times the vibrometer's resolution as noise."""
    law = planned.law
    x0 = planned.release.initial_displacement_m
    zeta_end = float(law.zeta) / (1.0 + 0.5 * change)  # mean over the amplitudes ≈ ζ

    def zeta(a: float) -> float:
        return zeta_end * (1.0 + change * a / x0)

    sensor = planned.sensor
    if noise != 1.0:
        sensor = replace(
            sensor,
            displacement_noise_m=sensor.displacement_resolution_m * noise,
            velocity_noise_m_per_s=sensor.velocity_resolution_m_per_s * noise,
        )
    return replace(
        planned, law=DissipationLaw(zeta=zeta, mu_k=law.mu_k, mu_s=law.mu_s), sensor=sensor
    )


def one(planned: Any, case: str, plan_seed: int) -> dict[str, Any]:
    """Every check of one simulated record."""
    run = planned.simulate()
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = check_adequacy(run)
    return {
        "case": case,
        "plan_seed": plan_seed,
        "run": planned.run_id,
        "adequate": bool(report.adequate),
        "passed": {c["key"]: c["passed"] for c in report.checks},
        "p_constancy": None if report.constancy is None else report.constancy.p_value,
        "p_halves": None if report.halves is None else report.halves.p_value,
        "extinction_quantile": report.extinction.quantile_of_measured("exact"),
        "peak_coverage": float(report.predictive.coverage),
        "check_alpha": getattr(report, "check_alpha", 0.05),
        "cpu_s": time.process_time() - start,
    }


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Failure counts per check and of the verdict."""
    n = len(rows)
    out: dict[str, Any] = {"runs": n}
    for key in CHECKS:
        made = [r["passed"][key] for r in rows if r["passed"][key] is not None]
        failed = sum(1 for p in made if p is False)
        out[key] = {"made": len(made), "failed": failed}
    k = sum(1 for r in rows if not r["adequate"])
    out["not_adequate"] = {"count": k, "rate": k / n if n else None, "interval_95": _interval(k, n)}
    out["cpu_s_median"] = float(np.median([r["cpu_s"] for r in rows])) if rows else None
    return out


def main() -> None:
    """Draw the records, check each, print the counts, write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plans", type=int, default=2, help="campaign plans of records")
    parser.add_argument("--power-runs", type=int, default=40, help="records per power case")
    parser.add_argument("--out", default="adequacy_verdict", help="results file stem")
    args = parser.parse_args()
    rows: list[dict[str, Any]] = []
    cases: dict[str, list[dict[str, Any]]] = {}

    def add(r: dict[str, Any]) -> None:
        rows.append(r)
        cases.setdefault(r["case"], []).append(r)

    law_runs = []
    for k in range(args.plans):
        seed = SEED0 + k
        for planned in campaign_plan(seed):
            case = {"glycerol": "law", "glycerol-water": "law", "air": "air", "oil": "oil"}[
                planned.series
            ]
            add(one(planned, case, seed))
            if case == "law":
                law_runs.append((seed, planned))
        print(f"plan {seed}: done", flush=True)
    power = [
        ("zeta+20%", 0.2, 1.0),
        ("zeta+20%, 10x", 0.2, 10.0),
        ("zeta+0.2%, 10x", 0.002, 10.0),
        ("zeta+0.1%, 10x", 0.001, 10.0),
    ]
    for name, change, noise in power:
        for seed, planned in law_runs[: args.power_runs]:
            add(one(_growing(planned, change, noise), name, seed))
        print(f"{name}: done", flush=True)
    table = {name: summary(rs) for name, rs in cases.items()}
    for name, s in table.items():
        checks = ", ".join(f"{k} {s[k]['failed']}/{s[k]['made']}" for k in CHECKS)
        lo, hi = s["not_adequate"]["interval_95"]
        print(
            f"{name:15s} not adequate {s['not_adequate']['count']:3d}/{s['runs']:<3d} "
            f"[{100 * lo:.0f}-{100 * hi:.0f} %]; failed: {checks}; "
            f"{s['cpu_s_median']:.2f} s CPU (median)",
            flush=True,
        )
    path = write_results(
        args.out,
        {
            "plans": [SEED0 + k for k in range(args.plans)],
            "power_runs": args.power_runs,
            "summary": table,
            "runs": rows,
        },
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
