"""Coverage of fits of accelerometer records (a velocity integrated from an acceleration).

Each run is simulated by ``benchmarks/_accel_sim.py`` (its own ``solve_ivp`` of
m ẍ + c ẋ + k x + μ_k N sgn ẋ + m q ẋ|ẋ| = 0, sticking when |k x| <= μ_s N,
independent of the package) on a spring-mass rig sliding on a flat (m = 0.25 kg,
f = 2.5 Hz, N = m g), sampled as an accelerometer would at 200 Hz: the mean acceleration
over each sample interval, a constant bias (± 0.5 m/s², and in half the runs a
smartphone's share of gravity, 9.3 to 9.8 m/s²) and white noise of 0.01 to 0.03 m/s²
per sample (log-uniform: 100 to 300 µg/√Hz, MEMS and phone sensors), 2 s of rest
before the release and 3 s after the stop (a drag-only record ends in motion, when the
viscous decay alone would be at e⁻⁴ of the release; where the swing fades into the
noise before, the analysis ends at the last turning point above it, with a
``FadeWarning``, :mod:`bayestribo.signal.decay`).
The record is written as a CSV with one column ``acceleration_m_per_s2`` (and the
time) and read by :func:`bayestribo.read_run`, which integrates it
(:mod:`bayestribo.io.acceleration`), then fitted:

* ``coulomb``: ζ ~ U(0.003, 0.01), μ_k ~ U(0.01, 0.03), μ_s/μ_k ~ U(1.1, 1.5),
  x₀ ~ U(30, 50) mm; ``bayestribo.fit(run)`` (viscous+coulomb), ζ and μ_k checked;
* ``viscous``: ζ ~ U(0.01, 0.04), no contact (``load_N`` 0), x₀ ~ U(20, 40) mm;
  ``fit(run)``, ζ₀ checked;
* ``quadratic``: quadratic drag q ~ U(0.5, 2) m⁻¹ per unit mass and ζ ~ U(0.005, 0.01),
  no contact; ``fit(run, law="auto")``, the drag's coefficient c₂ = q m [kg/m] checked
  when the law chosen holds it (the law chosen is reported).

The sensor's gain: the records are exact (gain 1) and their sidecars state no
``gain_uncertainty``, so each fit draws the default for an accelerometer (5 %, implied
by the acceleration the run is read from; 1 %, a sensor of unstated kind's, before
commit "An acceleration implies an accelerometer's gain uncertainty", which the
``acceleration_gain_*`` results below predate: ``--gain-uncertainty 0.01`` gives their
setting today; :mod:`bayestribo.signal.sensor`) into μ_k, whose posterior sd it makes
most of (its share of μ_k's variance is recorded per run). ``--gain-error SD`` multiplies each
record's acceleration by a gain 1 + ε, ε ~ N(0, SD²) drawn per run (its own random
stream: the records are otherwise the same), the error a real sensor's calibration
has; ``--gain-uncertainty U`` states U in the sidecar (``0``: the data's part of the
intervals alone).

A parameter is *covered* when the truth is in the 95 % interval of a fit that raised
no :class:`~bayestribo.errors.MisfitWarning` or ConvergenceWarning (nor a kind of
either, such as ``ShortAnalysisWarning``: the command's exit 1; before commit
"benchmarks/acceleration: a kind of MisfitWarning flags a fit", those two classes
alone); *flagged* when the fit warned (whatever its interval); *silently wrong* when it
did not warn and missed.
z = (posterior mean − truth) / posterior sd.

Run::

    nice -n 10 python benchmarks/acceleration.py --runs 20 --workers 2
    # the sensor's gain: exact and stated so, and drawn at 1 % with none stated
    python benchmarks/acceleration.py --runs 96 --cases coulomb --gain-uncertainty 0 \
        --output acceleration_gain_stated_zero
    python benchmarks/acceleration.py --runs 96 --cases coulomb --gain-error 0.01 \
        --output acceleration_gain_error

Runs are appended to ``benchmarks/results/acceleration_runs.jsonl`` (``--resume``);
writes ``benchmarks/results/acceleration.json`` (``--output NAME``: ``NAME_runs.jsonl``
and ``NAME.json``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _accel_sim as sim

RESULTS = Path(__file__).resolve().parent / "results"
CASES = ("coulomb", "viscous", "quadratic")
FLAGS = ("MisfitWarning", "ConvergenceWarning")


def flags(caught: list[warnings.WarningMessage]) -> list[str]:
    """The warnings of ``caught`` that flag a fit, by name: a warning is a flag when its
    class is one of :data:`FLAGS` or a kind of one (``ShortAnalysisWarning``,
    ``OffsetDriftWarning``, ... are MisfitWarnings: the command exits 1 on them)."""
    return sorted(
        {
            w.category.__name__
            for w in caught
            if any(c.__name__ in FLAGS for c in w.category.__mro__)
        }
    )


def draw(case: str, seed: int) -> tuple[sim.Rig, dict, dict]:
    """The rig, the record's settings and the truth of run ``seed`` of ``case``."""
    rng = np.random.default_rng([CASES.index(case), seed])
    noise = float(np.exp(rng.uniform(math.log(0.01), math.log(0.03))))
    bias = float(rng.uniform(-0.5, 0.5))
    if seed % 2:
        bias += float(sim.G * math.cos(rng.uniform(0.0, 0.35)))  # a phone's gravity
    settings = {"noise": noise, "bias": bias, "seed": seed + 1000}
    if case == "coulomb":
        mu = float(rng.uniform(0.01, 0.03))
        rig = sim.Rig(
            zeta=float(rng.uniform(0.003, 0.01)),
            mu_k=mu,
            mu_s_ratio=float(rng.uniform(1.1, 1.5)),
        )
        settings["x0"] = float(rng.uniform(0.03, 0.05))
        truth = {"zeta": rig.zeta, "mu_k": rig.mu_k}
    elif case == "viscous":
        rig = sim.Rig(zeta=float(rng.uniform(0.01, 0.04)))
        settings["x0"] = float(rng.uniform(0.02, 0.04))
        settings["duration"] = 4.0 / (rig.zeta * rig.omega)  # ends at e^-4 of x0
        truth = {"zeta0": rig.zeta}
    else:
        rig = sim.Rig(zeta=float(rng.uniform(0.005, 0.01)), q=float(rng.uniform(0.5, 2.0)))
        settings["x0"] = float(rng.uniform(0.03, 0.05))
        settings["duration"] = 4.0 / (rig.zeta * rig.omega)
        truth = {"c2_SI": rig.q * rig.mass}
    return rig, settings, truth


