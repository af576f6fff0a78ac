"""The independence Metropolis-Hastings move in the fit's mix, side by side with the DE moves alone.

In one process, fit by fit alternating, for seeds 1..``--seeds`` of each case: the fit
as it is (``SamplerSettings.independence`` 0: the DE/snooker mix alone, main's sampler
path to the bit) and the fit with the independence move in its mix after an adaptation
phase (``--weight``, ``--adapt``; :mod:`bayestribo.inference.independence`), the
stopping rule unchanged. Cases: the bundled runs ``--runs`` with the default law, and
the bundled run ``glycerol-N0.31-r1`` with each law of ``--laws``.

Reported per fit and as medians per case and setting: process CPU time of the fit and
of its sampler (``run_ensembles``), steps, the sampler's CPU per step, τ (the longest),
ESS (the smallest), log-posterior calls per effective sample (steps × walkers / ESS),
the move's weight and expected acceptance, and the first check at which the rule's
ESS and 20 τ held (τ settled and R-hat left aside: the steps the run could have
stopped at, were τ's estimate settled); per case, the posterior means of the two
settings against each other in units of the posterior sd (mean and rms over seeds;
the Monte Carlo error of a difference of two means at ESS ≥ 1000 is about 0.045 sd).

``--population N``: N simulated campaigns of ``benchmarks/population.py`` (its
glycerol series, no trend; campaign seeds 100..100+N−1), the population sampler of
:func:`bayestribo.population.trend` (a load trend, 6 hyperparameters) and of
:func:`bayestribo.population.population` (4) with the move off
(``population.sampler.POPULATION_INDEPENDENCE`` = 0, main's sampler) and on, fit by
fit alternating: CPU, steps, τ, ESS, convergence, the move's acceptance, and the
posterior means and 95 % interval ends of the two against each other in units of
the posterior sd, and whether each covers the truth (the campaign's mean and zero
slope).

Run: ``python benchmarks/independence.py``; writes ``benchmarks/results/independence.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import commit, write_results

import bayestribo.inference.chains as chains_module
import bayestribo.inference.sampling as sampling
from bayestribo.inference import fit
from bayestribo.inference.spec import FitSpec

ROOT = Path(__file__).resolve().parents[1]
RUNS = ("glycerol-N0.31-r1", "air-r1", "glycerol-N0.07-r1")
LAWS = ("quadratic", "viscous+quadratic", "coulomb+hysteretic")


class Probe:
    """The sampler's settings for the next fit, and what its run did."""

    def __init__(self) -> None:
        self.weight = 0.0
        self.adapt = 100
        self.steps = 0
        self.checks: list[tuple[int, float]] = []
        self.run: Any = None
        self.sampler_cpu = 0.0

    def install(self) -> None:
        settings_of = FitSpec.sampler_settings
        probe = self

        def sampler_settings(spec):
            return dataclasses.replace(
                settings_of(spec), independence=probe.weight, adapt_steps=probe.adapt
            )

        FitSpec.sampler_settings = sampler_settings
        run_grouped = sampling._Grouped.run

        def run(ensembles, steps):
            run_grouped(ensembles, steps)
            probe.steps = ensembles.sampler.iteration

        sampling._Grouped.run = run
        taus = sampling._autocorr_times

        def autocorr_times(chains, c=5.0):
            out = taus(chains, c)
            probe.checks.append((probe.steps, float(np.max(out))))
            return out

        sampling._autocorr_times = autocorr_times
        run_ensembles = sampling.run_ensembles

        def timed(*args, **kwargs):
            start = time.process_time()
            result = run_ensembles(*args, **kwargs)
            probe.sampler_cpu += time.process_time() - start
            probe.run = result
            return result

        chains_module.run_ensembles = timed

    def reset(self, weight: float) -> None:
        self.weight = weight
        self.steps = 0
        self.checks = []
        self.sampler_cpu = 0.0


def _first_enough(checks, walkers: int, floor: int, multiple: float, min_ess: float) -> int | None:
    """The first check's steps at which ESS ≥ ``min_ess`` and ``multiple`` τ held."""
    for steps, tau in checks:
        if not math.isfinite(tau):
            continue
        burn = max(math.ceil(2 * tau), floor)
        kept = steps - burn
        if kept >= multiple * tau and kept * walkers / tau >= min_ess:
            return steps
    return None


def _one(probe: Probe, path: Path, seed: int, weight: float, law: str | None) -> dict:
    probe.reset(weight)
    kwargs = {} if law is None else {"law": law}
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(path, seed=seed, **kwargs)
    cpu = time.process_time() - start
    run = probe.run
    walkers = int(run.chains.shape[0] * run.walker_acceptance.shape[1])
    ess = float(np.min(run.ess))
    floor = probe.adapt if run.independence > 0 else 0
    return {
        "seed": seed,
        "weight": weight,
        "cpu_seconds": cpu,
        "sampler_cpu_seconds": probe.sampler_cpu,
        "converged": bool(result.converged),
        "steps": int(run.n_steps),
        "burn": int(run.burn),
        "sampler_cpu_per_step_us": 1e6 * probe.sampler_cpu / max(run.n_steps, 1),
        "tau_max": float(np.max(run.autocorr_time)),
        "tau": [float(t) for t in run.autocorr_time],
        "ess_min": ess,
        "calls_per_ess": run.n_steps * walkers / ess,
        "independence_weight": float(run.independence),
        "independence_acceptance": float(run.independence_acceptance),
        "first_enough_steps": _first_enough(probe.checks, walkers, floor, 20.0, 1000.0),
        "names": list(run.names),
        "mean": [float(np.mean(result.samples(n))) for n in run.names],
        "sd": [float(np.std(result.samples(n), ddof=1)) for n in run.names],
    }


