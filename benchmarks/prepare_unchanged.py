"""The analysis of every bundled run and real recording, here and in another checkout.

Each bundled run (``data/runs``) is prepared as recorded and with its displacement
alone (the velocity derived), and each real recording of ``benchmarks/real.py`` as it
is read there (and with its displacement alone where it has both channels); the
observed Π increments, their variances and grid (a SHA-256 of their bytes), the end
of motion and whether the record holds it are compared between this checkout and the
one given with ``--base`` (a worktree of main), each imported in its own subprocess.

Run::

    python benchmarks/prepare_unchanged.py --base /path/to/main-worktree

Results: ``benchmarks/results/prepare_unchanged.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results


def digest(tree: Path) -> dict[str, Any]:
    """What the analysis gives on every record, with the package of ``tree``
    (imported: run in a subprocess whose PYTHONPATH is ``tree``)."""
    import numpy as np

    sys.path.insert(0, str(tree / "benchmarks"))
    import real

    from bayestribo import read_run
    from bayestribo.inference.preparation import prepare
    from bayestribo.io.run import Run

    out: dict[str, Any] = {}

    def one(name: str, run: Any) -> None:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                p = prepare(run)
        except Exception as exc:  # recorded, compared like any answer
            out[name] = ["refused", type(exc).__name__, str(exc)[:120]]
            return
        d = p.data
        arrays = (d.increments, d.variance, d.tau_grid)
        h = hashlib.sha256(b"".join(np.asarray(a, float).tobytes() for a in arrays))
        out[name] = [h.hexdigest()[:16], p.decay.peaks.stop_time, bool(d.motion_ended)]

    for path in sorted((tree / "data" / "runs").glob("*.csv")):
        run = read_run(path)
        one(path.stem, run)
        alone = Run(run.time, run.displacement, None, run.metadata)
        one(path.stem + " (displacement alone)", alone)
    for name in real.recordings():
        run, _ = real.load(name)
        one(name, run)
        if run.velocity is not None and run.displacement is not None:
            alone = Run(run.time, run.displacement, None, run.metadata)
            one(name + " (displacement alone)", alone)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=False)
    ap.add_argument("--name", default="prepare_unchanged")
    ap.add_argument("--digest", type=Path, help=argparse.SUPPRESS)  # the subprocess's
    a = ap.parse_args()
    if a.digest is not None:
        a.digest.write_text(json.dumps(digest(Path(os.environ["PYTHONPATH"]))))
        return
    found = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, tree in (("here", ROOT), ("base", a.base.resolve())):
            path = Path(tmp) / f"{label}.json"
            env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
            subprocess.run(
                [sys.executable, __file__, "--digest", str(path)], check=True, env=env, cwd=tmp
            )
            found[label] = json.loads(path.read_text())
    here, base = found["here"], found["base"]
    differ = {k: {"base": base.get(k), "here": here.get(k)} for k in here if here[k] != base.get(k)}
    base_commit = subprocess.run(
        ["git", "-C", str(a.base), "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
    ).stdout.strip()
    payload = {
        "commit": commit(),
        "base_commit": base_commit,
        "records": len(here),
        "identical": len(here) - len(differ),
        "differ": differ,
        "digests": here,
    }
    print(f"{payload['identical']} of {len(here)} identical; differ: {sorted(differ)}")
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
