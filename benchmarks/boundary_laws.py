"""Coverage of every parameter of a multi-term law when the truth sits on a bound of its
prior: a term that the record does not have (no quadratic drag, no friction, no
viscous damping, no power-law drag), fitted with ``law=`` a law that holds it.

The records are those of ``benchmarks/boundary_truth.py`` (its designs ``low``, ``mid``,
``high``; 1 Hz, 0.1 m released at rest, 30 periods, white noise of sd A/SNR; a
displacement without load or mass, so Coulomb friction is the friction displacement
x_c), simulated independently of the package: viscous damping and Coulomb friction in
closed form half cycle by half cycle (:func:`boundary_truth.simulate`), quadratic drag
alone, ``x'' + ω² x = -c₂ x'|x'|``, by ``scipy.integrate.solve_ivp`` (DOP853, rtol
1e-11). The amount of each term is set so that the record loses the design's fraction
of its amplitude: for quadratic drag alone, 1/A_N - 1/A_0 = (8/3) c₂ N over N periods.

Cases (record → law; the truth on a bound in brackets):

==========  ==========================  ===============================  =============
case        record                      law                              on its bound
==========  ==========================  ===============================  =============
vq_c0       viscous damping             viscous+quadratic                c₂ = 0
vq_z0       quadratic drag              viscous+quadratic                ζ = 0
cq_c0       Coulomb friction            coulomb+quadratic                c₂ = 0
cq_xc0      quadratic drag              coulomb+quadratic                x_c = 0
vcq_c0      viscous + Coulomb (½ each)  viscous+coulomb+quadratic        c₂ = 0
cp_za0      Coulomb friction            coulomb+power                    ζ_α = 0
ch_eta0     Coulomb friction            coulomb+hysteretic               (η = 0 inside)
==========  ==========================  ===============================  =============

Each record is fitted with :func:`bayestribo.fit` (``seed=1``, ``law=`` the case's law);
the 95 % interval of every parameter with a truth (ζ, x_c, c₂ per unit mass, ζ_α, η, and
μ_s/μ_k = 1: the closed form sticks at μ_s = μ_k) is recorded against it, as the
summary gives it (a quantity piled on its bound 0 has 0 as its lower end), with the
result's ``boundary`` record where the package has one. μ_s/μ_k is recorded but not
a boundary of a term (its 1 is the bound of its own prior, and it is not identified
on a record that does not stop).

Run: ``python benchmarks/boundary_laws.py --runs 20 --out
benchmarks/results/boundary_laws_after.json`` (``PYTHONPATH`` chooses the package).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import warnings
import zlib
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from boundary_truth import AMPLITUDE, DESIGNS, FREQUENCY, PERIODS, simulate

#: case: (record kind, law). Record kinds: "viscous", "coulomb", "both" (half of the
#: loss each), "quadratic".
CASES: dict[str, tuple[str, str]] = {
    "vq_c0": ("viscous", "viscous+quadratic"),
    "vq_z0": ("quadratic", "viscous+quadratic"),
    "cq_c0": ("coulomb", "coulomb+quadratic"),
    "cq_xc0": ("quadratic", "coulomb+quadratic"),
    "vcq_c0": ("both", "viscous+coulomb+quadratic"),
    "cp_za0": ("coulomb", "coulomb+power"),
    "ch_eta0": ("coulomb", "coulomb+hysteretic"),
}
#: summary quantity of each parameter with a truth, by the truth's key
QUANTITIES = {
    "zeta": "zeta",
    "xc": "friction_displacement",
    "c2": "c2_per_mass",
    "zeta_alpha": "zeta_alpha",
    "eta": "eta",
    "mu_s_ratio": "mu_s_ratio",
}


def quadratic(c2: float, t: np.ndarray) -> np.ndarray:
    """Displacement [m] of ``x'' + ω² x = -c₂ x'|x'|`` released at rest at AMPLITUDE,
    at times ``t`` [s]; ``c2`` in 1/m."""
    from scipy.integrate import solve_ivp

    omega = 2 * math.pi * FREQUENCY

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        x, v = s
        return [v, -(omega**2) * x - c2 * v * abs(v)]

    sol = solve_ivp(
        rhs, (0.0, float(t[-1])), [AMPLITUDE, 0.0], method="DOP853", t_eval=t,
        rtol=1e-11, atol=1e-13 * AMPLITUDE, max_step=0.01 / FREQUENCY,
    )  # fmt: skip
    return sol.y[0]


def truth(design: dict[str, float], kind: str) -> dict[str, float]:
    """The truth of a record of ``kind`` that loses about ``design["loss"]`` of its
    amplitude over the record: ζ, x_c [m], c₂ [1/m] (and ζ_α, η: 0)."""
    omega = 2 * math.pi * FREQUENCY
    loss = design["loss"]
    zeta_all = -math.log(1 - loss) / (omega * PERIODS / FREQUENCY)
    xc_all = loss * AMPLITUDE / (4 * PERIODS)
    c2_all = loss / ((1 - loss) * AMPLITUDE * (8 / 3) * PERIODS)
    share = {"viscous": (1, 0, 0), "coulomb": (0, 1, 0), "both": (0.5, 0.5, 0)}
    share["quadratic"] = (0, 0, 1)
    z, x, c = share[kind]
    out = {"zeta": z * zeta_all, "xc": x * xc_all, "c2": c * c2_all}
    out |= {"zeta_alpha": 0.0, "eta": 0.0}
    if x > 0:  # sticking at μ_s = μ_k
        out["mu_s_ratio"] = 1.0
    return out


def record(design: str, kind: str, seed: int, folder: Path) -> tuple[dict[str, float], Path]:
    """A simulated record of ``kind`` in ``design``, written to ``folder``: the truth
    and the file."""
    d = DESIGNS[design]
    true = truth(d, kind)
    t = np.arange(0, PERIODS / FREQUENCY, 1 / (FREQUENCY * d["per_period"]))
    if kind == "quadratic":
        x = quadratic(true["c2"], t)
    else:
        x = simulate(true["zeta"], true["xc"], t)
    rng = np.random.default_rng([seed, zlib.crc32(design.encode()), zlib.crc32(kind.encode())])
    x = x + rng.normal(0, AMPLITUDE / d["snr"], t.size)
    path = folder / f"{design}_{kind}_{seed}.csv"
    np.savetxt(path, np.c_[t, x], delimiter=",", header="time_s,displacement_m", comments="")
    return true, path


def one_run(design: str, case: str, seed: int, folder: Path) -> dict:
    import bayestribo as bt

    kind, law = CASES[case]
    true, path = record(design, kind, seed, folder)
    run = bt.read_run(path)
    cpu = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            r = bt.fit(run, seed=1, law=law)
        except Exception as exc:  # recorded, not hidden
            return {"design": design, "case": case, "seed": seed, "error": repr(exc)}
    cpu = time.process_time() - cpu
    summ = r.summary()
    out: dict[str, Any] = {
        "design": design,
        "case": case,
        "seed": seed,
        "law": r.law,
        "cpu_s": cpu,
        "truth": true,
        "warnings": sorted({type(w.message).__name__ for w in caught}),
        "converged": bool(r.converged),
        "interval": {},
        "covered": {},
    }
    for key, name in QUANTITIES.items():
        if name in summ:
            lo, hi = summ[name].interval
            out["interval"][key] = [float(lo), float(hi)]
            out["covered"][key] = bool(key in true and lo <= true[key] <= hi)
    boundary = getattr(r.record, "boundary", None)
    if boundary is not None:
        out["boundary"] = boundary
        out["mixed"] = boundary.get("mixed", [])
    return out


def table(rows: list[dict]) -> dict[str, dict[str, Any]]:
    """Coverage of each parameter by case and design, and the nested laws mixed in."""
    out: dict[str, dict[str, Any]] = {}
    for row in rows:
        cell = out.setdefault(
            f"{row['case']}/{row['design']}", {"n": 0, "errors": 0, "covered": {}, "mixed": {}}
        )
        if "error" in row:
            cell["errors"] += 1
            continue
        cell["n"] += 1
        for key, hit in row["covered"].items():
            if key == "mu_s_ratio" and row["truth"]["xc"] == 0.0:
                continue  # no friction: μ_s/μ_k has no truth
            cell["covered"][key] = cell["covered"].get(key, 0) + int(hit)
        mixed = (
            ", ".join(row["boundary"]["nested"][name]["law"] for name in row.get("mixed", []))
            or "none"
        )
        cell["mixed"][mixed] = cell["mixed"].get(mixed, 0) + 1
        cell["cpu_s"] = [*cell.get("cpu_s", []), row["cpu_s"]]
    for cell in out.values():
        cell["cpu_median_s"] = float(np.median(cell.pop("cpu_s", [math.nan])))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--designs", default=",".join(DESIGNS))
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--out", required=True)
    parser.add_argument(
        "--collect",
        nargs="+",
        default=None,
        help="write --out from the rows these runs' outputs printed (runs split in parts)",
    )
    args = parser.parse_args()
    from _machine import commit, machine

    import bayestribo

    package = Path(bayestribo.__file__).parent.parent
    if args.collect:
        by_key: dict[tuple, dict] = {}
        for log in args.collect:
            for line in Path(log).read_text().splitlines():
                if line.startswith('{"design"'):
                    row = json.loads(line)
                    by_key.setdefault((row["design"], row["case"], row["seed"]), row)
        rows = list(by_key.values())
    else:
        rows = []
        with tempfile.TemporaryDirectory() as tmp:
            for seed in range(args.first, args.first + args.runs):
                for case in args.cases.split(","):
                    for design in args.designs.split(","):
                        row = one_run(design, case, seed, Path(tmp))
                        rows.append(row)
                        print(json.dumps(row), flush=True)
    result = {
        "machine": machine(),
        "package": str(package),
        "commit": commit(package),
        "cases": {k: {"record": v[0], "law": v[1]} for k, v in CASES.items()},
        "coverage": table(rows),
        "runs": rows,
    }
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result["coverage"], indent=1))


if __name__ == "__main__":
    main()
