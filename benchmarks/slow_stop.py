"""A slow rig whose rest after the stop is shorter than the motion's blocks, here and
in another checkout, fitted as a user would and with the advice its warnings print.

Each record is ``tests/_slow_rig.py``'s independent ``solve_ivp`` simulation (0.3 Hz at
20 Hz, ζ = 0.004, μ_k = 0.002, 1.5 periods of rest after the stop, written with five
decimals of metres, 0.2 mm of noise) at a noise seed, with μ_s/μ_k = 20 (beyond the
default prior's 10) or 5 (inside it). Per record and checkout: ``bayestribo fit FILE
--json`` in a subprocess whose PYTHONPATH is the checkout; where its warnings advise
``--prior NAME=...``, the same with that option copied from the text. Recorded: the
exit status, whether ``bayestribo inspect`` finds the end of motion, the warnings' text
and whether the 95 % intervals of ζ, μ_k and μ_s cover the truth.

Run::

    python benchmarks/slow_stop.py --base /path/to/main-worktree --seeds 1-10

Results: ``benchmarks/results/slow_stop.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
from _machine import ROOT, commit, write_results  # noqa: E402
from _slow_rig import MU_K, ZETA, write_slow_decay  # noqa: E402

#: The static friction coefficients tried: μ_s/μ_k = 20 and 5.
MU_S = (0.04, 0.01)


def fit(tree: Path, path: Path, extra: list[str]) -> dict[str, Any]:
    """``bayestribo fit PATH --json EXTRA`` with the package of ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, "-m", "bayestribo", "fit", str(path), "--json", "--seed", "1", *extra],
        capture_output=True,
        text=True,
        env=env,
        cwd=tempfile.gettempdir(),
        timeout=900,
    )
    out: dict[str, Any] = {"exit": done.returncode, "stderr": done.stderr[-1500:]}
    try:
        record = json.loads(done.stdout)
    except json.JSONDecodeError:
        return out
    p = record["parameters"]
    return {**out, "parameters": {k: p[k]["interval"] for k in ("zeta", "mu_k", "mu_s") if k in p}}


def motion_ended(tree: Path, path: Path) -> bool | None:
    """Whether ``bayestribo inspect PATH`` with the package of ``tree`` finds the end of
    motion (None: it printed no analysis)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run(
        [sys.executable, "-m", "bayestribo", "inspect", str(path)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tempfile.gettempdir(),
        timeout=900,
    )
    line = next((x for x in done.stdout.splitlines() if x.startswith("analysed")), None)
    return None if line is None else "(motion ended)" in line


def covered(answer: dict[str, Any], mu_s: float) -> dict[str, bool] | None:
    """Whether each interval holds its truth."""
    found = answer.get("parameters")
    if not found:
        return None
    truth = {"zeta": ZETA, "mu_k": MU_K, "mu_s": mu_s}
    return {k: bool(lo <= truth[k] <= hi) for k, (lo, hi) in found.items()}


def seeds(text: str) -> list[int]:
    """``1-10`` or ``1,2,5``."""
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=True)
    ap.add_argument("--seeds", default="1-10")
    ap.add_argument("--name", default="slow_stop")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for mu_s in MU_S:
            for seed in seeds(args.seeds):
                path, _ = write_slow_decay(Path(folder), seed, mu_s)
                for label, tree in (("base", args.base), ("here", ROOT)):
                    first = fit(tree, path, [])
                    row = {"mu_s_ratio": mu_s / MU_K, "seed": seed, "tree": label}
                    row["motion_ended"] = motion_ended(tree, path)
                    row["first"] = {**first, "covered": covered(first, mu_s)}
                    advised = re.search(r"--prior (\S+=\w+\([^()]*\))", first["stderr"])
                    if advised:
                        then = fit(tree, path, ["--prior", advised[1]])
                        row["advised"] = f"--prior {advised[1]}"
                        row["followed"] = {**then, "covered": covered(then, mu_s)}
                    rows.append(row)
                    print(json.dumps({k: v for k, v in row.items()})[:400], flush=True)

    def summary(label: str, ratio: float) -> dict[str, Any]:
        mine = [r for r in rows if r["tree"] == label and r["mu_s_ratio"] == ratio]
        last = [r.get("followed", r["first"]) for r in mine]
        return {
            "records": len(mine),
            "motion_ended": sum(bool(r["motion_ended"]) for r in mine),
            "first_exit0": sum(r["first"]["exit"] == 0 for r in mine),
            "advised_prior": sum("advised" in r for r in mine),
            "answer_exit0": sum(a["exit"] == 0 for a in last),
            "answer_exit0_all_covered": sum(
                a["exit"] == 0 and bool(a.get("covered")) and all(a["covered"].values())
                for a in last
            ),
            "exit0_missing": sum(
                a["exit"] == 0 and bool(a.get("covered")) and not all(a["covered"].values())
                for a in last
            ),
        }

    result = {
        "commit": commit(),
        "base_commit": commit(args.base, short=True),
        "summary": {
            f"{label}, mu_s/mu_k {mu_s / MU_K:g}": summary(label, mu_s / MU_K)
            for label in ("base", "here")
            for mu_s in MU_S
        },
        "rows": rows,
    }
    print(json.dumps(result["summary"], indent=1))
    print(write_results(args.name, result))


if __name__ == "__main__":
    main()
