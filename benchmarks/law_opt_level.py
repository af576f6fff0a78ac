"""A law's compilation at numba's lower optimisation levels: CPU saved, warm calls lost,
and whether Π stays identical to the bit (lever for a test session's own law cache).

For each level of ``--levels`` (``NUMBA_OPT``) the package's own compiled functions are
first compiled once into a cache of that level (``NUMBA_CACHE_DIR``, a new folder per
level, so that no user's cache gets code of another level); then, for ``--rounds``
rounds (the levels alternating, reversed every other round) and each law of ``--laws``,
a fresh process with an empty law cache compiles the law on its first Π grid and times
its warm calls, as ``benchmarks/law_compile.py`` does (its worker, same inputs): the
first call's CPU, numba's compilation (outermost events), the median warm call to the
end of the record and to the end of motion, and the SHA-256 of the first call's Π.

Run: ``python benchmarks/law_opt_level.py --rounds 1``; writes
``benchmarks/results/law_opt_level.json``. ``--from-log FILE`` writes the rows of an
earlier run's printed lines instead of running.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import commit, write_results
from law_compile import TREE, measure


def row(level: str, law: str, round_: int) -> dict:
    """One fresh process's compilation of ``law`` at optimisation level ``level``."""
    result = measure(TREE, law, 5)
    return {
        "opt": level,
        "law": law,
        "round": round_,
        "first": result["first_call_cpu_s"],
        "compile": sum(e["inclusive_cpu_s"] for e in result["events"] if e["depth"] == 0),
        "warm": statistics.median(result["warm_cpu_s"]),
        "warm_motion": statistics.median(result["warm_motion_cpu_s"]),
        "sha": result["pi_sha256"][:16],
        "load": os.getloadavg()[0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--laws", nargs="+", default=["quadratic", "coulomb+power", "viscous+coulomb+quadratic"]
    )
    parser.add_argument("--levels", nargs="+", default=["3", "0", "1", "2"])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--from-log", type=Path, help="rows printed by an earlier run")
    parser.add_argument("--note", default="")
    parser.add_argument("--output", default="law_opt_level")
    args = parser.parse_args()
    if args.from_log:
        rows = [json.loads(line) for line in args.from_log.read_text().splitlines() if line]
    else:
        caches = Path(tempfile.mkdtemp(prefix="law-opt-"))
        rows = []
        for level in args.levels:  # the package's own functions, compiled at this level
            os.environ.update(NUMBA_OPT=level, NUMBA_CACHE_DIR=str(caches / level))
            measure(TREE, args.laws[0], 1)
        for r in range(args.rounds):
            for level in args.levels if r % 2 == 0 else args.levels[::-1]:
                os.environ.update(NUMBA_OPT=level, NUMBA_CACHE_DIR=str(caches / level))
                for law in args.laws:
                    rows.append(row(level, law, r))
                    print(json.dumps(rows[-1]), flush=True)
    summary = {}
    for law in sorted({r["law"] for r in rows}):
        reference = [r for r in rows if r["law"] == law and r["opt"] == "3"]
        for level in sorted({r["opt"] for r in rows}):
            mine = [r for r in rows if r["law"] == law and r["opt"] == level]
            if not mine or not reference:
                continue
            summary.setdefault(law, {})[level] = {
                "compile_cpu_s": statistics.median(r["compile"] for r in mine),
                "compile_ratio_to_O3": statistics.median(r["compile"] for r in mine)
                / statistics.median(r["compile"] for r in reference),
                "warm_ratio_to_O3": statistics.median(r["warm"] for r in mine)
                / statistics.median(r["warm"] for r in reference),
                "warm_motion_ratio_to_O3": statistics.median(r["warm_motion"] for r in mine)
                / statistics.median(r["warm_motion"] for r in reference),
                "pi_identical_to_O3": {r["sha"] for r in mine} == {r["sha"] for r in reference},
                "rounds": len(mine),
            }
    path = write_results(
        args.output,
        {
            "benchmark": "law_opt_level",
            "description": __doc__,
            "commit": commit(),
            "settings": {"laws": args.laws, "levels": args.levels, "rounds": args.rounds},
            "note": args.note,
            "rows": rows,
            "summary": summary,
        },
    )
    print(path)
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
