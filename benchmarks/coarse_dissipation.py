"""The law-free ΔE(A) of a coarse digitiser's record against the simulation's own energy.

Each record is an independent simulation (``benchmarks/_damped.py``: solve_ivp half
cycle by half cycle of a 32.6 Hz oscillator from 2 mm with viscous, Coulomb, quadratic or
mixed damping, 10 kHz), both channels rounded to ``steps`` levels across the swing on
levels placed at random (``numpy.random.default_rng([5, steps, noise_code, i])``: the
placement, then the white noise of ``noise`` steps before rounding). The record's energy
decay is measured as a fit measures it (:func:`bayestribo.signal.decay.energy_decay`),
and the law-free ΔE(A) (:func:`bayestribo.inference.dissipation.turning_point_dissipation`)
read off two sets of turning points at the same swings:

* ``levels``: the decay's turning points (parabolas through the staircase's extremes),
  as the package read them before :mod:`bayestribo.signal.staircase`;
* ``staircase``: those the fit now uses (:func:`bayestribo.inference.law_free.
  law_free_turning_points`: the staircase's where the displacement is coarse).

At each reported swing A the 95 % interval is held against the true ΔE/k at A
(``x_n² − x_n+1²`` of the simulation's turning points, interpolated log-log). Per
configuration: the records refused (the message), the swings covered (fraction), the
mean relative error of the mean, the swings whose mean is below zero and those whose
whole interval is (an :class:`~bayestribo.errors.EnergyGainWarning`), and the mean z.

Run (by hand)::

    nice python benchmarks/coarse_dissipation.py --runs 20

Writes ``benchmarks/results/coarse_dissipation.json`` (``--output NAME``).
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
from _damped import DAMPINGS, quantise, simulate, true_dissipation  # noqa: E402
from _machine import commit, write_results  # noqa: E402

META = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31, "gain_uncertainty": 0.0}
STEPS = (3, 4, 5, 10)
NOISES = (0.0, 0.05, 0.2)


class _Prepared:
    """The parts of a PreparedRun the law-free turning points read."""

    def __init__(self, run: Any, decay: Any) -> None:
        self.run, self.decay, self.name = run, decay, "simulated"


def one_record(decay: Any, name: str, steps: float, noise: float, index: int) -> dict[str, Any]:
    """Round one simulation and read its law-free ΔE(A) both ways."""
    from bayestribo.inference.dissipation import (
        dissipation_amplitudes,
        turning_point_dissipation,
    )
    from bayestribo.inference.law_free import law_free_turning_points
    from bayestribo.io.run import Run
    from bayestribo.model.laws import PhysicalScale
    from bayestribo.signal.decay import energy_decay

    rng = np.random.default_rng([5, int(steps), round(100 * noise), index])
    placement = tuple(float(u) for u in rng.uniform(-0.5, 0.5, 2))
    x, v = quantise(decay, steps, placement, noise, rng)
    out: dict[str, Any] = {"damping": name, "index": index, "placement_steps": placement}
    run = Run(time=decay.t, displacement=x, velocity=v, metadata=META)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            measured = energy_decay(decay.t, x, v, rig=run.rig())
            stair, used = law_free_turning_points(_Prepared(run, measured), warn_levels=False)
    except Exception as exc:  # recorded, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"[:200]
        return out
    ell = measured.scaling.length_scale
    out["staircase_used"] = used
    out["turning_points"] = [len(measured.peaks), int(stair.size)]
    # the swings the fit reports: those of the turning points it reads
    swings = dissipation_amplitudes(stair * ell)
    truth = true_dissipation(decay.turning, swings)
    for key, values in (("levels", measured.peaks.value), ("staircase", stair * ell)):
        band = turning_point_dissipation(values, swings, PhysicalScale(1.0, 1.0, "m"))
        if band is None:
            out[key] = None
            continue
        mean = np.asarray(band["mean"])
        sd = np.asarray(band["sd"])
        lo, hi = (np.asarray(b) for b in band["interval"])
        ok = np.isfinite(truth)
        out[key] = {
            "swings": int(ok.sum()),
            "covered": int(np.sum((lo <= truth) & (truth <= hi) & ok)),
            "relative_error": float(np.mean((mean[ok] - truth[ok]) / truth[ok])),
            "negative_mean": int(np.sum(mean < 0)),
            "below_zero": int(np.sum(hi < 0)),
            "z_mean": float(np.mean((mean[ok] - truth[ok]) / sd[ok])),
        }
    return out


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per way of reading: records answered, swings covered, error and sign."""
    answered = [r for r in rows if "refused" not in r]
    table: dict[str, Any] = {
        "records": len(rows),
        "refused": len(rows) - len(answered),
        "refusals": sorted({r["refused"][:90] for r in rows if "refused" in r}),
        "staircase_used": sum(bool(r.get("staircase_used")) for r in answered),
    }
    for key in ("levels", "staircase"):
        got = [r[key] for r in answered if r.get(key)]
        swings = sum(g["swings"] for g in got)
        table[key] = {
            "answered": len(got),
            "swings": swings,
            "coverage": (sum(g["covered"] for g in got) / swings) if swings else None,
            "relative_error_mean": float(np.mean([g["relative_error"] for g in got]))
            if got
            else None,
            "z_mean": float(np.mean([g["z_mean"] for g in got])) if got else None,
            "negative_mean": sum(g["negative_mean"] for g in got),
            "below_zero": sum(g["below_zero"] for g in got),
        }
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="placements per configuration")
    parser.add_argument("--output", default="coarse_dissipation")
    args = parser.parse_args()
    sims = {name: simulate(*params) for name, params in DAMPINGS.items()}
    configs: list[dict[str, Any]] = []
    for steps in STEPS:
        for noise in NOISES:
            for name, decay in sims.items():
                rows = [one_record(decay, name, steps, noise, i) for i in range(args.runs)]
                entry = {"steps": steps, "noise_steps": noise, "damping": name}
                entry["summary"] = summarise(rows)
                entry["rows"] = rows
                configs.append(entry)
                s = entry["summary"]
                print(
                    f"{steps:>2} steps noise {noise:<4} {name:<9} refused {s['refused']:>2} "
                    + " ".join(
                        f"{k}: cov {s[k]['coverage'] or float('nan'):.3f} "
                        f"err {s[k]['relative_error_mean'] or float('nan'):+.2f} "
                        f"neg {s[k]['negative_mean']} below0 {s[k]['below_zero']}"
                        for k in ("levels", "staircase")
                    ),
                    flush=True,
                )
    overall = {}
    for key in ("levels", "staircase"):
        for steps in STEPS:
            got = [c["summary"][key] for c in configs if c["steps"] == steps]
            swings = sum(g["swings"] for g in got)
            covered = sum((g["coverage"] or 0.0) * g["swings"] for g in got)
            overall[f"{key}_{steps}"] = {
                "swings": swings,
                "coverage": covered / swings if swings else None,
                "below_zero": sum(g["below_zero"] for g in got),
                "negative_mean": sum(g["negative_mean"] for g in got),
            }
    path = write_results(
        args.output,
        {
            "commit": commit(),
            "runs": args.runs,
            "seeds": "numpy.random.default_rng([5, steps, round(100 * noise), i])",
            "dampings": {k: list(v) for k, v in DAMPINGS.items()},
            "overall": overall,
            "configs": configs,
        },
    )
    print(path)


if __name__ == "__main__":
    main()
