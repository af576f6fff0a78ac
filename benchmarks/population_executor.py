"""The campaign's population analysis in series and on a 2-process pool, side by side.

A campaign of per-run posteriors shaped like the bundled programme (glycerol at five
loads and glycerol-water at six water fractions, three repeats each, and three runs in
air; per-run posteriors normal around values drawn from the populations, 300 draws each,
the sampler's default settings) is analysed by
:func:`bayestribo.campaign.analysis.analyse_campaign` without an executor and with a
:class:`concurrent.futures.ProcessPoolExecutor` of 2 workers, alternately, ``--repeats``
times each. The results must be identical (same seeds per group); the wall times are
compared by their medians, with the machine's load average at the start and the end.

Run: ``python benchmarks/population_executor.py [--repeats 3]``. Prints a table and writes
``benchmarks/results/population_executor.json``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

from bayestribo.campaign.analysis import analyse_campaign

RIG = {"mass_kg": 0.035, "natural_frequency_Hz": 32.6}


class _Fit:
    """A per-run posterior as the analysis reads it (samples, prior, metadata)."""

    def __init__(self, samples: dict[str, np.ndarray], metadata: dict[str, Any]) -> None:
        self._samples, self.metadata = samples, metadata
        self.parameter_names = list(samples)
        self.converged = True

    def samples(self, name: str) -> np.ndarray:
        return self._samples[name]

    def prior_logpdf(self, name: str, values: np.ndarray) -> np.ndarray:
        return np.where((values > 0) & (values < 0.3), -math.log(0.3), -np.inf)


def campaign(rng: np.random.Generator) -> list[_Fit]:
    """Runs shaped like the bundled programme."""
    fits = []
    for load in (0.07, 0.12, 0.31, 0.46, 0.59):
        for r in range(3):
            z, m = rng.normal(0.0236, 0.0012), rng.normal(0.0294, 0.0036)
            meta = {"run_id": f"g-N{load}-r{r}", "lubricant": "glycerol", "load_N": load, **RIG}
            meta["water_mass_fraction"] = 0.0055
            samples = {"zeta": rng.normal(z, 2e-5, 300), "mu_k": rng.normal(m, 5e-5, 300)}
            fits.append(_Fit(samples, meta))
    for w in (0.05, 0.1, 0.15, 0.2, 0.25, 0.3):
        for r in range(3):
            z, m = rng.normal(0.02 - 0.03 * w, 0.001), rng.normal(0.029, 0.0036)
            meta = {"run_id": f"gw-{w}-r{r}", "lubricant": "glycerol-water", "load_N": 0.31}
            meta.update(RIG, water_mass_fraction=w)
            samples = {"zeta": rng.normal(z, 2e-5, 300), "mu_k": rng.normal(m, 5e-5, 300)}
            fits.append(_Fit(samples, meta))
    for r in range(3):
        meta = {"run_id": f"air-r{r}", "lubricant": "none", "load_N": 0.0, **RIG}
        fits.append(_Fit({"zeta": rng.normal(rng.normal(0.0033, 1e-4), 1e-6, 300)}, meta))
    return fits


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    fits = campaign(np.random.default_rng(args.seed))
    load_start = os.getloadavg()
    times: dict[str, list[float]] = {"series": [], "2 processes": []}
    reference = None
    identical = True
    with ProcessPoolExecutor(max_workers=2) as pool:
        pool.submit(int, 0).result()  # workers started before the clock
        for _ in range(args.repeats):
            for label, executor in (("series", None), ("2 processes", pool)):
                start = time.perf_counter()
                analysis = analyse_campaign(fits, seed=args.seed, executor=executor)
                times[label].append(time.perf_counter() - start)
                rows = (analysis.group_rows(), analysis.trend_rows())
                reference = rows if reference is None else reference
                identical &= rows == reference
    load_end = os.getloadavg()
    median = {k: statistics.median(v) for k, v in times.items()}
    print(f"{'configuration':14s} {'median s':>9s}  all runs")
    for label, values in times.items():
        print(f"{label:14s} {median[label]:9.1f}  {', '.join(f'{v:.1f}' for v in values)}")
    speed_up = median["series"] / median["2 processes"]
    print(f"speed-up {speed_up:.2f}; identical results: {identical}")
    print(f"load average (1, 5, 15 min): start {load_start}, end {load_end}")
    path = write_results(
        "population_executor",
        {
            "runs": len(fits),
            "repeats": args.repeats,
            "seconds": times,
            "median_s": median,
            "speed_up": speed_up,
            "identical_results": bool(identical),
            "load_average_start": load_start,
            "load_average_end": load_end,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
