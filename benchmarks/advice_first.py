"""The first option a fit's warnings advise, followed as printed, here and in another
checkout: does it answer?

Situations, each an independent ``solve_ivp`` record (``tests/_law_recording.py``,
``tests/_slow_rig.py``) written as a file: quadratic drag alone (c₂/m = 40 /m, the
paper's rig without a load, noise seeds 1-3); damping that grows with the swing
(ζ = 0.01, c₂/m = 47 /m, Coulomb friction μ_k = 0.0294 sticking at μ_s = μ_k, 2 kHz,
seeds 1-3); viscous damping and Coulomb friction sticking at μ_s/μ_k = 15 and 20 on
the paper's rig (seeds 1-3; other ratios with ``--ratios``, a subset of the records
with ``--only``); the slow rig at μ_s/μ_k = 20 (seeds 1-4). Per record and
checkout: ``bayestribo fit FILE --json --seed 1`` (``bayestribo.cli.main``, in a
subprocess whose PYTHONPATH is the checkout), the first ``--law``, ``--restoring`` or
``--prior`` option its warnings print, and the fit with that option added: its exit
status, its law and whether the 95 % intervals hold the truths.

Run::

    python benchmarks/advice_first.py --base /path/to/main-worktree

Results: ``benchmarks/results/advice_first.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import ROOT, commit, write_results  # noqa: E402

#: An option the fit's warnings advise.
ADVICE = re.compile(r"--law \w+|--restoring \w+|--prior \S+?=\w+\([^()]*\)")
OMEGA = 2.0 * math.pi * 32.6
MASS, LOAD = 0.035, 0.31


def situations(
    folder: Path, ratios: tuple[float, ...] = (15, 20)
) -> dict[str, tuple[Path, dict[str, float]]]:
    """Each record's file and its truths (names of ``fit --json``'s parameters);
    ``ratios``: the μ_s/μ_k of the sticking records."""
    sys.path.insert(0, str(ROOT / "tests"))
    from _law_recording import law_recording
    from _slow_rig import MU_K, ZETA, write_slow_decay

    from bayestribo.io import write_run

    out: dict[str, tuple[Path, dict[str, float]]] = {}
    for seed in (1, 2, 3):
        run = law_recording(lambda v: 40.0 * v * abs(v), duration_s=1.5, seed=seed, load_N=None)
        out[f"drag_s{seed}"] = (write_run(run, folder / f"drag_s{seed}.csv"), {"c2_SI": 40 * MASS})
        run = law_recording(
            lambda v: 2.0 * 0.01 * OMEGA * v + 47.0 * v * abs(v),
            friction=0.0294 * LOAD / MASS,
            static_ratio=1.0,
            x0=1.5e-3,
            sample_rate_Hz=2000.0,
            duration_s=1.0,
            seed=seed,
        )
        truths = {"zeta": 0.01, "mu_k": 0.0294, "c2_SI": 47 * MASS}
        out[f"growing_s{seed}"] = (write_run(run, folder / f"growing_s{seed}.csv"), truths)
        for ratio in ratios:
            run = law_recording(
                lambda v: 2.0 * 0.02 * OMEGA * v,
                friction=0.03 * LOAD / MASS,
                static_ratio=ratio,
                duration_s=1.0,
                seed=seed,
            )
            truths = {"zeta": 0.02, "mu_k": 0.03, "mu_s": 0.03 * ratio}
            name = f"sticks{ratio:g}_s{seed}"
            out[name] = (write_run(run, folder / f"{name}.csv"), truths)
    for seed in (1, 2, 3, 4):
        path, _ = write_slow_decay(folder, seed=seed)
        out[f"slow20_s{seed}"] = (path, {"zeta": ZETA, "mu_k": MU_K, "mu_s": 20 * MU_K})
    return out


def command(argv: list[str]) -> tuple[int, str, str]:
    """``bayestribo ARGV`` in this process: exit status, stdout, stderr."""
    from bayestribo.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def followed(cases: dict[str, Any]) -> dict[str, Any]:
    """Each case's first fit, its first advice and the fit that follows it."""
    found: dict[str, Any] = {}
    for name, (path, truths) in cases.items():
        argv = ["fit", str(path), "--json", "--seed", "1"]
        status, _, err = command(argv)
        options = ADVICE.findall(err)
        entry: dict[str, Any] = {"exit": status, "advice": options}
        if options:
            status, out, err = command([*argv, *options[0].split()])
            record = json.loads(out)
            p = record["parameters"]
            entry["followed"] = {
                "option": options[0],
                "exit": status,
                "law": record["law"],
                "covered": {
                    k: bool(p[k]["interval"][0] <= v <= p[k]["interval"][1])
                    for k, v in truths.items()
                    if k in p
                },
                "warnings": [w[:160] for w in err.split("bayestribo fit: warning: ") if w],
            }
            f = entry["followed"]
            f["answers"] = f["exit"] == 0 and all(f["covered"].values()) and bool(f["covered"])
        found[name] = entry
        print(name, entry.get("advice", [])[:1], entry.get("followed", {}).get("answers"))
    return found


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path)
    ap.add_argument("--name", default="advice_first")
    ap.add_argument("--ratios", type=float, nargs="+", default=[15, 20], help="μ_s/μ_k sticking")
    ap.add_argument("--only", nargs="*", help="only the records whose names start so")
    ap.add_argument("--folder", type=Path, help=argparse.SUPPRESS)  # the subprocess's
    ap.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.out is not None:
        cases = json.loads((a.folder / "cases.json").read_text())
        a.out.write_text(json.dumps(followed({k: (Path(p), t) for k, (p, t) in cases.items()})))
        return
    result: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = {
            k: (str(p), t)
            for k, (p, t) in situations(folder, tuple(a.ratios)).items()
            if not a.only or k.startswith(tuple(a.only))
        }
        (folder / "cases.json").write_text(json.dumps(cases))
        for label, tree in (("here", ROOT), ("base", a.base.resolve())):
            path = folder / f"{label}.json"
            env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
            cmd = [sys.executable, __file__, "--folder", str(folder), "--out", str(path)]
            subprocess.run(cmd, check=True, env=env, cwd=tmp)
            result[label] = json.loads(path.read_text())
    base_commit = subprocess.run(
        ["git", "-C", str(a.base), "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
    ).stdout.strip()
    tally = {
        label: {
            "first_advice_answers": sum(
                bool(e.get("followed", {}).get("answers")) for e in found.values()
            ),
            "records": len(found),
        }
        for label, found in result.items()
    }
    payload = {
        "commit": commit(),
        "base_commit": base_commit,
        "command": sys.argv[1:],
        "tally": tally,
        **result,
    }
    print(json.dumps(tally))
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