def sensor_gain(case: str, seed: int, sd: float) -> float:
    """The sensor's gain 1 + ε of run ``seed`` of ``case``, ε ~ N(0, sd²) (1 for sd 0).

    Its own random stream: the run's motion, noise and bias are those of ``draw``."""
    if sd == 0.0:
        return 1.0
    return 1.0 + sd * float(np.random.default_rng([CASES.index(case), seed, 1]).normal())


def one(
    case: str, seed: int, gain_error: float = 0.0, gain_uncertainty: float | None = None
) -> dict:
    """Simulate, write, read and fit one run; its record.

    ``gain_error``: relative sd of the sensor's gain drawn into the record;
    ``gain_uncertainty``: stated in the sidecar (None: not stated)."""
    import bayestribo
    from bayestribo.errors import MisfitWarning

    rig, settings, truth = draw(case, seed)
    x0 = settings.pop("x0")
    gain = sensor_gain(case, seed, gain_error)
    rec = sim.record(rig, x0, gain=gain, **settings)
    load = rig.load if case == "coulomb" else 0.0
    meta = {"load_N": load, "mass_kg": rig.mass, "natural_frequency_Hz": rig.f_Hz}
    if gain_uncertainty is not None:
        meta["gain_uncertainty"] = gain_uncertainty
    out = {"case": case, "seed": seed, "truth": truth, "noise": settings["noise"]}
    out["bias"] = settings["bias"]
    out["gain"] = gain
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "accel.csv"
        rows = np.column_stack([rec["time"], rec["acceleration"]])
        np.savetxt(path, rows, delimiter=",", header="time_s,acceleration_m_per_s2", comments="")
        (Path(tmp) / "accel.json").write_text(json.dumps(meta))
        start = time.process_time()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                run = bayestribo.read_run(path)
                result = bayestribo.fit(run, law="auto" if case == "quadratic" else None)
            except Exception as exc:  # recorded, never dropped
                out["error"] = f"{type(exc).__name__}: {exc}"
                return out
        out["cpu_s"] = time.process_time() - start
    out["bias_read"] = run.metadata["acceleration"]["bias"]
    out["flags"] = flags(caught)
    # every warning of the package's, by name, and whether the command would exit 1 on
    # them (a MisfitWarning or any of its kinds)
    ours = [w for w in caught if type(w.message).__module__.startswith("bayestribo")]
    out["warnings"] = sorted({type(w.message).__name__ for w in ours})
    out["misfit_kind"] = any(issubclass(w.category, MisfitWarning) for w in ours)
    out["law"] = result.law
    sensor = result.sensor or {}
    out["gain_sd"] = sensor.get("gain_sd")
    out["gain_variance_share"] = sensor.get("variance_share")
    diagnostics = result.diagnostics
    if diagnostics.get("chi2_map") is not None and diagnostics.get("n_increments"):
        out["chi2_per_n"] = diagnostics["chi2_map"] / diagnostics["n_increments"]
    summary = result.summary(prob=0.95)
    out["parameters"] = {}
    for name, value in truth.items():
        key = name if name in summary else {"zeta0": "zeta"}.get(name, name)
        if key not in summary:
            continue
        s = summary[key]
        low, high = s.interval
        out["parameters"][name] = {
            "mean": s.mean,
            "sd": s.sd,
            "interval": [low, high],
            "covered": bool(low <= value <= high),
            "z": (s.mean - value) / s.sd if s.sd > 0 else None,
        }
    return out


