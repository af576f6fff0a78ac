"""One law on one recording fitted with a high step ceiling: a long reference chain.

A posterior whose default run stops unconverged on a ridge (HarmOsc3 under
``coulomb+power``: the ridge rule stops it at ~10 000-17 000 steps) is sampled with
the ceiling raised (``--max-steps``) so that the sampler's rule can be met in the
law's own coordinates; its posterior means and sd are the reference a faster run
(another tree, other coordinates) is held to. The package fitted is the one Python
imports (``PYTHONPATH`` at a tree)::

    PYTHONPATH=../main-tree python benchmarks/long_chain.py --law coulomb+power \\
        --recording HarmOsc3 --seed 2 --max-steps 120000 --output NAME

``--compare NAME OTHER...`` prints each quantity's |Δ mean| over the reference's sd
for ``every_law.py`` results (results/OTHER.json, their entry of that recording and law).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import RESULTS, commit, write_results


def _cpu() -> float:
    t = os.times()
    return t.user + t.system


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--law", default="coulomb+power")
    parser.add_argument("--recording", default="HarmOsc3", help="a name of benchmarks/real.py")
    parser.add_argument("--seed", type=int, default=2)
    parser.add_argument("--max-steps", type=int, default=120_000)
    parser.add_argument("--output", default="long_chain")
    parser.add_argument("--compare", nargs="+", metavar="NAME", help="reference, then others")
    args = parser.parse_args()
    if args.compare:
        ref = json.loads((RESULTS / f"{args.compare[0]}.json").read_text())
        for name in args.compare[1:]:
            other = json.loads((RESULTS / f"{name}.json").read_text())
            row = other["recordings"][ref["recording"]][ref["law"]]
            shifts = {
                q: abs(row["posterior"][q][0] - m) / s
                for q, (m, s) in ref["posterior"].items()
                if q in row["posterior"] and s > 0
            }
            print(name, {q: round(v, 2) for q, v in shifts.items()})
        return

    import real

    import bayestribo
    from bayestribo import fit

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = real.load(args.recording)[0]
    cpu, wall = _cpu(), time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, law=args.law, seed=args.seed, max_steps=args.max_steps)
    cpu, wall = _cpu() - cpu, time.perf_counter() - wall
    tree = Path(bayestribo.__file__).resolve().parents[1]
    diag = result.diagnostics
    write_results(
        args.output,
        {
            "law": args.law,
            "recording": args.recording,
            "seed": args.seed,
            "max_steps": args.max_steps,
            "package_tree": str(tree),
            "package_commit": commit(tree),
            "cpu_s": cpu,
            "wall_s": wall,
            "load_average": os.getloadavg(),
            "converged": bool(result.converged),
            "n_steps": int(diag.get("n_steps", 0)),
            "ess_min": float(diag.get("ess_min", float("nan"))),
            "autocorr_time": diag.get("autocorr_time"),
            "warnings": sorted({w.category.__name__ for w in caught}),
            "posterior": {
                name: [float(np.mean(result.samples(name))), float(np.std(result.samples(name)))]
                for name in result.parameter_names
            },
        },
    )


if __name__ == "__main__":
    main()
