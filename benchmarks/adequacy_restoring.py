"""The adequacy checks on a nonlinear restoring force: false alarms and power.

Independent records (``tests/_pendulum_decay.py``: ``solve_ivp`` half cycle by half
cycle, sticking in the friction band) of viscous damping and Coulomb friction with a
constant ζ and friction, so that the law the checks judge holds:

==============  ===========================================================================
pendulum        θ'' = -ω₀² sin θ - 2ζω₀θ' - ω₀²θ_c sgn θ', f₀ = 0.7 Hz, ζ = 0.003,
                θ_c = 0.012 rad, released at rest at an angle drawn in 60-90°, 40 s at
                200 Hz (the motion stops inside), angle and angular velocity recorded
                with 1 mrad and 4 mrad/s of white noise
linear          the same with a linear spring (x + 0·x³, released at 1.05-1.57 units):
                the checks' false alarms where they judged the linear law before
linear-fast     the linear spring at f₀ = 3 Hz, 15 s (the same friction, damping and noise)
duffing         x'' = -ω₀²(x + βx³) - ..., β = 0.6, f₀ = 1.5 Hz, ζ = 0.003, x_c = 0.01,
                released at 0.8-1.0 units, 20 s at 200 Hz, 0.3 and 3 units·mrad of noise
==============  ===========================================================================

Each record is checked by :func:`bayestribo.adequacy.check_adequacy` (least squares,
α = 0.05, 400 draws) with ``restoring`` its own force, ``"auto"``, and ``"linear"``
(the law on the wrong force: that it fails is the checks' power). Per check, the
fraction of records it fails, with its Clopper-Pearson 95 % interval, and the fraction
of verdicts "not adequate"; the force ``auto`` chose.

Run: ``python benchmarks/adequacy_restoring.py --runs 20`` (writes
``benchmarks/results/adequacy_restoring.json``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import scipy.stats

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(1, str(HERE.parent / "tests"))

from _machine import write_results  # noqa: E402
from _pendulum_decay import Swing, swing  # noqa: E402

from bayestribo.adequacy import check_adequacy  # noqa: E402
from bayestribo.io.run import Run  # noqa: E402

CHECKS = ("constancy", "extinction", "peaks", "halves")
CASES: dict[str, dict[str, Any]] = {
    "pendulum": {
        "swing": Swing(f0=0.7, zeta=0.003, friction=0.012, x0=1.0, duration=40.0),
        "release": (math.radians(60.0), math.radians(90.0)),
        "unit": "rad",
        "force": "pendulum",
        "restoring": ("pendulum", "auto", "linear"),
    },
    "linear": {
        "swing": Swing(f0=0.7, zeta=0.003, friction=0.012, x0=1.0, beta=0.0, duration=40.0),
        "release": (math.radians(60.0), math.radians(90.0)),
        "unit": "arbitrary",
        "force": "linear",
        "restoring": ("linear",),
    },
    "linear-fast": {
        "swing": Swing(f0=3.0, zeta=0.003, friction=0.012, x0=1.0, beta=0.0, duration=15.0),
        "release": (math.radians(60.0), math.radians(90.0)),
        "unit": "arbitrary",
        "force": "linear",
        "restoring": ("linear",),
    },
    "duffing": {
        "swing": Swing(
            f0=1.5,
            zeta=0.003,
            friction=0.01,
            x0=1.0,
            beta=0.6,
            duration=20.0,
            noise=3e-4,
            noise_v=3e-3,
        ),
        "release": (0.8, 1.0),
        "unit": "arbitrary",
        "force": "duffing",
        "restoring": ("duffing", "auto", "linear"),
    },
}


def _interval(k: int, n: int) -> list[float]:
    """Clopper-Pearson 95 % interval of a binomial proportion."""
    lo = 0.0 if k == 0 else float(scipy.stats.beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(scipy.stats.beta.ppf(0.975, k + 1, n - k))
    return [lo, hi]


def one(case: dict[str, Any], seed: int) -> dict[str, Any]:
    """Every check of one record under each of the case's ``restoring``."""
    rng = np.random.default_rng(seed)
    x0 = float(rng.uniform(*case["release"]))
    t, x, v = swing(Swing(**{**case["swing"].__dict__, "x0": x0}), seed)
    run = Run(t, x, v, metadata={"length_unit": case["unit"]}, source=f"seed {seed}")
    out: dict[str, Any] = {"seed": seed, "x0": x0}
    for restoring in case["restoring"]:
        start = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            report = check_adequacy(run, restoring=restoring)
        out[restoring] = {
            "adequate": report.adequate,
            "passed": {c["key"]: c["passed"] for c in report.checks},
            "force": report.restoring,
            "verdict": report.verdict,
            "cpu_s": time.process_time() - start,
        }
    return out


def summary(runs: list[dict[str, Any]], restoring: str) -> dict[str, Any]:
    """Failure rates per check and of the verdict over ``runs``."""
    n = len(runs)
    rows = [r[restoring] for r in runs]
    out: dict[str, Any] = {"runs": n}
    for key in CHECKS:
        made = [r["passed"][key] for r in rows if r["passed"][key] is not None]
        failed = sum(1 for p in made if p is False)
        out[key] = {
            "made": len(made),
            "failed": failed,
            "rate": failed / len(made) if made else None,
            "interval_95": _interval(failed, len(made)) if made else None,
        }
    failed = sum(1 for r in rows if not r["adequate"])
    out["not_adequate"] = {"count": failed, "rate": failed / n, "interval_95": _interval(failed, n)}
    # the force's name, without a Duffing spring's measured β
    out["forces"] = sorted({str(r["force"]).split(" (β")[0] for r in rows})
    out["cpu_s_median"] = float(np.median([r["cpu_s"] for r in rows]))
    return out


def main() -> None:
    """Run the cases, print a table and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="records per case")
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    parser.add_argument("--out", default="adequacy_restoring", help="results file stem")
    args = parser.parse_args()
    results: dict[str, Any] = {"runs": args.runs, "cases": {}}
    for name in args.cases:
        case = CASES[name]
        runs = [one(case, 1000 + k) for k in range(args.runs)]
        results["cases"][name] = {
            "summary": {r: summary(runs, r) for r in case["restoring"]},
            "runs": runs,
        }
        for restoring, s in results["cases"][name]["summary"].items():
            rates = ", ".join(f"{k} {s[k]['failed']}/{s[k]['made']}" for k in CHECKS)
            print(
                f"{name:9s} restoring={restoring:9s} not adequate "
                f"{s['not_adequate']['count']}/{s['runs']}; failed: {rates}; "
                f"forces {s['forces']}; {s['cpu_s_median']:.2f} s CPU (median)",
                flush=True,
            )
    path = write_results(args.out, results)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
