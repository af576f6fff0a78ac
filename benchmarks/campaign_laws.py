"""Campaigns in any law: group laws, population coverage and load trends (issue 40's goal).

Each campaign is a folder of independently simulated runs (``benchmarks/_laws_sim.py``:
solve_ivp half cycle by half cycle, nothing from the package's models) of two
lubricants at three loads, three repeats each:

* ``drag-oil``: viscous damping and quadratic drag, ζ ~ N(0.004, 0.0004) and
  c₂ ~ N(0.5, 0.05) kg/m per run;
* ``power-grease``: Coulomb friction and power-law drag, μ_k ~ N(0.03, 0.003),
  ζ_α ~ N(0.005, 0.0005) at the release amplitude, α ~ N(1.5, 0.05) per run.

The spread between repeats is the known σ of each draw; the population means do not
change with the load (every true load trend is flat). Each campaign is analysed by
the command line a user runs, ``bayestribo campaign DIR --law auto --json`` (or
``--law given``: each lubricant's folder with its true law, the populations alone),
and scored:

* the group law: each (lubricant, load) group's law is the true one;
* coverage: each group's population mean and between-run σ of every quantity of the
  true law, 95 % intervals, against the generating values (target 93–97 %). ζ_α is
  drawn at the release amplitude x₀ and the fit measures it at the run's first
  analysed swing (one oscillation later, a few per cent lower): it is scored apart
  (``own_amplitude``), as the campaign says of it;
* trends: the 95 % band of each quantity's slope against the load covers 0.

Run (in the background; a campaign of 18 runs takes minutes)::

    timeout 10000 python benchmarks/campaign_laws.py --campaigns 20 --law auto

Results accumulate campaign by campaign in
``benchmarks/results/campaign_laws_<law>.json``, each with the package's commit;
``--resume`` keeps the campaigns already there and runs only the seeds it lacks.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _laws_sim as sim
from _machine import commit, machine

RESULTS = Path(__file__).resolve().parent / "results"
LOADS = (0.1, 0.2, 0.3)
REPEATS = 3
X0 = 1.0e-3
DURATION = 1.5
#: Each lubricant: its true law, and each quantity's population mean and σ.
LUBRICANTS = {
    "drag-oil": {
        "law": "viscous+quadratic",
        "quantities": {"zeta": (0.004, 0.0004), "c2_SI": (0.5, 0.05)},
    },
    "power-grease": {
        "law": "coulomb+power",
        "quantities": {"mu_k": (0.03, 0.003), "zeta_alpha": (0.005, 0.0005), "alpha": (1.5, 0.05)},
    },
}


def _truth(lubricant: str, values: dict[str, float], load: float) -> sim.Truth:
    """The simulator's law of one run with these quantities at this load."""
    sim.LOAD = load  # the simulator's friction and ℓ = N/k read the load at call time
    if lubricant == "drag-oil":
        return sim.Truth(zeta=values["zeta"], q=values["c2_SI"] / sim.MASS)
    unit = sim.Truth(mu_k=values["mu_k"], b=1.0, alpha=values["alpha"], static_ratio=1.2)
    scale = unit.dimensionless(X0)["zeta_alpha"]  # ζ_α of b = 1, at x₀
    return sim.Truth(
        mu_k=values["mu_k"], b=values["zeta_alpha"] / scale, alpha=values["alpha"], static_ratio=1.2
    )


def write_campaign(folder: Path, seed: int) -> dict[str, dict[str, float]]:
    """Simulate one campaign's runs into ``folder``; return each run's true values."""
    rng = np.random.default_rng(seed)
    truths = {}
    for lubricant, spec in LUBRICANTS.items():
        for load in LOADS:
            for repeat in range(1, REPEATS + 1):
                values = {q: float(rng.normal(m, s)) for q, (m, s) in spec["quantities"].items()}
                truth = _truth(lubricant, values, load)
                t, x, v, _ = sim.simulate(
                    truth,
                    x0=X0,
                    fs=5000.0,
                    duration=DURATION,
                    noise=10.0,
                    seed=[seed, int(1000 * load), repeat, len(lubricant)],
                )
                name = f"{lubricant}-N{load}-r{repeat}"
                sub = folder / lubricant
                sub.mkdir(parents=True, exist_ok=True)
                np.savetxt(
                    sub / f"{name}.csv",
                    np.column_stack([t, x, v]),
                    delimiter=",",
                    header="time_s,displacement_m,velocity_m_per_s",
                    comments="",
                    fmt="%.10g",
                )
                meta = {
                    **sim.metadata(),
                    "load_N": load,
                    "lubricant": lubricant,
                    "repeat": repeat,
                    "run_id": name,
                    "gain_uncertainty": 0.0,
                }
                (sub / f"{name}.json").write_text(json.dumps(meta, indent=1))
                truths[name] = values
    return truths


def _campaign(folder: Path, law: str | None, out: Path, seed: int) -> tuple[dict, float]:
    cmd = [sys.executable, "-m", "bayestribo", "campaign", str(folder), "--out", str(out)]
    cmd += ["--json", "--quiet", "--seed", str(seed), "--no-figures", "--workers", "2"]
    cmd += ["--by", "lubricant,load_N"]
    if law:
        cmd += ["--law", law]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    if done.returncode == 2 or not done.stdout.strip():
        raise RuntimeError(f"campaign failed ({done.returncode}): {done.stderr[-2000:]}")
    return json.loads(done.stdout), seconds


