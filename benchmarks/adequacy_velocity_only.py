"""The constancy test on velocity-only records of the paper's rig: false alarms and power.

Records simulated by :func:`bayestribo.synthetic.simulate` on the paper's rig (ζ = 0.0236,
μ_k = 0.0294, μ_s = 1.2 μ_k, 10 kHz, the vibrometer's noise), each windowed
(:func:`bayestribo.adequacy.windows.windowed_fits`, least squares, two oscillations a
window) and tested (:func:`bayestribo.adequacy.constancy.constancy_test`):

=====================  ==================================================================
law, velocity          the velocity alone (the displacement integrated by the package):
                       each failure is a false alarm
zeta+20%, velocity     the velocity alone with ζ growing with the amplitude, ζ(a) =
                       ζ_end (1 + 0.2 a/x₀): power
law, both              both channels, the same records of the law: the results the
                       velocity-only changes must leave alone
=====================  ==================================================================

With ``--bayes N`` also the Bayesian fit (:func:`bayestribo.inference.fit`, seed 0) of
the first N records of the law with the velocity alone: each posterior mean's z against
the truth.

Per record the constancy p-value and each window's μ_k and ζ relative to the truth.
Counted at 5 % and at 5/3 % (the level ``check_adequacy`` tests it at). Run with the
package to measure on ``PYTHONPATH``.

Run: ``python benchmarks/adequacy_velocity_only.py --runs 24 --power-runs 10 --out NAME``
(writes ``benchmarks/results/NAME.json``).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import write_results  # noqa: E402

from bayestribo.adequacy.constancy import constancy_test  # noqa: E402
from bayestribo.adequacy.windows import windowed_fits  # noqa: E402
from bayestribo.synthetic import DissipationLaw, Sensor, simulate  # noqa: E402

ZETA, MU = 0.0236, 0.0294
X0 = 0.0015  # the default release [m]
LEVELS = (0.05, 0.05 / 3)


def law(change: float = 0.0) -> DissipationLaw:
    """The paper's law, ζ growing by ``change`` from the end to the release if given."""
    if change == 0.0:
        return DissipationLaw(zeta=ZETA, mu_k=MU, mu_s=1.2 * MU)
    zeta_end = ZETA / (1.0 + 0.5 * change)
    return DissipationLaw(zeta=lambda a: zeta_end * (1.0 + change * a / X0), mu_k=MU, mu_s=1.2 * MU)


def one(case: str, change: float, channels: tuple[str, ...], seed: int) -> dict[str, Any]:
    """The constancy test of one simulated record."""
    run = simulate(law(change), sensor=Sensor(channels=channels), seed=seed)
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        windows = windowed_fits(run)
        test = constancy_test(windows)
    return {
        "case": case,
        "seed": seed,
        "p": test.p_value,
        "p_trend": test.p_trend,
        "p_scatter": test.p_scatter,
        "mu_relative": (windows.column("mu") / MU - 1.0).tolist(),
        "mu_se_relative": [w.mu_se / MU for w in windows.windows],
        "zeta_relative": (windows.column("zeta") / ZETA - 1.0).tolist(),
        "cpu_s": time.process_time() - start,
    }


def bayes(seed: int) -> dict[str, Any]:
    """The Bayesian fit of one velocity-only record of the law: z of ζ and μ_k."""
    from bayestribo.inference import fit

    run = simulate(law(), sensor=Sensor(channels=("velocity",)), seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, seed=0)
    out: dict[str, Any] = {"seed": seed}
    for name, truth in (("zeta", ZETA), ("mu_k", MU)):
        draws = np.asarray(result.samples(name), dtype=float)
        out[name] = {"mean": float(draws.mean()), "sd": float(draws.std())}
        out[name]["z"] = (out[name]["mean"] - truth) / out[name]["sd"]
    return out


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Failures at each level, the median p-value and CPU."""
    ps = [r["p"] for r in rows]
    out: dict[str, Any] = {"runs": len(rows), "median_p": float(np.median(ps))}
    for level in LEVELS:
        out[f"failed_at_{level:.4g}"] = sum(p < level for p in ps)
    out["cpu_s_median"] = float(np.median([r["cpu_s"] for r in rows]))
    return out


def main() -> None:
    """Simulate, test, print the counts, write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=24, help="records of the law")
    parser.add_argument("--power-runs", type=int, default=10, help="records per other case")
    parser.add_argument("--bayes", type=int, default=0, help="Bayesian fits of the law")
    parser.add_argument("--out", default="adequacy_velocity_only", help="results file stem")
    args = parser.parse_args()
    rows = [one("law, velocity", 0.0, ("velocity",), s) for s in range(args.runs)]
    for s in range(args.power_runs):
        rows.append(one("zeta+20%, velocity", 0.2, ("velocity",), s))
        rows.append(one("law, both", 0.0, ("displacement", "velocity"), s))
    cases = {}
    for r in rows:
        cases.setdefault(r["case"], []).append(r)
    table = {name: summary(rs) for name, rs in cases.items()}
    for name, s in table.items():
        counts = ", ".join(f"{s[f'failed_at_{lv:.4g}']} at {100 * lv:.3g} %" for lv in LEVELS)
        print(
            f"{name:20s} failed {counts} of {s['runs']}; median p {s['median_p']:.3g}; "
            f"{s['cpu_s_median']:.2f} s CPU (median)",
            flush=True,
        )
    fits = [bayes(s) for s in range(args.bayes)]
    for name in ("zeta", "mu_k") if fits else ():
        z = np.array([f[name]["z"] for f in fits])
        print(f"Bayesian fit, {name}: z {z.mean():+.2f} ± {z.std(ddof=1):.2f}", flush=True)
    path = write_results(args.out, {"summary": table, "runs": rows, "bayes": fits})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
