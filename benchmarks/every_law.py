"""Every candidate law fitted alone, against the default fit, on the bundled and real runs.

Issue 42's second goal: each law ``law="auto"`` compares
(:func:`bayestribo.model.laws.candidates.candidate_laws`) fitted on its own within 3× the
default fit's time, and converged, on the bundled run and on every recording of
``../shared/external-data`` (read as ``benchmarks/real.py`` reads them).

One process fits everything in turn: first every law once on the bundled run (imports,
numba compilation and caches are not timed), then, per recording, the default law and
each candidate law with seed 1 (``--seed``). Each fit is timed in process CPU time (user + system;
on a shared machine the other processes' turns do not count) and wall time; recorded:
converged, ESS_min, the steps, and the ratio of its CPU time to the default fit's on
the same recording. Results are written after every fit to
``benchmarks/results/every_law.json``.

Run (tens of minutes; in the background)::

    timeout 5400 python benchmarks/every_law.py

``--recordings`` keeps the recordings whose names contain one of the words given
("bundled", "HarmOsc3", ...). The package fitted is the one Python imports: a side by
side of two trees runs this file twice at once, each with ``PYTHONPATH`` at its tree
and its own ``--output``; the results name the tree and its commit. ``--compare BASE NEW``
then prints, per recording and law, both ratios to the default fit and the largest shift
of a posterior mean from BASE to NEW in BASE's posterior sd (results/NAME.json each)::

    python benchmarks/every_law.py --compare every_law_main every_law_branch

``--perturb-coarse EPS`` scales the coarse model's Π (the optimiser's multi-start, any
``steps`` but 0) by 1 + EPS: how far a posterior moves under a change of that size (far
below the coarse model's own error, ~1e-5 of Π(0)) says how much of it the record and
the law determine, and how much the optimiser's path.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import commit, write_results

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
DEFAULT = "viscous+coulomb"


def _cpu() -> float:
    t = os.times()
    return t.user + t.system


def _fit(run: Any, law: str, seed: int = 1) -> dict[str, Any]:
    from bayestribo import fit

    cpu, wall = _cpu(), time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = fit(run, law=law, seed=seed)
        except Exception as exc:  # recorded: a law that cannot fit a record says why
            return {"error": f"{type(exc).__name__}: {exc}"[:400]}
    cpu, wall = _cpu() - cpu, time.perf_counter() - wall
    diag = result.diagnostics
    surrogate = diag.get("surrogate") or {}
    return {
        "cpu_s": cpu,
        "wall_s": wall,
        "converged": bool(result.converged),
        "ess_min": float(diag.get("ess_min", float("nan"))),
        "n_steps": int(diag.get("n_steps", 0)),
        "surrogate_attempt": surrogate.get("attempt"),
        "surrogate_passed": surrogate.get("passed"),
        "warnings": sorted({w.category.__name__ for w in caught}),
        # each parameter's posterior mean and sd: a change that speeds a law up must
        # leave them where they were (compare two runs with --compare)
        "posterior": {
            name: [float(np.mean(result.samples(name))), float(np.std(result.samples(name)))]
            for name in result.parameter_names
        },
    }


def compare(base: dict[str, Any], new: dict[str, Any]) -> list[dict[str, Any]]:
    """Per recording and law of both results: each one's CPU time over its default
    fit's, converged or not, and the largest |Δ mean| / sd of a posterior quantity
    from ``base`` to ``new`` (sd ``base``'s; inf where it is 0 and the mean moved)."""
    rows = []
    for name, laws in base["recordings"].items():
        other = new["recordings"].get(name, {})
        for law, row in laws.items():
            if law not in other:
                continue
            shift = 0.0
            for quantity, (mean, sd) in row.get("posterior", {}).items():
                moved = abs(other[law].get("posterior", {}).get(quantity, [mean])[0] - mean)
                if moved > 0.0:
                    shift = max(shift, moved / sd if sd > 0.0 else float("inf"))
            rows.append(
                {
                    "recording": name,
                    "law": law,
                    "base_over_default": row.get("over_default"),
                    "new_over_default": other[law].get("over_default"),
                    "base_converged": row.get("converged"),
                    "new_converged": other[law].get("converged"),
                    "largest_shift_sd": shift,
                }
            )
    return rows


def _perturb_coarse(eps: float) -> None:
    """Scale every Π of a model with fixed steps (the coarse model of the optimiser's
    multi-start) by 1 + ``eps`` in this process."""
    from bayestribo.model.laws.law import Law

    exact = Law.pi_grid

    def scaled(self: Law, *args: Any, steps: int = 0, **kwargs: Any) -> Any:
        pi = exact(self, *args, steps=steps, **kwargs)
        return pi * (1.0 + eps) if steps != 0 else pi

    Law.pi_grid = scaled  # type: ignore[method-assign]


def main() -> None:
    import json

    import real

    import bayestribo
    from bayestribo import read_run
    from bayestribo.model.laws.candidates import candidate_laws

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", nargs="*", default=None, help="default: every candidate")
    parser.add_argument("--output", default="every_law", help="results/NAME.json")
    parser.add_argument(
        "--recordings",
        nargs="*",
        default=None,
        help="keep the recordings whose names contain one of these (default: every one)",
    )
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("BASE", "NEW"),
        help="print two results side by side (results/BASE.json, results/NEW.json)",
    )
    parser.add_argument(
        "--seed", type=int, default=1, help="seed of every fit but the warm-up's (default 1)"
    )
    parser.add_argument(
        "--perturb-coarse",
        type=float,
        default=0.0,
        metavar="EPS",
        help="scale the coarse model's Π by 1 + EPS (a sensitivity check)",
    )
    args = parser.parse_args()
    if args.perturb_coarse:
        _perturb_coarse(args.perturb_coarse)
    if args.compare:
        base, new = (
            json.loads((ROOT / "benchmarks" / "results" / f"{n}.json").read_text())
            for n in args.compare
        )
        for row in compare(base, new):
            print(
                f"{row['recording']:28s} {row['law']:28s} "
                f"{row['base_over_default'] or float('nan'):6.2f}x -> "
                f"{row['new_over_default'] or float('nan'):6.2f}x  "
                f"converged {row['base_converged']}/{row['new_converged']}  "
                f"shift {row['largest_shift_sd']:.2f} sd"
            )
        return
    laws = tuple(args.laws or candidate_laws())

    def kept(name: str) -> bool:
        return args.recordings is None or any(word in name for word in args.recordings)

    runs: dict[str, Any] = {"bundled glycerol-N0.31-r1": read_run(BUNDLED)}
    first = runs["bundled glycerol-N0.31-r1"]
    for name in real.recordings():
        if not kept(name):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs[name] = real.load(name)[0]
    runs = {name: run for name, run in runs.items() if kept(name)}
    if not runs:
        parser.error(f"--recordings: no recording's name contains any of {args.recordings}")
    tree = Path(bayestribo.__file__).resolve().parents[1]
    results: dict[str, Any] = {
        "laws": list(laws),
        "package_tree": str(tree),
        "package_commit": commit(tree),
        "perturb_coarse": args.perturb_coarse,
        "seed": args.seed,
        "recordings": {},
    }
    t0 = time.perf_counter()
    for law in (DEFAULT, *laws):  # warm-up: imports, compilation, caches
        _fit(first, law)
    results["warm_up_s"] = time.perf_counter() - t0
    for name, run in runs.items():
        rows: dict[str, Any] = {}
        results["recordings"][name] = rows
        for law in (DEFAULT, *[law for law in laws if law != DEFAULT]):
            rows[law] = _fit(run, law, args.seed)
            base = rows[DEFAULT].get("cpu_s")
            if base and "cpu_s" in rows[law]:
                rows[law]["over_default"] = rows[law]["cpu_s"] / base
            print(name, law, rows[law], flush=True)
            write_results(args.output, {"load_average": os.getloadavg(), **results})
    summary = {}
    for name, rows in results["recordings"].items():
        ratios = {law: r.get("over_default") for law, r in rows.items() if law != DEFAULT}
        summary[name] = {
            "worst_law": max(ratios, key=lambda k: ratios[k] or 0.0) if ratios else None,
            "worst_over_default": max((v for v in ratios.values() if v), default=None),
            "within_3x": sorted(k for k, v in ratios.items() if v is not None and v <= 3.0),
            "not_converged": sorted(k for k, r in rows.items() if not r.get("converged")),
        }
    results["summary"] = summary
    write_results(args.output, {"load_average": os.getloadavg(), **results})


if __name__ == "__main__":
    main()
