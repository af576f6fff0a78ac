"""The optimiser of each law of ``law="auto"`` on one simulated run, timed alone.

The run is case ``--case`` of ``benchmarks/laws.py`` (the independent solve_ivp
simulator of ``benchmarks/_laws_sim.py``, run ``--index``), prepared as
``bayestribo.fit`` prepares it. Each law of :data:`bayestribo.inference.comparison.
auto_laws()` is optimised as the comparison does it, smallest first
(:func:`bayestribo.inference.pipeline.find_optimum`, started also at the optimum of the
largest nested law optimised before, :func:`bayestribo.inference.reduction.
nested_start`); unlike the comparison, a nested law's optimum is the optimiser's, not
its sampler's best draw, and nothing is sampled. Each law's CPU time
(``time.process_time``: the load of other processes hardly changes it) and wall time,
its optimum, Laplace covariance and log density are written, so that two trees can be
compared to the bit.

Run (by hand)::

    PYTHONPATH=. timeout 1800 nice python benchmarks/auto_optimum.py --case coulomb

Writes ``benchmarks/results/auto_optimum.json`` (``--output NAME``: ``NAME.json``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import provenance, write_results  # noqa: E402
from _tree import require_this_tree  # noqa: E402
from laws import CASES, _entropy, case_record  # noqa: E402


def optima(case: str, noise: float, index: int, seed: int) -> list[dict[str, Any]]:
    """Each auto law's optimum on run ``index`` of ``case``, timed."""
    from bayestribo.inference import comparison
    from bayestribo.inference.choice import complexity
    from bayestribo.inference.pipeline import find_optimum, prepare
    from bayestribo.inference.reduction import nested_start

    run, _facts = case_record(case, noise, _entropy(case, noise, index, seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(run)
        found: dict[str, dict[str, float]] = {}
        out = []
        for law in sorted(comparison.auto_laws(), key=complexity):
            posterior = comparison._posterior(law, prepared.data, "exact", False)
            nested = nested_start(law, prepared, found)
            wall, cpu = time.perf_counter(), time.process_time()
            theta, cov, ratio_range = find_optimum(posterior, prepared.decay, also_start_at=nested)
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
            found[law] = dict(zip(posterior.names, theta.tolist(), strict=True))
            lp = float(posterior(theta[None])[0])
            out.append(
                {
                    "law": law,
                    "cpu_seconds": cpu,
                    "seconds": wall,
                    "names": list(posterior.names),
                    "theta": theta.tolist(),
                    "cov": np.asarray(cov).tolist(),
                    "log_density": lp,
                    "ratio_range": None if ratio_range is None else list(map(float, ratio_range)),
                }
            )
            print(f"  {law:<28} CPU {cpu:8.2f} s wall {wall:8.2f} s log density {lp!r}", flush=True)
    return out


def main(argv: list[str] | None = None) -> None:
    """Command line: time each auto law's optimiser on one simulated run."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="coulomb", choices=list(CASES))
    parser.add_argument("--noise", type=float, default=10.0)
    parser.add_argument("--index", type=int, default=0)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--output", default="auto_optimum")
    args = parser.parse_args(argv)
    module = require_this_tree()
    load_start = os.getloadavg()
    laws = optima(args.case, args.noise, args.index, args.seed)
    path = write_results(
        args.output,
        {
            **provenance(module, vars(args), load_start),
            "cpu_seconds": sum(f["cpu_seconds"] for f in laws),
            "laws": laws,
        },
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