def summarise(records: list[dict]) -> dict:
    """Covered / flagged / silently wrong and z statistics per case and parameter."""
    out: dict = {}
    for case in CASES:
        mine = [r for r in records if r["case"] == case]
        errors = [r for r in mine if "error" in r]
        entry: dict = {"runs": len(mine), "errors": len(errors), "parameters": {}}
        entry["error_messages"] = [r["error"][:200] for r in errors]
        entry["laws"] = {}
        for r in mine:
            if "law" in r:
                entry["laws"][r["law"]] = entry["laws"].get(r["law"], 0) + 1
        names = sorted({n for r in mine for n in r.get("truth", {})})
        for name in names:
            fitted = [r for r in mine if name in r.get("parameters", {})]
            flagged = [r for r in fitted if r["flags"]]
            quiet = [r for r in fitted if not r["flags"]]
            z = [r["parameters"][name]["z"] for r in fitted if r["parameters"][name]["z"]]
            entry["parameters"][name] = {
                "fitted": len(fitted),
                "not_in_the_law_chosen": len([r for r in mine if "law" in r]) - len(fitted),
                "covered": sum(r["parameters"][name]["covered"] for r in quiet),
                "flagged": len(flagged),
                "flagged_and_covered": sum(r["parameters"][name]["covered"] for r in flagged),
                "silently_wrong": sum(not r["parameters"][name]["covered"] for r in quiet),
                "coverage_all_fits": (
                    sum(r["parameters"][name]["covered"] for r in fitted) / len(fitted)
                    if fitted
                    else None
                ),
                "z_mean": float(np.mean(z)) if z else None,
                "z_sd": float(np.std(z, ddof=1)) if len(z) > 1 else None,
            }
        chi2 = [r["chi2_per_n"] for r in mine if r.get("chi2_per_n") is not None]
        entry["chi2_per_n_median"] = float(np.median(chi2)) if chi2 else None
        entry["chi2_per_n_range"] = [float(min(chi2)), float(max(chi2))] if chi2 else None
        shares = [(r.get("gain_variance_share") or {}).get("mu_k") for r in mine]
        shares = [v for v in shares if v is not None]
        entry["mu_k_gain_variance_share_median"] = float(np.median(shares)) if shares else None
        cpu = [r["cpu_s"] for r in mine if "cpu_s" in r]
        entry["median_cpu_s"] = float(np.median(cpu)) if cpu else None
        out[case] = entry
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--report-only", action="store_true")
    parser.add_argument(
        "--gain-error",
        type=float,
        default=0.0,
        metavar="SD",
        help="relative sd of the sensor's gain drawn into each record (default 0: exact)",
    )
    parser.add_argument(
        "--gain-uncertainty",
        type=float,
        default=None,
        metavar="U",
        help="gain_uncertainty stated in each sidecar (default: none stated, the "
        "package's default for a sensor of unstated kind)",
    )
    parser.add_argument(
        "--output",
        default="acceleration",
        metavar="NAME",
        help="results/NAME.json and results/NAME_runs.jsonl (default: acceleration)",
    )
    args = parser.parse_args(argv)
    if not (math.isfinite(args.gain_error) and 0.0 <= args.gain_error < 0.3):
        parser.error(f"--gain-error: expected a relative sd in [0, 0.3), got {args.gain_error}")
    if args.gain_uncertainty is not None and not 0.0 <= args.gain_uncertainty <= 0.5:
        parser.error(
            f"--gain-uncertainty: expected a value in [0, 0.5], got {args.gain_uncertainty}"
        )
    runs_path = RESULTS / f"{args.output}_runs.jsonl"
    summary_path = RESULTS / f"{args.output}.json"
    RESULTS.mkdir(exist_ok=True)
    done: list[dict] = []
    if (args.resume or args.report_only) and runs_path.exists():
        done = [json.loads(line) for line in runs_path.read_text().splitlines() if line.strip()]
    elif runs_path.exists():
        runs_path.unlink()
    if not args.report_only:
        have = {(r["case"], r["seed"]) for r in done}
        todo = [(c, s) for c in args.cases for s in range(args.runs) if (c, s) not in have]
        with ProcessPoolExecutor(args.workers) as pool:
            cases, seeds = zip(*todo, strict=True) if todo else ((), ())
            n = len(cases)
            options = ([args.gain_error] * n, [args.gain_uncertainty] * n)
            for record in pool.map(one, cases, seeds, *options) if todo else []:
                done.append(record)
                with runs_path.open("a") as handle:
                    handle.write(json.dumps(record) + "\n")
                print(json.dumps(record)[:300], flush=True)
    import subprocess

    commit = subprocess.run(
        ["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=RESULTS
    ).stdout.strip()
    summary = {
        "commit": commit,
        "gain_error": args.gain_error,
        "gain_uncertainty": args.gain_uncertainty,
        "cases": summarise(done),
    }
    summary_path.write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
