"""The level and power of ``law="auto"``'s halves' check (``inference/halves.py``).

Independent ``solve_ivp`` records (``tests/_law_recording.py``, the simulator of the
halves' tests): a rig of the law ``viscous+coulomb`` (ζ = 0.005, μ_k N/m as the bundled
runs, 2.5 s at 5 kHz), the same with its friction 0.5 % and 1 % higher from a quarter
of the run on (the halves some 3 and 6 sd apart), and a rig of quadratic drag fitted
with ``quadratic`` (a law without a closed form: its halves' draws from the quadratic
surrogate). Each record is checked
with :func:`bayestribo.inference.halves.law_halves` at seed 1; recorded per record:
the verdict, the p-value, the largest |z|, each half's effective draws, and the CPU
time of the check.

Run once per tree, the tree on ``PYTHONPATH``::

    PYTHONPATH=/tmp/base nice -n 10 python benchmarks/halves_level.py --runs 30 \
        --output halves_level_base
    PYTHONPATH=. nice -n 10 python benchmarks/halves_level.py --runs 30 \
        --output halves_level

Writes ``benchmarks/results/NAME.json``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
from _machine import commit, write_results  # noqa: E402

OMEGA = 2 * math.pi * 32.6
FRICTION = 0.02 * 0.31 / 0.035  # μ_k N/m [m/s²]


def _record(case: str, seed: int) -> tuple[Any, str]:
    """The simulated run of ``case`` and the law to check its halves with."""
    from _law_recording import law_recording

    def viscous(v: float) -> float:
        return 2.0 * 0.005 * OMEGA * v

    if case == "constant":
        return law_recording(viscous, friction=FRICTION, x0=1e-3, duration_s=2.5, seed=seed), (
            "viscous+coulomb"
        )
    if case.startswith("friction+"):
        rise = 1.0 + float(case.split("+")[1].rstrip("%")) / 100.0
        run = law_recording(
            viscous,
            friction=FRICTION,
            x0=1e-3,
            duration_s=2.5,
            seed=seed,
            friction_change=(0.25, rise * FRICTION),
        )
        return run, "viscous+coulomb"
    if case == "quadratic":
        run = law_recording(
            lambda v: 40.0 * v * abs(v), load_N=None, x0=1e-3, duration_s=2.5, seed=seed
        )
        return run, "quadratic"
    raise ValueError(f"case: unknown {case!r}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument(
        "--cases", nargs="*", default=["constant", "friction+0.5%", "friction+1%", "quadratic"]
    )
    parser.add_argument("--output", default="halves_level")
    args = parser.parse_args()

    import bayestribo
    from bayestribo.inference.halves import HALVES_P, law_halves
    from bayestribo.inference.preparation import prepare

    rows: list[dict[str, Any]] = []
    for case in args.cases:
        for seed in range(args.runs):
            run, law = _record(case, seed)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                prepared = prepare(run)
                cpu = time.process_time()
                h = law_halves(prepared, law, seed=1)
                cpu = time.process_time() - cpu
            rows.append(
                {
                    "case": case,
                    "seed": seed,
                    "law": law,
                    "tested": h.tested,
                    "agree": h.agree,
                    "p_value": h.p_value,
                    "largest_z": h.largest_z,
                    "draws": [h.first.get("draws"), h.second.get("draws")],
                    "cpu_seconds": cpu,
                    "note": h.note,
                }
            )
            print(case, seed, h.agree, f"{h.p_value:.3g}", f"{h.largest_z:.2f}", f"{cpu:.2f}")
    summary = {}
    for case in args.cases:
        mine = [r for r in rows if r["case"] == case and r["tested"]]
        summary[case] = {
            "tested": len(mine),
            "disagree": sum(not r["agree"] for r in mine),
            "p_below_0.05": sum(r["p_value"] < 0.05 for r in mine),
            "cpu_seconds_total": sum(r["cpu_seconds"] for r in mine),
        }
    write_results(
        args.output,
        {
            "commit": commit(Path(bayestribo.__file__).resolve().parents[1]),
            "halves_p": HALVES_P,
            "summary": summary,
            "rows": rows,
        },
    )
    print(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
