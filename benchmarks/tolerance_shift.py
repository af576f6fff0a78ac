"""What the integrator's tolerance from the noise changes: the optimum, and Π's cost.

A law without a closed form is integrated to the error its increments' noise allows
(:attr:`bayestribo.inference.likelihood.PiLikelihood.integrator_tolerance`, 1 % of the
smallest increment sd over √m). For each (recording, law) pair this script prepares
the recording as the command a user gives does (``benchmarks/auto_ratio.py``'s list; the
preparation of a default fit, captured), builds the law's posterior twice, with the
tolerance and with the integrator's usual steps (the share set to 1e-12, below the
usual error), and reports

* the maximum a posteriori of each, and how far apart, in Laplace sds of the usual one
  (deterministic: no sampler);
* the time of Π on at most 256 rows drawn from that Laplace approximation (those inside the priors'
  support), each way (process
  CPU time, best of 5), and the largest difference of the model's increments in units
  of their noise sd, over the rows and together (the norm over the increments: the
  most it can move the posterior, in its sds).

Run (by hand, a minute or two)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus PYTHONPATH=. python benchmarks/tolerance_shift.py

Writes ``benchmarks/results/tolerance_shift.json`` (``--output NAME``).
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
from auto_ratio import EXTERNAL, commands, run  # noqa: E402

PAIRS = [
    "seismometer-magnet-10:coulomb+power",
    "seismometer-magnet-5:power",
    "seismometer-no-magnet:coulomb+quadratic",
    "HarmOsc2:coulomb+power",
    "HarmOsc1:quadratic",
    "spring-disc-soft-capstone:power",
    "spring-disc-hard-capstone:viscous+coulomb+quadratic",
    "smorzamento-1:power",
    "bicycle-wheel-radial-gyro:viscous+coulomb+quadratic",
]


def _prepared(argv: list[str]) -> Any:
    """The preparation a default fit of this command makes."""
    import bayestribo.inference.fitting as fitting

    captured: list[Any] = []
    real = fitting.prepare

    def keep(*args: Any, **kwargs: Any) -> Any:
        out = real(*args, **kwargs)
        captured.append(out)
        return out

    fitting.prepare = keep  # the name the fit calls
    try:
        run([*argv, "--law", "viscous", "--seed", "1"])
    finally:
        fitting.prepare = real
    return captured[0]


def _best_time(call: Any, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        call()
        best = min(best, time.process_time() - start)
    return best


def measure(name: str, law: str, argv: list[str]) -> dict[str, Any]:
    import bayestribo.inference.likelihood as likelihood
    from bayestribo.inference import pipeline
    from bayestribo.inference.start import maximum_a_posteriori

    prepared = _prepared(argv)
    share = likelihood.INTEGRATOR_SHARE
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loose = pipeline.build_posterior(prepared.data, law=law)
        theta, _, _ = maximum_a_posteriori(loose, prepared.decay)
        likelihood.INTEGRATOR_SHARE = 1e-12
        try:
            usual = pipeline.build_posterior(prepared.data, law=law)
            theta0, cov0, _ = maximum_a_posteriori(usual, prepared.decay)
        finally:
            likelihood.INTEGRATOR_SHARE = share
    sd = np.sqrt(np.clip(np.diag(cov0), 1e-300, None))
    rows = np.random.default_rng(0).multivariate_normal(theta0, cov0, size=512)
    rows = rows[np.isfinite(usual(rows))][:256]  # inside the priors' support
    params = usual.physical(rows)["params"]
    inc_loose = loose.likelihood.model_increments(params)
    inc_usual = usual.likelihood.model_increments(params)
    noise = np.sqrt(usual.likelihood.data.variance)
    ok = np.all(np.isfinite(inc_loose), axis=1) & np.all(np.isfinite(inc_usual), axis=1)
    moved = (inc_loose[ok] - inc_usual[ok]) / noise
    t_loose = _best_time(lambda: loose.likelihood.model_increments(params))
    t_usual = _best_time(lambda: usual.likelihood.model_increments(params))
    out = {
        "recording": name,
        "law": law,
        "increments": int(noise.size),
        "tolerance": loose.likelihood.integrator_tolerance,
        "names": list(loose.names),
        "map_shift_laplace_sd": (np.abs(theta - theta0) / sd).tolist(),
        "rows": int(ok.sum()),
        "largest_increment_shift_sd": float(np.max(np.abs(moved))) if moved.size else None,
        "largest_shift_norm_sd": float(np.max(np.linalg.norm(moved, axis=1)))
        if moved.size
        else None,
        "pi_cpu_seconds_256_rows": {"tolerance": t_loose, "usual": t_usual},
        "speed_up": t_usual / t_loose,
    }
    print(
        f"{name:28s} {law:26s} m={out['increments']:4d} tol {out['tolerance'] or 0:.1e} "
        f"MAP shift ≤ {max(out['map_shift_laplace_sd']):.4f} sd, increments ≤ "
        f"{out['largest_shift_norm_sd'] or 0:.4f} sd together, Π {t_usual * 1e3:.1f} → "
        f"{t_loose * 1e3:.1f} ms ({out['speed_up']:.1f}×)",
        flush=True,
    )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", nargs="*", default=PAIRS, help="recording:law")
    parser.add_argument("--output", default="tolerance_shift")
    args = parser.parse_args()
    start = os.getloadavg()
    found, _ = commands(EXTERNAL)
    rows = []
    for pair in args.pairs:
        name, law = pair.split(":")
        if name not in found:
            print(f"{name}: absent", flush=True)
            continue
        rows.append(measure(name, law, found[name]))
    payload = {**provenance(__file__, {"pairs": args.pairs}, start), "pairs": rows}
    path = write_results(args.output, payload)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
