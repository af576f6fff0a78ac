"""Forced inlining in the law template: a law's first compilation and its warm calls,
for several trees of the package side by side, and every compiled entry point's
values compared bit for bit.

For each law of ``--laws`` and each tree of ``--tree NAME=PATH`` (the trees differing
in which functions of :mod:`bayestribo.model.laws._core` carry ``inline="always"``),
``--repeats`` rounds, the laws in turn and the trees alternating for each law (their
order rotated from law to law and round to round): a fresh process with an empty
``$BAYESTRIBO_CACHE_DIR`` imports the package and calls
``Law.pi_grid(..., tau_end=80, method="integrate")`` on fixed inputs (32 parameter
sets, numpy seed 20261130, 256 times): its process CPU time (``time.process_time``)
is the first call, which generates the law's module and compiles ``grid`` and what
it calls; each ``numba:compile`` event is timed, exclusive of the compilations nested
in it. In the first round only, every entry point the template exports is then called
on the same parameter grid and its values hashed (SHA-256 of the bytes): ``grid`` to
the end of the record, to the end of motion, with 64 fixed steps and with -32 (the
coarse model), ``turns`` (four trajectories), ``swing_drops`` (32 rows × 5 swings)
and ``averaged_tail`` (four starts, the ladder's half cycles and 8 fixed steps, called
directly with ``fixed`` given). The results are written after every law.
Then, warm, the Π grid to the end of the record and to the end of motion, timed
call by call (as many calls as fill about ``--warm-seconds`` of CPU, at least 20),
their medians.

Run: ``python benchmarks/law_inline.py --tree main=<worktree of main> --tree
selective=. --repeats 3 --output law_inline``; writes
``benchmarks/results/<output>.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

#: The laws ``law="auto"`` compares (the default law among them).
LAWS = (
    "viscous",
    "coulomb",
    "quadratic",
    "power",
    "hysteretic",
    "viscous+coulomb",
    "viscous+quadratic",
    "coulomb+quadratic",
    "coulomb+power",
    "coulomb+hysteretic",
    "quadratic+hysteretic",
    "viscous+coulomb+quadratic",
)

WORKER = r"""
import hashlib, json, math, statistics, sys, time
c_start = time.process_time()
import numpy as np
from numba.core import event
import bayestribo
from bayestribo.model.laws import get_law
from bayestribo.model.laws.integrator import compiled_law
c_import = time.process_time()

class CpuListener(event.Listener):
    def __init__(self):
        self.stack, self.out = [], []
    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"].py_func.__name__, time.process_time(), 0.0])
    def on_end(self, ev):
        name, t0, child = self.stack.pop()
        dur = time.process_time() - t0
        if self.stack:
            self.stack[-1][2] += dur
        self.out.append({"function": name, "depth": len(self.stack), "inclusive_cpu_s": dur,
                         "exclusive_cpu_s": dur - child})

name, hashes, warm_seconds = sys.argv[1], sys.argv[2] == "1", float(sys.argv[3])
law = get_law(name)
rng = np.random.default_rng(20261130)
size = 32
values = {n: rng.uniform(0.005, 0.05, size) for n in law.parameter_names}
if "mu_s_ratio" in values:
    values["mu_s_ratio"] = rng.uniform(1.0, 1.5, size)
if "alpha" in values:
    values["alpha"] = rng.uniform(0.8, 2.5, size)
tau = np.linspace(0.0, 80.0, 256)
y0 = rng.uniform(0.8, 1.2, size)

def call(end, steps=0):
    return law.pi_grid(tau, values, y0, tau_end=end, method="integrate", steps=steps)

listener = CpuListener()
with event.install_listener("numba:compile", listener):
    c0 = time.process_time()
    first = call(80.0)
    c1 = time.process_time()
