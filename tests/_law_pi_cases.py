"""Π of every registered law on a parameter grid, as a tree before the creep's integration
computed it: the fixture of ``tests/test_model_laws_creep_unchanged.py``.

The rows that tree left finite must be the same to the bit in the tree that integrates
a drag's creep to rest (:mod:`bayestribo.model.laws._creep`), but for the rows whose
motion it ended by a creep whose ∫E it took from the quasi-static balance (at most
1e-8 of Π(0)): those are found by computing the grid again in a copy of that tree
whose rule takes no creep (``_CREEP_SHARE = 0``), where they are NaN.

Run once, from the tree that integrates the creep, with the older tree's path::

    PYTHONPATH=. python tests/_law_pi_cases.py /path/to/older/tree

which writes ``tests/law_pi_before_creep.npz`` (the cases, each tree's Π and the rows
ended by a creep). The cases themselves (:func:`cases`) are drawn here with a fixed
seed: each law's parameters from their default priors at the amplitude :data:`Y0`,
half of them on the prior's whole range and half scaled down by 10-1000 (a decay over
many half cycles), under each of :data:`CONFIGS`.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

FIXTURE = Path(__file__).resolve().parent / "law_pi_before_creep.npz"
#: The laws: every candidate, the cubic drag, and a power drag beside a viscous one.
LAWS = (
    "viscous",
    "coulomb",
    "quadratic",
    "power",
    "hysteretic",
    "cubic",
    "viscous+coulomb",
    "viscous+quadratic",
    "viscous+power",
    "coulomb+quadratic",
    "coulomb+power",
    "coulomb+hysteretic",
    "quadratic+hysteretic",
    "viscous+coulomb+quadratic",
)
Y0 = 7.4
TAU = np.linspace(0.0, 95.0, 31)
#: (y'₀, τ_end (inf: to the end of motion), steps, method) of each block of rows.
CONFIGS = (
    (0.0, np.inf, 0, "integrate"),
    (0.0, 80.0, 0, "integrate"),
    (0.9, np.inf, 0, "integrate"),
    (0.0, np.inf, -8, "integrate"),
    (0.0, np.inf, 0, "auto"),
)
ROWS = 24


def cases() -> list[dict]:
    """The blocks of rows: law, config and each parameter's values (ROWS,)."""
    from bayestribo.model.laws import get_law

    rng = np.random.default_rng(2024)
    out = []
    for name in LAWS:
        law = get_law(name)
        for yp0, tau_end, steps, method in CONFIGS:
            values = {}
            for p in law.parameters:
                spec = p.prior(Y0)
                low, high = float(spec["low"]), float(spec["high"])
                u = rng.uniform(low, high, ROWS)
                if p.name not in ("alpha", "mu_s_ratio", "eta"):
                    u[ROWS // 2 :] = high * 10.0 ** rng.uniform(-3.0, -1.0, ROWS - ROWS // 2)
                values[p.name] = u
            out.append(
                {
                    "law": name,
                    "yp0": yp0,
                    "tau_end": tau_end,
                    "steps": steps,
                    "method": method,
                    "values": values,
                }
            )
    return out


def compute(blocks: list[dict]) -> np.ndarray:
    """Π of every block's rows, stacked (blocks, ROWS, TAU.size)."""
    from bayestribo.model.laws import get_law

    out = np.empty((len(blocks), ROWS, TAU.size))
    for b, case in enumerate(blocks):
        law = get_law(case["law"])
        tau_end = None if np.isinf(case["tau_end"]) else float(case["tau_end"])
        out[b] = law.pi_grid(
            TAU,
            case["values"],
            np.full(ROWS, Y0),
            case["yp0"],
            tau_end,
            reference=Y0,
            method=case["method"],
            steps=case["steps"],
        )
    return out


def _run(tree: Path, cache: Path | None, target: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(tree))
    if cache is not None:  # else the user's law cache, where the older tree's laws are
        env["BAYESTRIBO_CACHE_DIR"] = str(cache)
    subprocess.run([sys.executable, __file__, "--compute", str(target)], env=env, check=True)


def main() -> None:
    if sys.argv[1] == "--compute":
        np.save(sys.argv[2], compute(cases()))
        return
    tree = Path(sys.argv[1]).resolve()
    work = Path(tempfile.mkdtemp(prefix="law_pi_cases_"))
    try:
        _run(tree, None, work / "before.npy")
        # the same tree taking no creep: the rows it ended by one are NaN there
        shutil.copytree(tree / "bayestribo", work / "copy" / "bayestribo")
        core = work / "copy" / "bayestribo" / "model" / "laws" / "_core.py"
        text, n = re.subn(
            r"^_CREEP_SHARE = .*$", "_CREEP_SHARE = 0.0", core.read_text(), flags=re.M
        )
        if n != 1:
            raise SystemExit("_CREEP_SHARE not found once in the older tree's _core.py")
        core.write_text(text)
        _run(
            work / "copy", Path(tempfile.gettempdir()) / "law_pi_cases_cache", work / "no_creep.npy"
        )
        before = np.load(work / "before.npy")
        no_creep = np.load(work / "no_creep.npy")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    blocks = cases()
    creep = np.isfinite(before).all(axis=-1) & ~np.isfinite(no_creep).all(axis=-1)
    commit = subprocess.run(
        ["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    np.savez_compressed(
        FIXTURE,
        before=before,
        creep=creep,
        cases=json.dumps(
            [{**c, "values": {k: v.tolist() for k, v in c["values"].items()}} for c in blocks]
        ),
        commit=commit,
    )
    print(f"{FIXTURE.name}: {before.shape[0]} blocks of {ROWS} rows, commit {commit}")
    finite = int(np.isfinite(before).all(axis=-1).sum())
    print(f"finite rows {finite}, ended by a creep {int(creep.sum())}")


if __name__ == "__main__":
    main()