def _medians(fits: list[dict]) -> dict:
    keys = (
        "cpu_seconds",
        "sampler_cpu_seconds",
        "steps",
        "sampler_cpu_per_step_us",
        "tau_max",
        "ess_min",
        "calls_per_ess",
        "independence_acceptance",
    )
    out = {k: float(np.median([f[k] for f in fits])) for k in keys}
    enough = [f["first_enough_steps"] for f in fits if f["first_enough_steps"] is not None]
    out["first_enough_steps"] = float(np.median(enough)) if enough else None
    out["converged"] = sum(f["converged"] for f in fits)
    out["ess_per_cpu_second"] = float(np.median([f["ess_min"] / f["cpu_seconds"] for f in fits]))
    return out


def _population_case(campaigns: int) -> dict:
    """The population sampler with the move off and on (see the module notes)."""
    import population as population_benchmark

    import bayestribo.population.sampler as population_sampler
    from bayestribo.population import population, trend

    weight = population_sampler.POPULATION_INDEPENDENCE
    seen: dict[str, Any] = {}
    sample = population_sampler.run_ensembles

    def kept(*args, **kwargs):
        seen["run"] = sample(*args, **kwargs)
        return seen["run"]

    population_sampler.run_ensembles = kept
    fits: dict[str, dict[str, list[dict]]] = {
        kind: {"off": [], "on": []} for kind in ("trend", "population")
    }
    for c in range(campaigns):
        runs = population_benchmark.campaign(np.random.default_rng(100 + c), np.zeros(2))
        for kind in fits:
            for setting in ("off", "on"):
                population_sampler.POPULATION_INDEPENDENCE = weight if setting == "on" else 0.0
                start = time.process_time()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    if kind == "trend":
                        trend(runs, "load_N", population_benchmark.PARAMS, seed=c)
                    else:
                        population(runs, population_benchmark.PARAMS, seed=c)
                cpu = time.process_time() - start
                run = seen["run"]
                flat = run.chains.reshape(-1, run.chains.shape[-1])
                fits[kind][setting].append(
                    {
                        "campaign": c,
                        "cpu_seconds": cpu,
                        "steps": int(run.n_steps),
                        "tau_max": float(np.max(run.autocorr_time)),
                        "ess_min": float(np.min(run.ess)),
                        "converged": bool(run.converged),
                        "independence_weight": float(run.independence),
                        "independence_acceptance": float(run.independence_acceptance),
                        "names": list(run.names),
                        "mean": flat.mean(axis=0).tolist(),
                        "sd": flat.std(axis=0, ddof=1).tolist(),
                        "low": np.quantile(flat, 0.025, axis=0).tolist(),
                        "high": np.quantile(flat, 0.975, axis=0).tolist(),
                    }
                )
    population_sampler.POPULATION_INDEPENDENCE = weight
    population_sampler.run_ensembles = sample
    truth = {
        "beta[0,zeta]": population_benchmark.MEAN[0],
        "beta[0,mu_k]": population_benchmark.MEAN[1],
        "beta[1,zeta]": 0.0,
        "beta[1,mu_k]": 0.0,
        "log_sigma[zeta]": float(np.log(population_benchmark.SIGMA[0])),
        "log_sigma[mu_k]": float(np.log(population_benchmark.SIGMA[1])),
    }
    out: dict[str, Any] = {"campaigns": campaigns, "weight": weight}
    for kind, both in fits.items():
        off, on = both["off"], both["on"]
        names = off[0]["names"]

        def shift(key: str, off=off, on=on) -> list[float]:
            return np.mean(
                [
                    (np.array(b[key]) - np.array(a[key])) / np.array(a["sd"])
                    for a, b in zip(off, on, strict=True)
                ],
                axis=0,
            ).tolist()

        def rms(key: str, off=off, on=on) -> list[float]:
            return np.sqrt(
                np.mean(
                    [
                        ((np.array(b[key]) - np.array(a[key])) / np.array(a["sd"])) ** 2
                        for a, b in zip(off, on, strict=True)
                    ],
                    axis=0,
                )
            ).tolist()

        def covered(fits_: list[dict], names=names) -> dict[str, int]:
            return {
                n: int(sum(f["low"][i] <= truth[n] <= f["high"][i] for f in fits_))
                for i, n in enumerate(names)
                if n in truth
            }

        def med(fits_: list[dict], key: str) -> float:
            return float(np.median([f[key] for f in fits_]))

        out[kind] = {
            "names": names,
            "cpu_ratio_on_off": med(on, "cpu_seconds") / med(off, "cpu_seconds"),
            "off": {k: med(off, k) for k in ("cpu_seconds", "steps", "tau_max", "ess_min")}
            | {"converged": int(sum(f["converged"] for f in off)), "covered_95": covered(off)},
            "on": {
                k: med(on, k)
                for k in (
                    "cpu_seconds",
                    "steps",
                    "tau_max",
                    "ess_min",
                    "independence_acceptance",
                )
            }
            | {"converged": int(sum(f["converged"] for f in on)), "covered_95": covered(on)},
            "mean_shift_sd": shift("mean"),
            "rms_mean_shift_sd": rms("mean"),
            "rms_low_shift_sd": rms("low"),
            "rms_high_shift_sd": rms("high"),
            "fits": both,
        }
        o, n = out[kind]["off"], out[kind]["on"]
        print(
            f"population {kind}: CPU {o['cpu_seconds']:.3f} -> {n['cpu_seconds']:.3f} s "
            f"({out[kind]['cpu_ratio_on_off']:.2f}x); steps {o['steps']:.0f} -> "
            f"{n['steps']:.0f}; tau {o['tau_max']:.1f} -> {n['tau_max']:.1f}; ESS "
            f"{o['ess_min']:.0f} -> {n['ess_min']:.0f}; converged {o['converged']} -> "
            f"{n['converged']} of {campaigns}; acceptance {n['independence_acceptance']:.2f}; "
            f"rms mean shift {np.round(out[kind]['rms_mean_shift_sd'], 3).tolist()} sd",
            flush=True,
        )
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="fits per case and setting")
    parser.add_argument("--weight", type=float, default=0.75, help="the move's weight")
    parser.add_argument("--adapt", type=int, default=100, help="adaptation steps")
    parser.add_argument("--runs", nargs="*", default=list(RUNS), help="bundled runs")
    parser.add_argument("--laws", nargs="*", default=list(LAWS), help="laws on the first run")
    parser.add_argument("--population", type=int, default=0, help="simulated campaigns")
    parser.add_argument("--output", default="independence", help="results/<output>.json")
    args = parser.parse_args()
    probe = Probe()
    probe.adapt = args.adapt
    probe.install()
    cases = [(run, None) for run in args.runs]
    cases += [(args.runs[0], law) for law in args.laws] if args.runs else []
    out: dict[str, Any] = {
        "commit": commit(),
        "settings": {"weight": args.weight, "adapt_steps": args.adapt, "seeds": args.seeds},
        "load_before": list(os.getloadavg()),
        "cases": [],
    }
    for run_name, law in cases:
        path = ROOT / "data" / "runs" / f"{run_name}.csv"
        for weight in (0.0, args.weight):  # warm-up: imports, compilation
            _one(probe, path, 0, weight, law)
        fits: dict[str, list[dict]] = {"off": [], "on": []}
        for seed in range(1, args.seeds + 1):
            fits["off"].append(_one(probe, path, seed, 0.0, law))
            fits["on"].append(_one(probe, path, seed, args.weight, law))
        shifts = np.array(
            [
                (np.array(on["mean"]) - np.array(off["mean"])) / np.array(off["sd"])
                for on, off in zip(fits["on"], fits["off"], strict=True)
            ]
        )
        case = {
            "run": run_name,
            "law": law or "default",
            "names": fits["off"][0]["names"],
            "off": _medians(fits["off"]),
            "on": _medians(fits["on"]),
            "mean_shift_sd": shifts.mean(axis=0).tolist(),
            "rms_shift_sd": np.sqrt((shifts**2).mean(axis=0)).tolist(),
            "fits": fits,
        }
        case["cpu_ratio_on_off"] = case["on"]["cpu_seconds"] / case["off"]["cpu_seconds"]
        case["calls_per_ess_ratio_off_on"] = (
            case["off"]["calls_per_ess"] / case["on"]["calls_per_ess"]
        )
        out["cases"].append(case)
        off, on = case["off"], case["on"]
        print(
            f"{run_name} {law or 'default'}: CPU {off['cpu_seconds']:.3f} -> "
            f"{on['cpu_seconds']:.3f} s ({case['cpu_ratio_on_off']:.2f}x); steps "
            f"{off['steps']:.0f} -> {on['steps']:.0f} (ESS and 20 tau first held at "
            f"{off['first_enough_steps']} -> {on['first_enough_steps']}); tau "
            f"{off['tau_max']:.1f} -> {on['tau_max']:.1f}; calls/ESS "
            f"{off['calls_per_ess']:.1f} -> {on['calls_per_ess']:.1f}; sampler us/step "
            f"{off['sampler_cpu_per_step_us']:.0f} -> {on['sampler_cpu_per_step_us']:.0f}; "
            f"acceptance {on['independence_acceptance']:.2f}; mean shift "
            f"{np.round(case['mean_shift_sd'], 3).tolist()} sd",
            flush=True,
        )
    if args.population:
        out["population"] = _population_case(args.population)
    out["load_after"] = list(os.getloadavg())
    print(write_results(args.output, out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
