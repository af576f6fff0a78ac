"""A fitting process for side-by-side timings of two versions of bayestribo.

Run with ``PYTHONPATH`` pointing at the tree to time; it imports nothing else from
``benchmarks/``, so the same file drives the current tree and an old commit's
worktree. It reads one JSON request per line on stdin, ``{"path": ..., "seed": ...}``,
fits the recording with the defaults of that tree's ``fit`` (``bayestribo.inference.fit``,
or ``bayestribo.fit.fit`` in older trees) and writes one JSON line per request: wall
and process CPU time of the call, convergence, the sampler's diagnostics, posterior means and
standard deviations, and the load average before and after.
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings

import numpy as np

PARAMS = ("zeta", "mu_k", "mu_s_ratio", "y0")


def _fit_function():
    try:
        from bayestribo.inference import fit
    except ImportError:  # trees before the inference/ layout
        from bayestribo.fit import fit
    return fit


def main() -> int:
    import bayestribo

    fit = _fit_function()
    print(json.dumps({"ready": True, "module": bayestribo.__file__}), flush=True)
    for line in sys.stdin:
        request = json.loads(line)
        load_before = os.getloadavg()
        start, cpu_start = time.perf_counter(), time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit(request["path"], seed=int(request["seed"]))
        seconds = time.perf_counter() - start
        cpu_seconds = time.process_time() - cpu_start
        d = result.diagnostics
        out = {
            "seed": request["seed"],
            "seconds": seconds,
            "cpu_seconds": cpu_seconds,
            "converged": bool(result.converged),
            "ess_min": float(d["ess_min"]),
            "ess_per_second": float(d["ess_min"]) / seconds,
            "n_steps": int(d["n_steps"]),
            "n_walkers": int(d.get("n_walkers", 0)),
            "autocorr_time_max": float(d["autocorr_time_max"]),
            "acceptance_fraction": float(d["acceptance_fraction"]),
            "mean": {p: float(np.mean(result.samples(p))) for p in PARAMS},
            "sd": {p: float(np.std(result.samples(p), ddof=1)) for p in PARAMS},
            "load_before": list(load_before),
            "load_after": list(os.getloadavg()),
        }
        print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
