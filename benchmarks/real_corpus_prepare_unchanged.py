"""The preparation of every real-corpus command, here and in another checkout.

Each recording of ``data/real/manifest.json`` found on this machine (as
``tests/_real_corpus.py`` says) is read with each of its steps' options (the steps
with ``--law`` left out: the law does not enter the preparation) and prepared
(:func:`bayestribo.inference.preparation.prepare`); the observed Π increments, their
variances and grid are hashed (or the refusal recorded) and compared between this
checkout and the one given with ``--base``, each imported in its own subprocess.

Run::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus python benchmarks/real_corpus_prepare_unchanged.py \\
        --base /path/to/main-worktree --name NAME

Results: ``benchmarks/results/NAME.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results


def digest() -> dict[str, str]:
    """Each command's preparation hashed, with the package on ``PYTHONPATH``."""
    import hashlib
    import importlib.util
    import warnings

    import numpy as np

    from bayestribo.cli._common import read_run_from_args
    from bayestribo.cli.main import build_parser
    from bayestribo.inference.preparation import prepare

    spec = importlib.util.spec_from_file_location("_rc", ROOT / "tests" / "_real_corpus.py")
    corpus = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(corpus)
    listed = json.loads((ROOT / "data" / "real" / "manifest.json").read_text())
    out = {}
    for recording in listed["recordings"]:
        path = corpus.locate(recording)
        if path is None:
            continue
        for step in recording["steps"]:
            if "--law" in step["options"]:
                continue
            key = " ".join([recording["name"], *step["options"]])
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    args = build_parser().parse_args(["inspect", str(path), *step["options"]])
                    d = prepare(read_run_from_args(args)).data
                arrays = (d.increments, d.variance, d.tau_grid)
                joined = b"".join(np.asarray(a, float).tobytes() for a in arrays)
                out[key] = hashlib.sha256(joined).hexdigest()[:16]
            except Exception as exc:  # recorded, compared like any answer
                out[key] = f"refused: {type(exc).__name__}: {str(exc)[:100]}"
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path)
    ap.add_argument("--name", default="real_corpus_prepare_unchanged")
    ap.add_argument("--digest", type=Path, help=argparse.SUPPRESS)  # the subprocess's
    a = ap.parse_args()
    if a.digest is not None:
        a.digest.write_text(json.dumps(digest()))
        return
    found = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, tree in (("here", ROOT), ("base", a.base.resolve())):
            path = Path(tmp) / f"{label}.json"
            env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
            cmd = [sys.executable, __file__, "--digest", str(path)]
            subprocess.run(cmd, check=True, env=env, cwd=tmp)
            found[label] = json.loads(path.read_text())
    here, base = found["here"], found["base"]
    differ = {k: {"base": base.get(k), "here": here[k]} for k in here if here[k] != base.get(k)}
    payload = {
        "commit": commit(),
        "base_commit": commit(a.base),
        "commands": len(here),
        "identical": len(here) - len(differ),
        "differ": differ,
        "digests": here,
    }
    print(f"{payload['identical']} of {len(here)} identical; differ: {sorted(differ)}")
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
