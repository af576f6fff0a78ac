"""Where a law's first use with an empty law cache spends its CPU: numba's compilation
of each generated function, side by side with another tree of the package.

For each law of ``--laws`` and each tree (this one and ``--baseline``), ``--repeats``
rounds, the trees alternating within a round and the laws within a tree: a fresh
process with an empty ``$BAYESTRIBO_CACHE_DIR`` (a new private folder) imports the
package, then calls ``Law.pi_grid(..., method="integrate")`` on fixed inputs, which
generates the law's module and compiles it. Each ``numba:compile`` event (one per
function and signature, nested where a function compiles its callees) is timed in
process CPU time (``time.process_time``), inclusive and exclusive of the compilations
nested in it. Then, warm, ``--calls`` calls of the same Π grid (32 parameter sets ×
256 times, to the end of the record and to the end of motion), their median CPU time.
The Π values of every call are hashed bit for bit, so that the trees' results can be
compared exactly. Before the rounds each tree runs once unmeasured, so that the
package's own compiled functions (cached beside its modules) are warm in both.

Run: ``python benchmarks/law_compile.py --baseline <worktree of main> --repeats 3``;
writes ``benchmarks/results/law_compile.json``.
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
from _machine import commit, write_results

TREE = Path(__file__).resolve().parent.parent

WORKER = r"""
import hashlib, json, sys, time
c_start = time.process_time()
import numpy as np
from numba.core import event
import bayestribo
from bayestribo.model.laws import get_law
c_import = time.process_time()

class CpuListener(event.Listener):
    def __init__(self):
        self.stack, self.out = [], []
    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"].py_func.__name__, time.process_time(), 0.0,
                           str(ev.data["args"])])
    def on_end(self, ev):
        name, t0, child, args = self.stack.pop()
        dur = time.process_time() - t0
        if self.stack:
            self.stack[-1][2] += dur
        self.out.append({"function": name, "depth": len(self.stack), "inclusive_cpu_s": dur,
                         "exclusive_cpu_s": dur - child, "signature": args})

law = get_law(sys.argv[1])
rng = np.random.default_rng(20261130)
size = 32
values = {name: rng.uniform(0.005, 0.05, size) for name in law.parameter_names}
if "mu_s_ratio" in values:
    values["mu_s_ratio"] = rng.uniform(1.0, 1.5, size)
if "alpha" in values:
    values["alpha"] = rng.uniform(0.8, 2.5, size)
tau = np.linspace(0.0, 80.0, 256)
y0 = rng.uniform(0.8, 1.2, size)

def call(end):
    return law.pi_grid(tau, values, y0, tau_end=end, method="integrate")

listener = CpuListener()
with event.install_listener("numba:compile", listener):
    c0 = time.process_time()
    first = call(80.0)
    c1 = time.process_time()
    first_motion = call(None)
    c2 = time.process_time()
warm, warm_motion, digests = [], [], set()
for _ in range(int(sys.argv[2])):
    t0 = time.process_time(); a = call(80.0); t1 = time.process_time()
    b = call(None); t2 = time.process_time()
    warm.append(t1 - t0); warm_motion.append(t2 - t1)
    digests.add(hashlib.sha256(a.tobytes() + b.tobytes()).hexdigest())
