"""What the boundary average adds where nothing is mixed in: the CPU time of
:func:`bayestribo.inference.boundary.boundary_mixture` on a checked sample whose nested
laws are improbable (its mean over 200 calls, the nested fits refused), beside the
sample-and-check CPU time of the same law, on the bundled ``glycerol-N0.31-r1``, seed 1,
for ``coulomb+hysteretic`` (averaged on this branch, not on main) and the default law.

Run once per tree, alternating (``PYTHONPATH`` chooses the package):
``python benchmarks/boundary_laws_cost.py OUT.json``; the rounds are gathered in
``results/boundary_laws_added_cost.json``.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LAWS = ("coulomb+hysteretic", "viscous+coulomb")


def _refused(name: str) -> None:
    raise AssertionError(f"{name}: nothing is to be mixed in here")


def main() -> None:
    import bayestribo as bt
    from bayestribo.inference.boundary import boundary_mixture
    from bayestribo.inference.checks import check
    from bayestribo.inference.law_frame import sample_law
    from bayestribo.inference.preparation import prepare
    from bayestribo.model.laws import get_law

    warnings.simplefilter("ignore")
    out = {}
    for law in LAWS:
        prepared = prepare(bt.read_run(ROOT / "data/runs/glycerol-N0.31-r1.csv"))
        cpu = time.process_time()
        framed, sampled = sample_law(prepared, get_law(law), seed=np.random.default_rng(1))
        checked = check(framed, sampled)
        fit_cpu = time.process_time() - cpu
        cpu = time.process_time()
        for _ in range(200):
            _, record = boundary_mixture(checked.sampled, _refused, _refused)
        out[law] = {
            "sample_and_check_cpu_s": fit_cpu,
            "boundary_mixture_cpu_s": (time.process_time() - cpu) / 200,
            "mixed": record and record["mixed"],
            "probabilities": record
            and {k: v["probability"] for k, v in record["parameters"].items()},
        }
        print(law, out[law], flush=True)
    Path(sys.argv[1]).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
