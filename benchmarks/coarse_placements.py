"""A coarse digitiser's levels placed at random: the calibration ``steps-10`` cannot show.

The ``steps-10`` case of ``benchmarks/misspecification.py`` rounds both channels of the
independent simulation (``benchmarks/_chain.py``: solve_ivp half cycle by half cycle,
the paper's rig, ζ = 0.0236, μ_k = 0.0294, 10 kHz) to a tenth of their swing, with levels
at whole multiples of the step from the zero. Its white noise (1.5 µm, 0.15 µm/s) is a
thousandth of a step: its 20 runs are one rounded record twenty times, and its coverage
is one draw. Here run ``i`` places the levels of each channel at an offset drawn
uniformly over a step (``numpy.random.default_rng([77, i])``), the noise from
``[77, i, 1]``; the fit is :func:`bayestribo.fit` with seed ``i``. Per run: refused (the
message), the z and coverage of ζ and μ_k, and the flags (MisfitWarning,
ChannelCalibrationWarning, ConvergenceWarning, PriorBoundWarning).

Run (by hand)::

    nice python benchmarks/coarse_placements.py --steps 10 --runs 20

``--skip 0`` fits with the first oscillation kept, as the refusal of a record too short
for the skipped one advises. ``--velocity-steps N`` rounds the velocity to its own count
of steps across its swing (``--steps 0``: the displacement is not rounded), so that the
velocity swings over a few steps only near the stop; ``--velocity-only`` fits the
velocity alone (the displacement is not given).

Writes ``benchmarks/results/coarse_placements_<steps>.json`` (``--output NAME``).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _chain import MU_K, ZETA, apply_chain, metadata, record  # noqa: E402
from _machine import commit, write_results  # noqa: E402
from _outcome import against_truth, flags_of  # noqa: E402

FLAGS = ("MisfitWarning", "ChannelCalibrationWarning", "ConvergenceWarning", "PriorBoundWarning")
TRUTH = {"zeta": ZETA, "mu_k": MU_K}
#: ``--decay viscous``: no contact, ζ = 0.005, 3 s of motion after 0.1 s of rest (the
#: swing falls to 5 % of itself, where the record ends in motion); the fit has no load,
#: so ζ alone is its parameter.
VISCOUS_ZETA = 0.005
DECAYS = {
    "paper": (
        lambda: record(10_000.0, 0.1, 0.1),
        metadata,
        TRUTH,
    ),
    "viscous": (
        lambda: record(10_000.0, 0.1, 0.0, zeta=VISCOUS_ZETA, mu_k=0.0, duration=3.0),
        lambda: {**metadata(), "load_N": 0.0},
        {"zeta": VISCOUS_ZETA},
    ),
}


def one_run(
    steps: float,
    index: int,
    skip: int = 1,
    *,
    velocity_steps: float | None = None,
    velocity_only: bool = False,
    decay: str = "paper",
) -> dict[str, Any]:
    """Round run ``index`` to ``steps`` across the swing (the velocity to
    ``velocity_steps``, default ``steps``; 0: not rounded) on levels placed at random,
    fit it (the velocity alone with ``velocity_only``), and say how its intervals stand
    against the truth (``decay``: a key of :data:`DECAYS`)."""
    from bayestribo import fit
    from bayestribo.io.run import Run

    simulate, meta, truth_of = DECAYS[decay]
    t, x, v = simulate()
    rng = np.random.default_rng([77, index])
    xs, vs = apply_chain(t, x, v, 10_000.0, seed=[77, index, 1], noise=10.0)
    ux, uv = rng.uniform(-0.5, 0.5, 2)
    vsteps = steps if velocity_steps is None else velocity_steps
    if steps > 0:
        qx = np.ptp(x) / steps
        xs = (np.round(xs / qx + ux) - ux) * qx
    if vsteps > 0:
        qv = np.ptp(v) / vsteps
        vs = (np.round(vs / qv + uv) - uv) * qv
    out: dict[str, Any] = {"index": index, "placement_steps": [float(ux), float(uv)]}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(
                Run(
                    time=t,
                    displacement=None if velocity_only else xs,
                    velocity=vs,
                    metadata=meta(),
                ),
                seed=index,
                skip_oscillations=skip,
            )
    except Exception as exc:  # recorded, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    out["flags"] = flags_of(caught, FLAGS)
    out.update(against_truth(result, truth_of))
    return out


def summarise(rows: list[dict[str, Any]], truth: dict[str, float] = TRUTH) -> dict[str, Any]:
    """Refused, covered (every parameter of ``truth``), flagged, missed, silently wrong
    (|z| > 3.29 unflagged), and z's mean and sd per parameter over the fitted runs."""
    fitted = [r for r in rows if "refused" not in r]
    both = [r for r in fitted if all(r[p]["covered"] for p in truth)]
    uncovered = [r for r in fitted if r not in both]
    table: dict[str, Any] = {
        "runs": len(rows),
        "refused": len(rows) - len(fitted),
        "covered": len(both),
        "flagged": sum(bool(r["flags"]) for r in uncovered),
        "missed": sum(not r["flags"] for r in uncovered),
        "silently_wrong": sum(
            1 for r in fitted if not r["flags"] and max(abs(r[p]["z"]) for p in truth) > 3.2905
        ),
        "warned": sum(bool(r["flags"]) for r in fitted),
    }
    for p in truth:
        z = np.array([r[p]["z"] for r in fitted])
        table[f"z_{p}"] = (
            {"mean": float(z.mean()), "sd": float(z.std(ddof=1))} if z.size > 1 else None
        )
        table[f"covered_{p}"] = sum(r[p]["covered"] for r in fitted)
    return table


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, default=10.0, help="steps across the swing")
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument(
        "--skip", type=int, default=1, help="oscillations skipped after the release (the fit's)"
    )
    parser.add_argument(
        "--velocity-steps",
        type=float,
        default=None,
        help="the velocity's steps across its swing (default --steps; 0: not rounded)",
    )
    parser.add_argument("--velocity-only", action="store_true", help="fit the velocity alone")
    parser.add_argument(
        "--decay",
        choices=sorted(DECAYS),
        default="paper",
        help="the simulated decay: the paper's rig (friction, sticks) or a viscous fade",
    )
    parser.add_argument("--output", default=None, help="results/NAME.json")
    args = parser.parse_args(argv)
    if args.steps < 0 or (args.velocity_steps is not None and args.velocity_steps < 0):
        parser.error("--steps, --velocity-steps: expected a count >= 0 (0: not rounded)")
    rows = []
    for i in range(args.runs):
        rows.append(
            one_run(
                args.steps,
                i,
                args.skip,
                velocity_steps=args.velocity_steps,
                velocity_only=args.velocity_only,
                decay=args.decay,
            )
        )
        print(rows[-1], flush=True)
    truth = DECAYS[args.decay][2]
    table = summarise(rows, truth)
    print(table)
    name = args.output or f"coarse_placements_{args.steps:g}"
    path = write_results(
        name,
        {
            "source": commit(),
            "steps": args.steps,
            "velocity_steps": args.velocity_steps,
            "velocity_only": args.velocity_only,
            "skip": args.skip,
            "decay": args.decay,
            "truth": truth,
            "table": table,
            "runs": rows,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