digest = hashlib.sha256(first.tobytes() + first_motion.tobytes()).hexdigest()
print(json.dumps({
    "import_cpu_s": c_import - c_start, "first_call_cpu_s": c1 - c0,
    "first_motion_call_cpu_s": c2 - c1, "events": listener.out,
    "warm_cpu_s": warm, "warm_motion_cpu_s": warm_motion,
    "pi_sha256": digest, "pi_sha256_stable": digests == {digest},
    "finite_rows": int(np.isfinite(first).all(axis=1).sum()),
    "module": bayestribo.__file__,
}))
"""


def measure(tree: Path, law: str, calls: int) -> dict:
    """Compile ``law`` in a fresh process of ``tree`` with an empty law cache.

    Parameters
    ----------
    tree : Path
        The package's tree (set as ``PYTHONPATH``).
    law : str
        A registered law without a closed form (``"quadratic"``, ...).
    calls : int
        Warm calls timed after the compilation.

    Returns
    -------
    dict
        The worker's record: CPU times [s] of the import, the first calls and the warm
        ones, each compilation event, the SHA-256 of the Π values.
    """
    with tempfile.TemporaryDirectory(prefix="law-compile-") as tmp:
        cache = Path(tmp) / "laws"
        env = {**os.environ, "PYTHONPATH": str(tree), "BAYESTRIBO_CACHE_DIR": str(cache)}
        proc = subprocess.run(
            [sys.executable, "-W", "ignore", "-c", WORKER, law, str(calls)],
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
    return result


def summarise(results: list[dict]) -> dict:
    """Medians over rounds: first-call CPU, compile CPU by function, warm CPU."""
    by_function: dict[str, list[float]] = defaultdict(list)
    signatures: dict[str, int] = {}
    for r in results:
        per: dict[str, float] = defaultdict(float)
        count: dict[str, int] = defaultdict(int)
        for e in r["events"]:
            per[e["function"]] += e["exclusive_cpu_s"]
            count[e["function"]] += 1
        for name, value in per.items():
            by_function[name].append(value)
        signatures = dict(count)
    outer = [sum(e["inclusive_cpu_s"] for e in r["events"] if e["depth"] == 0) for r in results]
    return {
        "first_call_cpu_s": statistics.median(r["first_call_cpu_s"] for r in results),
        "compile_cpu_s": statistics.median(outer),
        "import_cpu_s": statistics.median(r["import_cpu_s"] for r in results),
        "warm_cpu_s": statistics.median(statistics.median(r["warm_cpu_s"]) for r in results),
        "warm_motion_cpu_s": statistics.median(
            statistics.median(r["warm_motion_cpu_s"]) for r in results
        ),
        "exclusive_compile_cpu_s": {
            k: statistics.median(v)
            for k, v in sorted(by_function.items(), key=lambda kv: -sum(kv[1]))
        },
        "compilations": signatures,
        "pi_sha256": sorted({r["pi_sha256"] for r in results}),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--laws",
        nargs="+",
        default=["quadratic", "coulomb+power", "viscous+coulomb+quadratic"],
        help="laws without a closed form",
    )
    parser.add_argument("--baseline", type=Path, required=True, help="tree to compare with")
    parser.add_argument("--repeats", type=int, default=3, help="rounds of every law and tree")
    parser.add_argument("--calls", type=int, default=15, help="warm calls timed per process")
    parser.add_argument("--output", default="law_compile")
    args = parser.parse_args()
    trees = {"current": TREE, "baseline": args.baseline.resolve()}
    for tree in trees.values():  # the package's own compiled functions, warm in both
        measure(tree, args.laws[0], 1)
    load_start = list(os.getloadavg())
    rows: dict[str, dict[str, list[dict]]] = {law: {k: [] for k in trees} for law in args.laws}
    for r in range(args.repeats):
        order = list(trees) if r % 2 == 0 else list(trees)[::-1]
        for kind in order:
            for law in args.laws:
                result = measure(trees[kind], law, args.calls)
                result["load_average"] = list(os.getloadavg())
                rows[law][kind].append(result)
    summary = {law: {k: summarise(v) for k, v in kinds.items()} for law, kinds in rows.items()}
    for law, s in summary.items():
        cur, base = s["current"], s["baseline"]
        print(
            f"{law:28s} first call {cur['first_call_cpu_s']:6.2f} s against "
            f"{base['first_call_cpu_s']:6.2f} s; warm {cur['warm_cpu_s'] * 1e3:7.2f} ms against "
            f"{base['warm_cpu_s'] * 1e3:7.2f} ms; "
            f"Π identical: {cur['pi_sha256'] == base['pi_sha256']}"
        )
    write_results(
        args.output,
        {
            "benchmark": "law_compile",
            "description": __doc__,
            "commit": commit(short=True),
            "baseline_commit": commit(args.baseline, short=True),
            "settings": {**vars(args), "baseline": str(args.baseline)},
            "load_average_start": load_start,
            "load_average_end": list(os.getloadavg()),
            "runs": rows,
            "summary": summary,
        },
    )


if __name__ == "__main__":
    main()
