"""Per-law calibration of the true-law fits of ``benchmarks/laws.py``: one z per run.

A calibration statistic needs independent z values. The 12 swings at which a fit
reports ΔE(A) are not independent (for viscous damping ΔE = πcωA² at every swing: one
run has the same z at all of them), so a run gives one z per quantity: each sampled
parameter, and ΔE(A) at three fixed swings of the reported ones (the smallest, the
middle and the largest), each its own row. Over the runs of one law and noise level:

* coverage of the 95 % interval, with its Clopper-Pearson 95 % interval;
* mean(z) ± se and sd(z) ± se, se(sd) = sd/√(2(n-1)) (1 when calibrated), and
  ``sd_off`` = (sd - 1)/se, the distance of sd(z) from 1 in its standard errors.

μ_s/μ_k is reported but is not a calibration quantity: its posterior is bounded by
where the decay did and did not stick (an interval of the prior, not a normal), and is
the prior wherever the decay does not end on a stick.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from _chain import clopper_pearson

__all__ = [
    "DISSIPATION_ROWS",
    "NOT_CALIBRATION",
    "calibration",
    "print_calibration",
    "rate",
    "run_quantities",
    "z_stats",
]

#: ΔE(A) rows: the name and which of the reported swings (sorted by amplitude).
DISSIPATION_ROWS = ("ΔE(A_min)", "ΔE(A_mid)", "ΔE(A_max)")
#: Parameters reported but left out of the calibration (see the module's docstring).
NOT_CALIBRATION = frozenset({"mu_s_ratio"})


def rate(k: int, n: int) -> dict[str, Any]:
    """k of n, the rate and its Clopper-Pearson 95 % interval."""
    return {"covered": k, "of": n, "rate": k / n if n else None, "ci95": clopper_pearson(k, n)}


def z_stats(z: list[float]) -> dict[str, float] | None:
    """n, mean ± se, sd ± se (sd/√(2(n-1))), (sd - 1)/se and max |z| of the finite z;
    None for fewer than two."""
    a = np.asarray(z, dtype=float)
    a = a[np.isfinite(a)]
    n = a.size
    if n < 2:
        return None
    sd = float(a.std(ddof=1))
    se = sd / math.sqrt(2 * (n - 1))
    return {
        "n": n,
        "mean": float(a.mean()),
        "mean_se": sd / math.sqrt(n),
        "sd": sd,
        "sd_se": se,
        "sd_off": (sd - 1.0) / se if se > 0 else math.nan,
        "max_abs": float(np.abs(a).max()),
    }


def _swing_indices(amplitudes: list[float]) -> dict[str, int]:
    order = np.argsort(np.asarray(amplitudes, dtype=float))
    return {
        DISSIPATION_ROWS[0]: int(order[0]),
        DISSIPATION_ROWS[1]: int(order[order.size // 2]),
        DISSIPATION_ROWS[2]: int(order[-1]),
    }


def run_quantities(fit: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """One true-law fit's record (``run["true_fit"]``) as quantity -> its z and
    coverage (in the true frame, and in the package's frame for the parameters)."""
    out: dict[str, dict[str, Any]] = {}
    if "error" in fit:
        return out
    for name, p in fit.get("parameters", {}).items():
        lo, hi = p["interval"]
        out[name] = {
            "z": p["z"],
            "covered": bool(p["covered"]),
            "z_in_package_frame": p.get("z_in_package_frame", math.nan),
            "covered_in_package_frame": bool(lo <= p.get("truth_in_package_frame", math.nan) <= hi),
            "amplitude_m": None,
        }
    d = fit.get("dissipation")
    if d and d.get("z"):
        for row, i in _swing_indices(d["amplitude_m"]).items():
            out[row] = {
                "z": d["z"][i],
                "covered": bool(d["covered"][i]),
                "amplitude_m": d["amplitude_m"][i],
            }
    return out


def _quantity_stats(per_run: list[dict[str, Any]]) -> dict[str, Any]:
    row: dict[str, Any] = {
        "coverage": rate(sum(q["covered"] for q in per_run), len(per_run)),
        "z": z_stats([q["z"] for q in per_run]),
    }
    if "z_in_package_frame" in per_run[0]:
        row["coverage_in_package_frame"] = rate(
            sum(q["covered_in_package_frame"] for q in per_run), len(per_run)
        )
        row["z_in_package_frame"] = z_stats([q["z_in_package_frame"] for q in per_run])
    amps = [q["amplitude_m"] for q in per_run if q["amplitude_m"] is not None]
    if amps:
        row["median_amplitude_m"] = float(np.median(amps))
    return row


def calibration(records: list[dict[str, Any]], cases: dict[str, tuple]) -> dict[str, Any]:
    """Per case (with a registered true law) and noise level: per quantity, the coverage
    and z statistics over the runs (one z per run); and ``pooled`` over the cases: the
    parameters (less μ_s/μ_k) and ΔE(A_mid)."""
    table: dict[str, Any] = {}
    pooled_par: list[dict[str, Any]] = []
    pooled_de: list[dict[str, Any]] = []
    for case, (law, *_rest) in cases.items():
        if law is None:
            continue
        for noise in sorted({r["noise"] for r in records}):
            rows = [r for r in records if r["case"] == case and r["noise"] == noise]
            if not rows:
                continue
            fits = [r.get("true_fit", {"error": "missing"}) for r in rows]
            ok = [f for f in fits if "error" not in f]
            per_run = [run_quantities(f) for f in ok]
            names = list(dict.fromkeys(k for q in per_run for k in q))
            quantities = {}
            for name in names:
                values = [q[name] for q in per_run if name in q]
                quantities[name] = _quantity_stats(values)
                quantities[name]["calibration_quantity"] = name not in NOT_CALIBRATION
                if name == DISSIPATION_ROWS[1]:
                    pooled_de.extend(values)
                elif name not in NOT_CALIBRATION and name not in DISSIPATION_ROWS:
                    pooled_par.extend(values)
            table[f"{case}@{noise:g}x"] = {
                "law": law,
                "runs": len(rows),
                "errors": [
                    {"index": r["index"], "error": f["error"]}
                    for r, f in zip(rows, fits, strict=True)
                    if "error" in f
                ],
                "not_converged": sum(not f.get("converged", False) for f in ok),
                "warned": {
                    w: sum(w in f.get("warnings", []) for f in ok)
                    for w in sorted({w for f in ok for w in f.get("warnings", [])})
                },
                "quantities": quantities,
            }
    pooled = {
        "parameters": _quantity_stats(pooled_par) if pooled_par else None,
        DISSIPATION_ROWS[1]: _quantity_stats(pooled_de) if pooled_de else None,
    }
    return {"per_law": table, "pooled": pooled}


def _cell(r: dict[str, Any] | None) -> str:
    if not r or not r["of"]:
        return "-"
    lo, hi = r["ci95"]
    return (
        f"{r['covered']:3d}/{r['of']:<3d} {100 * r['rate']:3.0f} [{100 * lo:2.0f}-{100 * hi:3.0f}]"
    )


def _zcell(z: dict[str, Any] | None) -> str:
    if not z:
        return "-"
    return (
        f"{z['mean']:+.2f}±{z['mean_se']:.2f}  {z['sd']:.2f}±{z['sd_se']:.2f} ({z['sd_off']:+.1f})"
    )


def print_calibration(cal: dict[str, Any]) -> None:
    """The per-law table: coverage % [CP 95 %], mean(z) ± se, sd(z) ± se ((sd-1)/se)."""
    print(
        "\nPer-law calibration of the true-law fit, one z per run and quantity "
        "(μ_s/μ_k in brackets: not a calibration quantity)"
    )
    head = f"{'case@noise':28s} {'quantity':10s} {'covered % [CP 95 %]':>24s}"
    print(f"{head}  {'mean(z)':>10s}  {'sd(z) ((sd-1)/se)':>18s}  max|z|  pkg-frame sd(z)")
    for key, row in cal["per_law"].items():
        extra = f"  not converged {row['not_converged']}" if row["not_converged"] else ""
        if row["errors"]:
            extra += f"  errors {len(row['errors'])}"
        print(f"{key:28s} {row['law']} ({row['runs']} runs){extra}")
        for name, q in row["quantities"].items():
            label = name if q["calibration_quantity"] else f"[{name}]"
            z = q["z"]
            frame = (
                _zcell(q.get("z_in_package_frame")).split("  ")[-1]
                if "z_in_package_frame" in q
                else ""
            )
            print(
                f"{'':28s} {label:10s} {_cell(q['coverage']):>24s}  {_zcell(z):>32s}  "
                f"{z['max_abs'] if z else math.nan:5.2f}  {frame}"
            )
    for name, q in cal["pooled"].items():
        if q:
            print(f"{'pooled':28s} {name:10s} {_cell(q['coverage']):>24s}  {_zcell(q['z']):>32s}")
