"""Where the time of ``law="auto"`` goes: each law's fit inside the comparison, timed.

The machine is shared: each time is given as wall time and as the process's CPU time
(``time.process_time``), which the load of other processes hardly changes.

One run of a case of ``benchmarks/laws.py`` (the independent solve_ivp simulator of
``benchmarks/_laws_sim.py``, the same seeds as run ``--index`` there) is fitted with
``bayestribo.fit(run, law="auto")`` with the seed ``benchmarks/laws.py`` gives its auto
fit. Each law's fit inside the comparison (:func:`bayestribo.inference.comparison.
_fit_law`, the first grid and the rivals' finer grid apart) is timed, with its steps,
whether it converged and why not, and whether the comparison recognised it as its
nested law (extra terms at zero) or settled it at its optimum (not sampled: it could no
longer change the choice); the rest of the fit (preparation, the verdict again
in its own frame, the halves check, the summaries) is the total minus their sum.

Run (by hand)::

    PYTHONPATH=. timeout 3000 nice -n 10 python benchmarks/auto_speed.py --case coulomb

Writes ``benchmarks/results/auto_speed.json`` (``--output NAME``: ``NAME.json``) with
the machine description, the package's commit and the load averages.
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
from _tree import require_this_tree  # noqa: E402
from laws import CASES, _entropy, case_record  # noqa: E402


def _describe(comparison: dict[str, Any]) -> str | None:
    """The comparison's sentence, as the fit's text gives it."""
    if not comparison:
        return None
    from bayestribo.inference.comparison import LawComparison

    fields = ("run_name", "table", "best", "verdict", "as_good", "warnings", "adequate")
    kwargs = {k: comparison[k] for k in fields}
    kwargs.update(halves=comparison.get("halves"), rivals=comparison.get("rivals"))
    if "equivalent" in LawComparison.__dataclass_fields__:
        kwargs["equivalent"] = comparison.get("equivalent") or {}
    return LawComparison(**kwargs).describe()


def timed_auto(case: str, noise: float, index: int, seed: int, max_steps: int) -> dict[str, Any]:
    """Fit run ``index`` of ``case`` with ``law="auto"``; each law's fit timed."""
    from bayestribo import fit
    from bayestribo.inference import comparison

    entropy = _entropy(case, noise, index, seed)
    fit_seed = int(np.random.default_rng([*entropy, 1]).integers(2**31, size=2)[1])
    run, _facts = case_record(case, noise, entropy)
    fits: list[dict[str, Any]] = []
    original = comparison._fit_law

    def timed(law: str, prepared: Any, *args: Any, **kwargs: Any) -> Any:
        start, cpu = time.perf_counter(), time.process_time()
        sampled, idata = original(law, prepared, *args, **kwargs)
        s = sampled.run
        fits.append(
            {
                "law": law,
                "grid_points": int(prepared.data.increments.size),
                "seconds": time.perf_counter() - start,
                "cpu_seconds": time.process_time() - cpu,
                "n_steps": int(s.n_steps),
                "max_steps": int(sampled.settings.max_steps),
                "hit_max_steps": bool(s.n_steps >= sampled.settings.max_steps),
                "converged": bool(s.converged),
                "reasons": list(s.reasons),
                "parameters": list(sampled.posterior.names),
                "autocorr_time": dict(
                    zip(sampled.posterior.names, map(float, s.autocorr_time), strict=True)
                ),
            }
        )
        return sampled, idata

    comparison._fit_law = timed
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start, cpu = time.perf_counter(), time.process_time()
            result = fit(run, law="auto", seed=fit_seed, max_steps=max_steps)
            total, total_cpu = time.perf_counter() - start, time.process_time() - cpu
    finally:
        comparison._fit_law = original
    comparison_out = result.law_comparison or {}
    table = comparison_out.get("table", {})
    grid = fits[0]["grid_points"] if fits else None
    for entry in fits:
        row = table.get(entry["law"], {})
        if entry["grid_points"] == grid and "seconds" in row:
            # the comparison's own time of the law: its optimum too (the wrapper times
            # the sampling alone where the optimum is found before it)
            entry["sampling_seconds"] = entry["seconds"]
            entry["seconds"] = row["seconds"]
            if "cpu_seconds" in row:
                entry["sampling_cpu_seconds"] = entry["cpu_seconds"]
                entry["cpu_seconds"] = row["cpu_seconds"]
    for law, row in table.items():
        if row.get("reduces_to") or row.get("settled"):
            fits.append(
                {
                    "law": law,
                    "grid_points": grid,
                    "seconds": row["seconds"],
                    "cpu_seconds": row.get("cpu_seconds"),
                    "n_steps": 0,
                    "max_steps": max_steps,
                    "hit_max_steps": False,
                    "converged": None,
                    "reasons": [],
                    "reduces_to": row.get("reduces_to"),
                    "terms_at_zero": row.get("terms_at_zero"),
                    "settled": bool(row.get("settled")),
                    "settle": row.get("settle"),
                }
            )
    return {
        "case": case,
        "noise": noise,
        "index": index,
        "seed": seed,
        "fit_seed": fit_seed,
        "max_steps": max_steps,
        "total_seconds": total,
        "total_cpu_seconds": total_cpu,
        "laws_seconds": sum(f["seconds"] for f in fits),
        "laws_cpu_seconds": sum(f.get("cpu_seconds") or 0.0 for f in fits),
        "law": result.law,
        "converged": bool(result.converged),
        "verdict": comparison_out.get("verdict"),
        "as_good": comparison_out.get("as_good"),
        "equivalent": comparison_out.get("equivalent"),
        "comparison_warnings": comparison_out.get("warnings"),
        "describe": _describe(comparison_out),
        "fits": fits,
    }


def main(argv: list[str] | None = None) -> None:
    """Command line: time law="auto" on one simulated run per case asked."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=["coulomb"], choices=list(CASES))
    parser.add_argument("--noise", type=float, default=10.0)
    parser.add_argument("--index", type=int, default=0)
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--max-steps", type=int, default=6000)
    parser.add_argument("--output", default="auto_speed")
    args = parser.parse_args(argv)
    module = require_this_tree()
    load_start = os.getloadavg()
    runs = []
    for case in args.cases:
        out = timed_auto(case, args.noise, args.index, args.seed, args.max_steps)
        runs.append(out)
        print(
            f"{case}: {out['total_seconds']:.0f} s in all ({out['total_cpu_seconds']:.0f} s of "
            f"CPU), {out['laws_seconds']:.0f} s in the laws' fits; chose {out['law']}",
            flush=True,
        )
        for f in out["fits"]:
            print(
                f"  {f['law']:<28} {f['grid_points']:>5} pts {f['seconds']:7.1f} s "
                f"(CPU {f.get('cpu_seconds') or 0.0:7.1f} s) "
                f"{f['n_steps']:>6} steps converged={f['converged']} "
                f"{f.get('reduces_to') or ('settled' if f.get('settled') else '')} "
                f"{'; '.join(f['reasons'])}",
                flush=True,
            )
    path = write_results(
        args.output,
        {
            **provenance(module, vars(args), load_start),
            "runs": runs,
        },
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
