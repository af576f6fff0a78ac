"""The optimiser's multi-start: every start to its end, or a start that comes within a
Laplace sd of an optimum found before ends there.

:func:`bayestribo.inference.start.maximum_a_posteriori` starts the least squares from
each of the decay's first guesses, and, with μ_s/μ_k, from each again with the ratio
at the middle of its range. On a law with a drag and no closed form the coarse model's
starts already stop where they join an optimum found before; this measures the same
rule where the posterior itself is maximised (the closed forms, laws without a drag,
the averaged model), applied by a wrapper, against every start run to its end (the
package's rule), alternately in one process. Each recording a user would give
(``auto_ratio.commands``: the bundled runs, ``../shared/external-data`` and the real
corpus where found) is fitted with ``bayestribo fit FILE --law LAW --seed 1`` in this
process, every call of ``maximum_a_posteriori`` recorded: the optimum, its Laplace
sds, its log density and its CPU time; the kernels are loaded first (seed 99, not
timed). Reported: the largest shift of an optimum in the Laplace sds of the
package's (μ_s/μ_k, whose Laplace variance is zero, left out), the log density's
difference, and the multi-start's CPU time under each rule.

Run (by hand, about 6 minutes)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus PYTHONPATH=. \\
        timeout 1800 python benchmarks/start_join.py

Writes ``benchmarks/results/start_join.json`` (``--output NAME``: ``NAME.json``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import auto_ratio  # noqa: E402
from _machine import commit, provenance, write_results  # noqa: E402

LAWS = ("viscous+coulomb", "viscous", "coulomb", "hysteretic", "coulomb+hysteretic")


_CALLS: list[dict[str, Any]] = []  # the calls of the fit being run
_JOIN = [False]  # the rule measured: a start that joins a found optimum ends there


def _install() -> None:
    """Record every ``maximum_a_posteriori`` call (the module's name and the name
    ``law_frame`` imported), and apply the joining rule to the starts of a call where
    ``_JOIN`` is set."""
    import bayestribo.inference.law_frame as law_frame
    import bayestribo.inference.start as start

    original, optimise = start.maximum_a_posteriori, start._optimise
    joined: list[Any] = []  # the optima of this call's starts so far

    def joining(posterior: Any, guess: Any, ratio: Any = None, found: Any = None) -> Any:
        if found is not None or not _JOIN[0]:  # the coarse multi-start joins already
            return optimise(posterior, guess, ratio, found)
        out = optimise(posterior, guess, ratio, list(joined))
        joined.append(out)
        return out

    def recorded(posterior: Any, decay: Any) -> Any:
        joined.clear()
        cpu = time.process_time()
        out = original(posterior, decay)
        ms = 1000.0 * (time.process_time() - cpu)
        theta, cov, _ = out
        _CALLS.append(
            {
                "names": list(posterior.names),
                "theta": [float(x) for x in theta],
                "sd": [float(x) for x in np.sqrt(np.clip(np.diag(cov), 0.0, None))],
                "log_density": float(posterior(np.asarray(theta)[None])[0]),
                "ms": ms,
            }
        )
        return out

    start._optimise = joining
    start.maximum_a_posteriori = law_frame.maximum_a_posteriori = recorded


def record_calls(argv: list[str], join: bool) -> tuple[int, list[dict[str, Any]]]:
    """Exit code of ``bayestribo fit ARGV`` and each ``maximum_a_posteriori`` call's
    optimum, Laplace sds, log density and CPU milliseconds, with or without the rule."""
    _CALLS.clear()
    _JOIN[0] = join
    code = auto_ratio.run(argv)[0]
    return code, list(_CALLS)


def compare(fits: dict[str, Any]) -> dict[str, Any]:
    """Per recording and law: the largest shift of an optimum under the rule in the
    Laplace sds of the optimum without it, the log density's difference (with minus
    without; the largest in magnitude over the fit's calls) and the CPU times."""
    rows, ms_join, ms_every = [], 0.0, 0.0
    for key, fit in fits.items():
        a, b = fit["join"], fit["every"]
        if len(a["calls"]) != len(b["calls"]) or not a["calls"]:
            rows.append({"fit": key, "note": "calls differ in number or none made"})
            continue
        shift, diffs = 0.0, [0.0]
        for ca, cb in zip(a["calls"], b["calls"], strict=True):
            for name, x, y, sd in zip(ca["names"], ca["theta"], cb["theta"], cb["sd"], strict=True):
                if name != "mu_s_ratio" and sd > 0:
                    shift = max(shift, abs(x - y) / sd)
            diffs.append(ca["log_density"] - cb["log_density"])
        t_join = sum(c["ms"] for c in a["calls"])
        t_every = sum(c["ms"] for c in b["calls"])
        ms_join, ms_every = ms_join + t_join, ms_every + t_every
        rows.append(
            {
                "fit": key,
                "exit": [a["exit"], b["exit"]],
                "shift_sd": shift,
                "log_density_join_minus_every": max(diffs, key=abs),
                "ms_join_every": [t_join, t_every],
            }
        )
    compared = [r for r in rows if "shift_sd" in r]
    return {
        "rows": rows,
        "fits_compared": len(compared),
        "shifted_over_0.1_sd": sum(r["shift_sd"] > 0.1 for r in compared),
        "worse_by_over_0.01": sum(r["log_density_join_minus_every"] < -0.01 for r in compared),
        "largest_shift_sd": max((r["shift_sd"] for r in compared), default=0.0),
        "most_negative_log_density_difference": min(
            (r["log_density_join_minus_every"] for r in compared), default=0.0
        ),
        "multi_start_ms_join_every": [ms_join, ms_every],
        "cpu_ratio_join_over_every": ms_join / ms_every if ms_every else None,
    }


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laws", nargs="+", default=list(LAWS))
    parser.add_argument("--only", nargs="*", help="recordings to fit (default: all)")
    parser.add_argument("--output", default="start_join")
    args = parser.parse_args(argv)
    import bayestribo

    load_start = os.getloadavg()
    _install()
    commands, absent = auto_ratio.commands(auto_ratio.EXTERNAL)
    for path in sorted((ROOT / "data" / "runs").glob("*.csv")):
        commands.setdefault(f"bundled {path.stem}", [str(path)])
    if args.only:
        commands = {k: v for k, v in commands.items() if k in args.only}
    for command in commands.values():  # kernels compiled or loaded before any timing
        for law in args.laws:
            record_calls([*command, "--law", law, "--seed", "99"], False)
        break
    fits: dict[str, Any] = {}
    for name, command in commands.items():
        for law in args.laws:
            argv_ = [*command, "--law", law, "--seed", "1"]
            every = record_calls(argv_, False)
            join = record_calls(argv_, True)
            fits[f"{name} | {law}"] = {
                "every": {"exit": every[0], "calls": every[1]},
                "join": {"exit": join[0], "calls": join[1]},
            }
            print(f"{name} | {law}: exit {every[0]}/{join[0]}", flush=True)
    out = compare(fits)
    print({k: v for k, v in out.items() if k != "rows"})
    package = Path(bayestribo.__file__).resolve().parent
    write_results(
        args.output,
        {
            "package_commit": commit(package.parent),
            **provenance(str(package), {"laws": args.laws, "only": args.only}, load_start),
            "absent": absent,
            **out,
            "fits": fits,
        },
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