def _inside(summary: dict, value: float) -> bool:
    low, high = summary["interval"]
    return low <= value <= high


def score(report: dict, lubricant_of: dict[str, str]) -> dict:
    """Group laws, coverage of every group's mean and σ, and the trends' bands."""
    out: dict = {"laws": [], "coverage": [], "trends": []}
    for label, g in (report.get("group_laws") or {}).items():
        lubricant = lubricant_of[g["runs"][0]]
        out["laws"].append(
            {
                "group": label,
                "law": g["law"],
                "true": LUBRICANTS[lubricant]["law"],
                "right": g["law"] == LUBRICANTS[lubricant]["law"],
                "disagree": g["disagree"],
            }
        )
    for g in (report.get("contact") or {}).get("groups", []):
        lubricant = lubricant_of[g["runs"][0]]
        spec = LUBRICANTS[lubricant]
        for name, (mean, sigma) in spec["quantities"].items():
            entry = (g.get("parameters") or {}).get(name)
            if entry is None:
                continue  # another law than the true one: no such quantity
            out["coverage"].append(
                {
                    "own_amplitude": name == "zeta_alpha",
                    "group": g["label"],
                    "quantity": name,
                    "mean_covered": _inside(entry["mean"], mean),
                    "sigma_covered": _inside(entry["sigma"], sigma),
                    "mean_z": (entry["mean"]["mean"] - mean) / entry["mean"]["sd"],
                    "converged": g.get("diagnostics", {}).get("converged"),
                }
            )
    for label, t in (report.get("trends") or {}).items():
        for name, entry in (t.get("parameters") or {}).items():
            covers = _inside(entry["slope"], 0.0)
            out["trends"].append({"series": label, "quantity": name, "covers_flat": covers})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=int, default=20)
    parser.add_argument("--law", choices=("auto", "given"), default="auto")
    parser.add_argument("--first-seed", type=int, default=1)
    parser.add_argument(
        "--resume",
        action="store_true",
        help="keep the campaigns already in the results file and skip their seeds",
    )
    args = parser.parse_args()
    path = RESULTS / f"campaign_laws_{args.law}.json"
    results = {"machine": machine(), "settings": vars(args), "campaigns": []}
    if args.resume and path.exists():
        results["campaigns"] = json.loads(path.read_text())["campaigns"]
    done_seeds = {c["seed"] for c in results["campaigns"]}
    tree = commit(short=True, unknown="unknown")
    for seed in range(args.first_seed, args.first_seed + args.campaigns):
        if seed in done_seeds:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / "runs"
            truths = write_campaign(folder, seed)
            lubricant_of = {n: n.rsplit("-N", 1)[0] for n in truths}
            scored: dict = {"laws": [], "coverage": [], "trends": []}
            seconds = 0.0
            if args.law == "auto":
                report, seconds = _campaign(folder, "auto", Path(tmp) / "out", seed)
                scored = score(report, lubricant_of)
            else:
                for lubricant, spec in LUBRICANTS.items():
                    report, s = _campaign(
                        folder / lubricant, spec["law"], Path(tmp) / f"out-{lubricant}", seed
                    )
                    seconds += s
                    part = score(report, lubricant_of)
                    for key in scored:
                        scored[key].extend(part[key])
        results["campaigns"].append({"seed": seed, "commit": tree, "seconds": seconds, **scored})
        results["summary"] = summarise(results["campaigns"])
        path.write_text(json.dumps(results, indent=1) + "\n")
        print(json.dumps({"seed": seed, "seconds": round(seconds), **results["summary"]}))


def summarise(campaigns: list[dict]) -> dict:
    """Rates over the campaigns so far."""
    laws = [x for c in campaigns for x in c["laws"]]
    everything = [x for c in campaigns for x in c["coverage"]]
    cov = [x for x in everything if not x.get("own_amplitude")]
    own = [x for x in everything if x.get("own_amplitude")]
    trends = [x for c in campaigns for x in c["trends"]]

    def rate(items: list, key: str) -> float | None:
        return None if not items else float(np.mean([bool(x[key]) for x in items]))

    z = [x["mean_z"] for x in cov if x["mean_z"] is not None and math.isfinite(x["mean_z"])]
    return {
        "n_campaigns": len(campaigns),
        "group_law_right": rate(laws, "right"),
        "n_groups": len(laws),
        "mean_coverage": rate(cov, "mean_covered"),
        "sigma_coverage": rate(cov, "sigma_covered"),
        "n_intervals": len(cov),
        "mean_z_sd": float(np.std(z)) if z else None,
        "trend_covers_flat": rate(trends, "covers_flat"),
        "n_trends": len(trends),
        "populations_converged": rate(cov, "converged"),
        "own_amplitude_mean_coverage": rate(own, "mean_covered"),
        "own_amplitude_mean_z": float(np.mean([x["mean_z"] for x in own])) if own else None,
    }


if __name__ == "__main__":
    main()
