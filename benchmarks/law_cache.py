"""The first fit of a law without a closed form: its integrator compiled, or loaded.

Each law's integrator is compiled by numba on its first use and cached in
``$BAYESTRIBO_CACHE_DIR`` (``bayestribo/model/laws/cache.py``). For each law of
``--laws``, ``--repeats`` rounds, in fresh processes on the bundled run
``data/runs/glycerol-N0.31-r1.csv``:

* ``cold``: an empty law cache (a new private folder): ``fit(run, law=LAW)`` twice;
  the first compiles the law's integrator and writes it to the cache;
* ``cached``: a new process on the folder the cold one filled: ``fit`` twice; the first
  loads the compiled code.

Reported per law: the process CPU time (``time.process_time``) of the first fit and of
the second (the warm fit), medians over the rounds; the first fit's extra cost over
the warm one is what compiling (``cold``) or loading (``cached``) the law costs. The
package's own compiled functions are cached beside its modules and are warm in both
(run the benchmark once before timing a fresh checkout). The laws alternate within a
round so that the load of a shared machine falls on all alike.

Run: ``python benchmarks/law_cache.py --repeats 3``; writes
``benchmarks/results/law_cache.json``.
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
from _machine import commit, write_results

TREE = Path(__file__).resolve().parent.parent
RUN = TREE / "data" / "runs" / "glycerol-N0.31-r1.csv"

WORKER = """
import json, sys, time
import bayestribo
run = bayestribo.read_run(sys.argv[1])
law = sys.argv[2]
times = []
for seed in (1, 2):
    c0 = time.process_time()
    result = bayestribo.fit(run, seed=seed, law=law)
    times.append(time.process_time() - c0)
print(json.dumps({"first_cpu_s": times[0], "second_cpu_s": times[1],
                  "converged": bool(result.converged), "module": bayestribo.__file__}))
"""


def measure(law: str, cache: Path) -> dict:
    """Fit ``law`` twice in a fresh process whose law cache is ``cache``.

    Parameters
    ----------
    law : str
        A registered law (``"quadratic"``, ``"viscous+quadratic"``, ...).
    cache : Path
        The folder given as ``BAYESTRIBO_CACHE_DIR``.

    Returns
    -------
    dict
        ``first_cpu_s`` and ``second_cpu_s`` [s] of process CPU time, ``converged``.
    """
    env = {**os.environ, "PYTHONPATH": str(TREE), "BAYESTRIBO_CACHE_DIR": str(cache)}
    proc = subprocess.run(
        [sys.executable, "-W", "ignore", "-c", WORKER, str(RUN), law],
        env=env,
        capture_output=True,
        text=True,
        cwd=cache.parent,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{law}: {proc.stderr[-2000:]}")
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(result["module"]).resolve().is_relative_to(TREE.resolve()):
        raise RuntimeError(f"the worker imported {result['module']}")
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--laws", nargs="+", default=["quadratic", "power", "viscous+quadratic"], help="laws"
    )
    parser.add_argument("--repeats", type=int, default=3, help="rounds of every law")
    parser.add_argument("--output", default="law_cache")
    args = parser.parse_args()
    load_start = list(os.getloadavg())
    rows: dict[str, dict[str, list[dict]]] = {law: {"cold": [], "cached": []} for law in args.laws}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats):
            for law in args.laws:
                cache = Path(tmp) / f"cache-{r}-{law.replace('+', '_')}"
                for kind in ("cold", "cached"):
                    result = measure(law, cache)
                    result["load_average"] = list(os.getloadavg())
                    rows[law][kind].append(result)
    summary = {}
    for law, kinds in rows.items():
        s = {}
        for kind, results in kinds.items():
            first = statistics.median(x["first_cpu_s"] for x in results)
            second = statistics.median(x["second_cpu_s"] for x in results)
            extra = statistics.median(x["first_cpu_s"] - x["second_cpu_s"] for x in results)
            s[kind] = {"first_cpu_s": first, "warm_cpu_s": second, "extra_cpu_s": extra}
        summary[law] = s
    print(f"{'law':20s} {'compile [s]':>12s} {'load [s]':>9s} {'warm fit [s]':>13s}")
    for law, s in summary.items():
        print(
            f"{law:20s} {s['cold']['extra_cpu_s']:12.2f} {s['cached']['extra_cpu_s']:9.2f} "
            f"{s['cached']['warm_cpu_s']:13.2f}"
        )
    write_results(
        args.output,
        {
            "benchmark": "law_cache",
            "description": __doc__,
            "commit": commit(short=True),
            "settings": vars(args),
            "load_average_start": load_start,
            "load_average_end": list(os.getloadavg()),
            "runs": rows,
            "summary": summary,
        },
    )


if __name__ == "__main__":
    main()
