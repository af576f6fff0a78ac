"""``law="auto"`` on records whose laws of other ΔE(A) shapes are as good as its verdict.

Two sets, each fitted with ``bayestribo.fit(run, law="auto", seed=1)``:

* dithered coarse records of Coulomb decays (``benchmarks/_damped.py``, the records of
  ``benchmarks/coarse_dissipation.py`` at its seeds ``[5, steps, round(100 noise), i]``):
  friction at 4 steps across the swing and 0.05 step of noise, strong friction at 5 steps
  and 0.2 step, i = 1, 2, where a `viscous` verdict came with exit 0 before the check
  (``benchmarks/README.md``, the dithered coarse records' section);
* every bundled run (``data/runs/*.csv``), where the laws' shapes are told apart and
  nothing must change.

Per record: the verdict, the laws as good, ``law_comparison["shape_unresolved"]``, the
misfit warnings (exit 1) and, for the simulated records, the true law's shape (1 for
friction).

Run (by hand)::

    nice python benchmarks/shape_unresolved.py

Writes ``benchmarks/results/shape_unresolved.json`` (``--output NAME``).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _damped import DAMPINGS, quantise, simulate  # noqa: E402
from _machine import commit, write_results  # noqa: E402

META = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31, "gain_uncertainty": 0.0}
DITHERED = (("coulomb", 4, 0.05), ("strong-coulomb", 5, 0.2))


def one(run: Any, label: dict[str, Any]) -> dict[str, Any]:
    """Fit one record with law='auto' and keep what the check says."""
    import bayestribo
    from bayestribo.errors import ConvergenceWarning, MisfitWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = bayestribo.fit(run, law="auto", seed=1)
        except Exception as exc:  # recorded, never dropped
            return {**label, "refused": f"{type(exc).__name__}: {exc}"[:200]}
    comparison = result.law_comparison or {}
    misfits = sorted({w.category.__name__ for w in caught if issubclass(w.category, MisfitWarning)})
    exit1 = any(issubclass(w.category, (MisfitWarning, ConvergenceWarning)) for w in caught)
    return {
        **label,
        "exit": 1 if exit1 else 0,
        "verdict": comparison.get("verdict"),
        "as_good": comparison.get("as_good"),
        "shape_unresolved": comparison.get("shape_unresolved"),
        "misfit_warnings": misfits,
    }


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="shape_unresolved")
    parser.add_argument("--no-bundled", action="store_true")
    args = parser.parse_args(argv)
    from bayestribo.io.run import Run

    rows: list[dict[str, Any]] = []
    for name, steps, noise in DITHERED:
        decay = simulate(*DAMPINGS[name])
        for i in (1, 2):
            rng = np.random.default_rng([5, steps, round(100 * noise), i])
            placement = tuple(float(u) for u in rng.uniform(-0.5, 0.5, 2))
            x, v = quantise(decay, steps, placement, noise, rng)
            run = Run(time=decay.t, displacement=x, velocity=v, metadata=META)
            label = {"record": f"{name}, {steps} steps, {noise} step, i={i}", "true_slope": 1.0}
            rows.append(one(run, label))
            print(rows[-1], flush=True)
    if not args.no_bundled:
        for path in sorted((HERE.parent / "data" / "runs").glob("*.csv")):
            rows.append(one(str(path), {"record": path.stem}))
            print(rows[-1]["record"], rows[-1].get("exit"), rows[-1].get("verdict"), flush=True)
    simulated = [r for r in rows if "true_slope" in r]
    bundled = [r for r in rows if "true_slope" not in r]
    summary = {
        "dithered_records": len(simulated),
        "dithered_exit0": sum(r.get("exit") == 0 for r in simulated),
        "dithered_unresolved": sum(bool(r.get("shape_unresolved")) for r in simulated),
        "bundled_runs": len(bundled),
        "bundled_unresolved": sum(bool(r.get("shape_unresolved")) for r in bundled),
        "bundled_exit1": sum(r.get("exit") == 1 for r in bundled),
    }
    print(summary)
    write_results(args.output, {"commit": commit(), "summary": summary, "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
