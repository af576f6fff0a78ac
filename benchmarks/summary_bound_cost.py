"""What a fit's summary costs with the bounds' test, here and in another checkout.

``FitResult.summary()`` now tests each quantity's posterior against its prior
(``inference/flatness.bound_interval``) so that a quantity the data do not constrain is
summarised as a bound in every output. Per round and checkout, in a subprocess whose
PYTHONPATH is the checkout, alternating: the bundled run ``glycerol-N0.31-r1`` fitted
(seed 1), ``summary()`` timed over 50 calls, and two fits with their ``to_dict()``
(seeds 2, 3), in process CPU time; and, here only, the bounds' test alone over the
quantities of the summary.

Run::

    python benchmarks/summary_bound_cost.py --base /path/to/main-worktree --rounds 5

Results: ``benchmarks/results/summary_bound_cost.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

PROBE = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
import bayestribo
run = sys.argv[1] + "/data/runs/glycerol-N0.31-r1.csv"
r = bayestribo.fit(run, seed=1)
r.summary()
t = time.process_time()
for _ in range(50):
    r.summary()
out = {"summary_s": (time.process_time() - t) / 50}
t = time.process_time()
for seed in (2, 3):
    bayestribo.fit(run, seed=seed).to_dict()
out["fit_and_dict_s"] = (time.process_time() - t) / 2
try:
    from types import SimpleNamespace
    from bayestribo.inference.flatness import bound_interval
except ImportError:
    pass
else:
    fit = SimpleNamespace(priors=r.priors, samples=r.samples)
    names = list(r.quantity_info())
    t = time.process_time()
    for _ in range(50):
        for n in names:
            bound_interval(fit, n, r.samples(n), 0.95)
    out["bounds_test_s"] = (time.process_time() - t) / 50
print(json.dumps(out))
"""


def probe(tree: Path) -> dict[str, float]:
    """One round's figures with the package of ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(ROOT)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tempfile.gettempdir(),
        check=True,
        timeout=900,
    )
    return json.loads(done.stdout.splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=True)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--name", default="summary_bound_cost")
    args = ap.parse_args()
    load = [os.getloadavg()[0]]
    for tree in (args.base, ROOT):  # numba's caches warmed, not timed
        probe(tree)
    rounds = []
    for _ in range(args.rounds):
        rounds.append({"base": probe(args.base), "here": probe(ROOT)})
        print(json.dumps(rounds[-1]), flush=True)
    load.append(os.getloadavg()[0])

    def ratio(key: str) -> float:
        return statistics.median(r["here"][key] / r["base"][key] for r in rounds)

    summary = {
        "summary_ratio_median": ratio("summary_s"),
        "fit_and_dict_ratio_median": ratio("fit_and_dict_s"),
        "bounds_test_s_median": statistics.median(r["here"]["bounds_test_s"] for r in rounds),
        "bounds_test_share_of_fit": statistics.median(
            r["here"]["bounds_test_s"] / r["here"]["fit_and_dict_s"] for r in rounds
        ),
        "load_1min": load,
    }
    print(json.dumps(summary, indent=1))
    result = {"commit": commit(), "base_commit": commit(args.base, short=True)}
    print(write_results(args.name, {**result, "summary": summary, "rounds": rounds}))


if __name__ == "__main__":
    main()
