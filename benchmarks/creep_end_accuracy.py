"""Π of a power drag whose creep ends at a given time, against ``solve_ivp``.

A power drag below α = 1 ends its motion by an overdamped creep; summed to the end of
motion with ``creep_end`` (:meth:`bayestribo.model.laws.Law.pi_grid`), the creep is
integrated up to that time, where a record's detected stop would be. For α in
{0.3, 0.5, 0.7, 0.9}, ζ_α in {0.2, 0.5, 0.8} and ends inside the creep (and one before
it starts), Π at the grid points before the end is compared with ``solve_ivp``'s
∫_τ^end E (y'' = -y - c|y'|^α sgn y', ∫E a third state) by LSODA and by Radau at rtol
1e-12, relative to Π(0); also the ∫E past the end that the creep to rest would add
(NaN where it diverges, α <= 1/3). Writes ``results/NAME.json``::

    python benchmarks/creep_end_accuracy.py --output creep_end_accuracy
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from _machine import write_results
from scipy.integrate import solve_ivp

from bayestribo.model.laws import get_law
from bayestribo.model.laws.base import harmonic_power_integral
from bayestribo.model.laws.integrator import compiled_law

Y0 = 1.0
TAU = np.linspace(0.0, 40.0, 81)


def _c(zeta: float, alpha: float) -> float:
    return 2.0 * math.pi * zeta * Y0 ** (1.0 - alpha) / harmonic_power_integral(alpha + 1.0)


def _reference(zeta: float, alpha: float, end: float, method: str) -> np.ndarray:
    c = _c(zeta, alpha)

    def rhs(t, s):
        y, v, _ = s
        return [v, -y - c * abs(v) ** alpha * np.sign(v), 0.5 * (y * y + v * v)]

    sol = solve_ivp(
        rhs, (0.0, end), [Y0, 0.0, 0.0], method=method, rtol=1e-12, atol=1e-16, dense_output=True
    )
    return sol.y[2, -1] - sol.sol(TAU[TAU < end])[2]


def _creep_start(zeta: float, alpha: float) -> float:
    module = compiled_law(*get_law("power")._layout[0])
    times, _ = module.turns(Y0, np.array([_c(zeta, alpha), alpha]), 1.0, 0.0, math.inf, 10_000)
    return float(times[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="creep_end_accuracy")
    args = parser.parse_args()
    law = get_law("power")
    rows = []
    for alpha in (0.3, 0.5, 0.7, 0.9):
        for zeta in (0.2, 0.5, 0.8):
            start = _creep_start(zeta, alpha)
            ends = sorted({round(start + d, 2) for d in (0.75, 3.0, 12.0, 30.0)})
            if start > 2.0:
                ends.insert(0, round(0.5 * start, 2))  # before the creep starts
            for end in ends:
                values = {"zeta_alpha": np.array([zeta]), "alpha": np.array([alpha])}
                pi = law.pi_grid(TAU, values, [Y0], reference=Y0, creep_end=end)[0]
                rest = law.pi_grid(TAU, values, [Y0], reference=Y0)[0]
                before = TAU < end
                # before the creep starts, the reference ends at its start
                ref_end = max(end, start)
                row = {
                    "alpha": alpha,
                    "zeta_alpha": zeta,
                    "creep_start": start,
                    "end": end,
                    "grid_points_before_end": int(before.sum()),
                    "past_end_to_rest_over_pi0": float((rest[0] - pi[0]) / pi[0]),
                    "zero_past_end": bool(np.all(pi[TAU >= ref_end] == 0.0)),
                }
                for method in ("LSODA", "Radau"):
                    ref = _reference(zeta, alpha, ref_end, method)
                    n = ref.size
                    row[f"max_error_over_pi0_{method}"] = float(
                        np.max(np.abs(pi[:n] - ref)) / ref[0]
                    )
                rows.append(row)
                print(
                    f"α {alpha} ζ_α {zeta} creep from τ {start:.2f}, end {end}: "
                    f"LSODA {row['max_error_over_pi0_LSODA']:.1e}, "
                    f"Radau {row['max_error_over_pi0_Radau']:.1e} of Π(0); "
                    f"to rest adds {row['past_end_to_rest_over_pi0']:.1e}"
                )
    lsoda = [r["max_error_over_pi0_LSODA"] for r in rows]
    print(f"{len(rows)} cases: LSODA {min(lsoda):.1e} to {max(lsoda):.1e} of Π(0)")
    write_results(args.output, {"cases": rows, "tau": TAU.tolist()})


if __name__ == "__main__":
    main()
