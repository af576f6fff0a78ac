"""ΔE(A)'s band of a law without a closed form, with and without the log-amount basis.

The summary's band interpolates ΔE at each swing over the posterior's draws
(``inference/dissipation.py`` ``_swing_dissipation``); where every interpolation misses
its check, each of the 1000 draws is integrated at that swing. This script captures the
draws of each band a fit computes (the command a user gives, ``benchmarks/auto_ratio.py``'s
list), and for each band of 1000 draws times the band's ΔE with the log-amount basis
(the package) and without it (``_log_amount_basis`` returning None: the package before),
process CPU time, best of 3, and compares both with every draw integrated: the largest
error over all draws, and the move of the 95 % interval's ends, in units of the band's
sd.

Run (by hand, a minute)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus PYTHONPATH=. python benchmarks/band_log_amount.py

Writes ``benchmarks/results/band_log_amount.json`` (``--output NAME``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import provenance, write_results  # noqa: E402
from auto_ratio import EXTERNAL, commands, run  # noqa: E402

CASES = ["seismometer-magnet-5:auto:1", "seismometer-magnet-5:power:1", "HarmOsc2:auto:1"]


def _bands(argv: list[str], law: str, seed: str) -> list[tuple[Any, ...]]:
    """The (law, swings, values, reference) of every band of 1000 draws the fit makes."""
    from bayestribo.inference import dissipation

    captured: list[tuple[Any, ...]] = []
    real = dissipation._swing_dissipation

    def keep(lw: Any, amps: Any, values: Any, ref: float) -> Any:
        n = max(np.size(v) for v in values.values())
        if n >= 1000 and not lw.closed_form:
            captured.append((lw, np.array(amps), {k: np.array(v) for k, v in values.items()}, ref))
        return real(lw, amps, values, ref)

    dissipation._swing_dissipation = keep
    try:
        run([*argv, "--law", law, "--seed", seed])
    finally:
        dissipation._swing_dissipation = real
    return captured


def _best(call: Any, repeats: int = 3) -> tuple[float, Any]:
    best, out = float("inf"), None
    for _ in range(repeats):
        start = time.process_time()
        out = call()
        best = min(best, time.process_time() - start)
    return best, out


def measure(name: str, band: tuple[Any, ...]) -> dict[str, Any]:
    from bayestribo.inference import dissipation

    law, amps, values, ref = band
    full = law.swing_dissipation(amps, values, ref)
    sd = full.std(axis=0)
    ends = np.percentile(full, [2.5, 97.5], axis=0)
    row: dict[str, Any] = {"recording": name, "law": law.name, "swings": int(amps.size)}
    real = dissipation._log_amount_basis
    for label, basis in (("log_amount", real), ("before", lambda *a: None)):
        dissipation._log_amount_basis = basis
        try:
            seconds, got = _best(lambda: dissipation._swing_dissipation(law, amps, values, ref))
        finally:
            dissipation._log_amount_basis = real
        row[label] = {
            "cpu_seconds": seconds,
            "largest_error_sd": float(np.max(np.abs(got - full) / sd)),
            "interval_ends_moved_sd": float(
                np.max(np.abs(np.percentile(got, [2.5, 97.5], axis=0) - ends) / sd)
            ),
        }
    print(
        f"{name:24s} {law.name:12s} before {row['before']['cpu_seconds']:.3f} s "
        f"(error ≤ {row['before']['largest_error_sd']:.4f} sd), log amounts "
        f"{row['log_amount']['cpu_seconds']:.3f} s (≤ {row['log_amount']['largest_error_sd']:.4f}"
        f" sd, ends {row['log_amount']['interval_ends_moved_sd']:.4f} sd)",
        flush=True,
    )
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=CASES, help="recording:law:seed")
    parser.add_argument("--output", default="band_log_amount")
    args = parser.parse_args()
    start = os.getloadavg()
    found, _ = commands(EXTERNAL)
    rows = []
    for case in args.cases:
        name, law, seed = case.split(":")
        if name not in found:
            print(f"{name}: absent", flush=True)
            continue
        for band in _bands(found[name], law, seed):
            rows.append({"case": case, **measure(name, band)})
    payload = {**provenance(__file__, {"cases": args.cases}, start), "bands": rows}
    print(f"wrote {write_results(args.output, payload)}")


if __name__ == "__main__":
    main()