digests = {}
if hashes:
    def sha(*arrays):
        data = b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)
        return hashlib.sha256(data).hexdigest()
    digests["grid_record"] = sha(first)
    digests["grid_motion"] = sha(call(None))
    digests["grid_fixed64"] = sha(call(80.0, 64))
    digests["grid_coarse-32"] = sha(call(None, -32))
    turns = []
    for p in range(4):
        row = {k: float(v[p]) for k, v in values.items()}
        turns += list(law.turning_points(row, float(y0[p]), tau_max=400.0, max_count=5000))
    digests["turns"] = sha(*turns)
    coef = law.coefficients(values, 1.0)
    module = compiled_law(*law._layout[0])
    digests["swing_drops"] = sha(module.swing_drops(coef, np.linspace(0.2, 1.0, 5)))
    m = module.LADDER[-1] + 1
    work = np.empty(m), np.empty(m), np.empty((2, m))
    fixed = module.nodes(0.0, 8), np.zeros(1, np.int64)
    tails = []
    for p in range(4):
        c = np.ascontiguousarray(coef[p])
        amp = float(y0[p])
        small = 1e-12 * amp**2
        ladder = module._TABLES, module._OFFSETS
        tails.append(module.averaged_tail(amp, c, 1.0, 20000, small, *ladder, *work, 0))
        tails.append(module.averaged_tail(amp, c, 1.0, 20000, small, *fixed, *work, 8))
    digests["averaged_tail"] = sha(np.array(tails))
    digests["averaged_tail_finite"] = int(np.isfinite(tails).sum())
def timed(end):
    t0 = time.process_time(); call(end); return time.process_time() - t0
probe = statistics.median(timed(80.0) + timed(None) for _ in range(3))
n = int(min(max(warm_seconds / max(probe, 1e-6), 20), 2000))
warm, warm_motion = [], []
for _ in range(n):
    warm.append(timed(80.0)); warm_motion.append(timed(None))
