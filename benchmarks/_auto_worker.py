"""A process that fits recordings with ``law="auto"``, for side-by-side timings of two trees.

Run with ``PYTHONPATH`` pointing at the tree to time; it imports nothing from
``benchmarks/``, so the same file drives the current tree and an old commit's worktree.
It reads one JSON request per line on stdin, ``{"path": ..., "seed": ..., "read": ...}``
(``read``: the keywords of :func:`bayestribo.read_run`, or null for a bundled run
read by ``fit``; ``default``: also time the default fit of the recording), fits the
recording with ``fit(..., law="auto")`` and writes one JSON line per request: the CPU
time of the process (``time.process_time``) and the wall time of the call (and of the
default fit's), the law chosen and the comparison (verdict, adequacy, the laws as good as
it, each law's row), and the posterior mean and sd of every quantity the result
summarises.
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

#: Keys of a comparison's table row worth keeping.
ROW_KEYS = (
    "elpd_diff",
    "dse",
    "adequate",
    "converged",
    "sampled",
    "reduces_to",
    "screened",
    "screen",
    "settled",
    "settle",
    "seconds",
    "cpu_seconds",
)


def _row(row: dict[str, Any]) -> dict[str, Any]:
    return {k: row[k] for k in ROW_KEYS if k in row}


def fit_auto(request: dict[str, Any]) -> dict[str, Any]:
    """One ``law="auto"`` fit of the request's recording, timed."""
    import numpy as np

    from bayestribo import fit, read_run

    source: Any = request["path"]
    if request.get("read"):
        source = read_run(source, **request["read"])
    load_before = os.getloadavg()
    start, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(source, law="auto", seed=int(request["seed"]))
    cpu_seconds, seconds = time.process_time() - cpu, time.perf_counter() - start
    default_cpu = None
    if request.get("default"):
        # the default fit of the same recording in the same (warm) process, the unit
        # of the goal for law="auto"
        cpu = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit(source, seed=int(request["seed"]))
        default_cpu = time.process_time() - cpu
    comparison = result.law_comparison or {}
    summary = result.summary()
    return {
        "name": request.get("name"),
        "seed": request["seed"],
        "cpu_seconds": cpu_seconds,
        "seconds": seconds,
        "default_cpu_seconds": default_cpu,
        "law": result.law,
        "converged": bool(result.converged),
        "verdict": comparison.get("verdict"),
        "adequate": comparison.get("adequate"),
        "best": comparison.get("best"),
        "as_good": comparison.get("as_good"),
        "equivalent": comparison.get("equivalent"),
        "rivals": (comparison.get("rivals") or {}).get("laws"),
        "table": {law: _row(row) for law, row in (comparison.get("table") or {}).items()},
        "mean": {k: float(np.mean(s.mean)) for k, s in summary.items()},
        "sd": {k: float(np.mean(s.sd)) for k, s in summary.items()},
        "load_before": list(load_before),
        "load_after": list(os.getloadavg()),
    }


def main() -> int:
    """Serve requests from stdin, one JSON line each way."""
    import bayestribo

    print(json.dumps({"ready": True, "module": bayestribo.__file__}), flush=True)
    for line in sys.stdin:
        request = json.loads(line)
        if request.get("warm_up"):
            # the compiled kernels loaded once, before anything is timed
            from bayestribo import fit

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fit(request["path"], seed=1)
                if request.get("auto"):
                    # and every compiled law and surrogate kernel auto uses
                    fit(request["path"], seed=1, law="auto")
            print(json.dumps({"warm": True}), flush=True)
            continue
        print(json.dumps(fit_auto(request)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
