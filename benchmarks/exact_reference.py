"""Posterior means of a few laws sampled on the exact posterior, no surrogate.

The reference against which a change to the surrogate, the optimiser or the dissipation
band is judged: each (recording, law) given is fitted with seed 1 as ``fit`` does, but
its sampler runs on the exact posterior (``sample_from(surrogate=False)``), and each
parameter's posterior mean and sd are recorded, with the CPU time. Compare with an
``every_law.py`` result (its ``posterior``) by :func:`shifts`::

    python benchmarks/exact_reference.py --cases HarmOsc1:viscous+coulomb+quadratic \\
        --output exact_reference_NAME

Run it for each tree (``PYTHONPATH`` at the tree): the exact posterior itself follows the
optimum its second pass is weighted at.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import commit, write_results

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"


def _exact_fit(run: Any, law: str, seed: int) -> dict[str, Any]:
    from bayestribo import fit
    from bayestribo.inference import chains, law_frame

    sample_from = law_frame.sample_from
    law_frame.sample_from = partial(chains.sample_from, surrogate=False)
    try:
        cpu = sum(os.times()[:2])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(run, law=law, seed=seed)
        cpu = sum(os.times()[:2]) - cpu
    finally:
        law_frame.sample_from = sample_from
    return {
        "cpu_s": cpu,
        "converged": bool(result.converged),
        "ess_min": float(result.diagnostics.get("ess_min", float("nan"))),
        "posterior": {
            n: [float(np.mean(result.samples(n))), float(np.std(result.samples(n)))]
            for n in result.parameter_names
        },
    }


def shifts(reference: dict[str, Any], other: dict[str, Any]) -> dict[str, float]:
    """|Δ mean| / reference sd of each parameter of ``other`` (an every_law row)."""
    out = {}
    for name, (mean, sd) in reference["posterior"].items():
        if name in other.get("posterior", {}) and sd > 0:
            out[name] = abs(other["posterior"][name][0] - mean) / sd
    return out


def main() -> None:
    import real

    import bayestribo
    from bayestribo import read_run

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", required=True, help="RECORDING:LAW ...")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--output", required=True, help="results/NAME.json")
    args = parser.parse_args()
    tree = Path(bayestribo.__file__).resolve().parents[1]
    results: dict[str, Any] = {
        "package_tree": str(tree),
        "package_commit": commit(tree),
        "seed": args.seed,
        "recordings": {},
    }
    for case in args.cases:
        name, law = case.split(":", 1)
        if name == "bundled":
            run = read_run(BUNDLED)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                run = real.load(name)[0]
        row = _exact_fit(run, law, args.seed)
        results["recordings"].setdefault(name, {})[law] = row
        print(name, law, row, flush=True)
        write_results(args.output, {"load_average": os.getloadavg(), **results})


if __name__ == "__main__":
    main()