print(json.dumps({
    "import_cpu_s": c_import - c_start, "first_call_cpu_s": c1 - c0, "events": listener.out,
    "warm_calls": n, "warm_cpu_s": statistics.median(warm),
    "warm_motion_cpu_s": statistics.median(warm_motion), "digests": digests,
    "finite_rows": int(np.isfinite(first).all(axis=1).sum()), "module": bayestribo.__file__,
}))
"""


def measure(
    tree: Path, law: str, hashes: bool, warm_seconds: float, cache: Path | None = None
) -> dict:
    """One fresh process of ``tree`` with an empty law cache: the law's first call, its
    entry points' digests (``hashes``) and its warm calls.

    Parameters
    ----------
    tree : Path
        The package's tree (set as ``PYTHONPATH``).
    law : str
        A registered law.
    hashes : bool
        Whether to call and hash every entry point.
    warm_seconds : float
        About how much CPU [s] the warm calls take.
    cache : Path, optional
        A law cache kept from process to process (warm calls only: the first call then
        loads the law); default an empty one.

    Returns
    -------
    dict
        The worker's record: CPU times [s], compilation events, digests.
    """
    with tempfile.TemporaryDirectory(prefix="law-inline-") as tmp:
        folder = cache if cache is not None else Path(tmp) / "l"
        env = {**os.environ, "PYTHONPATH": str(tree), "BAYESTRIBO_CACHE_DIR": str(folder)}
        proc = subprocess.run(
            [
                sys.executable,
                "-W",
                "ignore",
                "-c",
                WORKER,
                law,
                str(int(hashes)),
                str(warm_seconds),
            ],
            env=env,
            capture_output=True,
            text=True,
            cwd=tmp,
        )
    if proc.returncode != 0:
        raise RuntimeError(f"{tree} {law}: {proc.stderr[-2000:]}")
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(result["module"]).resolve().is_relative_to(tree.resolve()):
        raise RuntimeError(f"the worker imported {result['module']}")
    result["load_average"] = list(os.getloadavg())
    return result


def exclusive(result: dict) -> dict[str, float]:
    """Exclusive compile CPU [s] by function name, summed over its signatures."""
    per: dict[str, float] = defaultdict(float)
    for e in result["events"]:
        per[e["function"]] += e["exclusive_cpu_s"]
    return dict(sorted(per.items(), key=lambda kv: -kv[1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tree", action="append", required=True, help="NAME=PATH")
    parser.add_argument("--laws", nargs="+", default=list(LAWS))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--warm-seconds", type=float, default=0.6)
    parser.add_argument("--output", default="law_inline")
    parser.add_argument(
        "--cache-dir",
        type=Path,
        help="keep each tree's law cache in DIR/NAME (warm calls only; default empty caches)",
    )
    parser.add_argument(
        "--skip-warmup", action="store_true", help="the trees' own numba caches are warm"
    )
    args = parser.parse_args()
    trees = {k: Path(v).resolve() for k, v in (t.split("=", 1) for t in args.tree)}
    names = list(trees)
    for tree in () if args.skip_warmup else trees.values():  # the package's own kernels
        measure(tree, "viscous", False, 0.0)
    load_start = list(os.getloadavg())
    runs: dict[str, dict[str, list[dict]]] = {law: {k: [] for k in trees} for law in args.laws}
    for r in range(args.repeats):
        for i, law in enumerate(args.laws):
            shift = (r + i) % len(names)
            for kind in names[shift:] + names[:shift]:
                cache = None if args.cache_dir is None else args.cache_dir.resolve() / kind
                res = measure(trees[kind], law, r == 0, args.warm_seconds, cache)
                res["exclusive_cpu_s"] = exclusive(res)
                del res["events"]
                runs[law][kind].append(res)
                print(
                    f"round {r} {kind:10s} {law:26s} first {res['first_call_cpu_s']:6.2f} s "
                    f"warm {res['warm_cpu_s'] * 1e3:8.3f} ms",
                    flush=True,
                )
            write(args, trees, runs, load_start)


def summarise(runs: dict, names: list[str]) -> dict:
    """Per law and tree: first-call CPU [s] per round and its ratio to the first tree's,
    the ratio of the warm calls' medians, and whether every entry point's digest is the
    first tree's."""
    summary = {}
    for law, kinds in runs.items():
        base = kinds[names[0]]
        s = {}
        for kind, rows in kinds.items():
            if not rows or len(rows) != len(base):
                continue
            warm = statistics.median(x["warm_cpu_s"] for x in rows)
            motion = statistics.median(x["warm_motion_cpu_s"] for x in rows)
            first = statistics.median(x["first_call_cpu_s"] for x in rows)
            s[kind] = {
                "first_call_cpu_s": [x["first_call_cpu_s"] for x in rows],
                "first_call_median_s": first,
                "first_call_ratio": first / statistics.median(b["first_call_cpu_s"] for b in base),
                "first_call_ratio_per_round": [
                    x["first_call_cpu_s"] / b["first_call_cpu_s"]
                    for x, b in zip(rows, base, strict=True)
                ],
                "warm_cpu_s": [x["warm_cpu_s"] for x in rows],
                "warm_motion_cpu_s": [x["warm_motion_cpu_s"] for x in rows],
                "warm_ratio": warm / statistics.median(b["warm_cpu_s"] for b in base),
                "warm_motion_ratio": motion
                / statistics.median(b["warm_motion_cpu_s"] for b in base),
                "digests_identical": rows[0]["digests"] == base[0]["digests"],
            }
        summary[law] = s
    return summary


def write(args: argparse.Namespace, trees: dict, runs: dict, load_start: list) -> None:
    """Write the rounds so far and their summary."""
    summary = summarise(runs, list(trees))
    for law, s in summary.items():
        keys = ("first_call_ratio", "warm_ratio", "warm_motion_ratio", "digests_identical")
        print(law, json.dumps({k: {kk: v[kk] for kk in keys} for k, v in s.items()}), flush=True)
    write_results(
        args.output,
        {
            "benchmark": "law_inline",
            "description": __doc__,
            "trees": {k: str(v) for k, v in trees.items()},
            "settings": {k: str(v) for k, v in vars(args).items() if k != "tree"},
            "load_average_start": load_start,
            "load_average_end": list(os.getloadavg()),
            "runs": runs,
            "summary": summary,
        },
    )


if __name__ == "__main__":
    main()
