"""The default fit's warnings on every bundled run and real recording, here and in
another checkout: only the advice's order may change.

Each bundled run (``data/runs``, as recorded) and each real recording of
``benchmarks/real.py`` (as it is read there) is fitted with the default law (seed 1),
and each warning's category and text (the run's path left out) is kept, with the
options it advises in order (``--law``, ``--restoring``, ``--prior``) and the fit's
process CPU time. This checkout and the one given with ``--base`` (a worktree of main)
are each imported in their own subprocess, alternating over chunks of the records.
Records whose texts differ are listed with both texts and whether the same options are
advised (in another order).

Run::

    python benchmarks/advice_unchanged.py --base /path/to/main-worktree

Results: ``benchmarks/results/advice_unchanged.json`` (``--name``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import ROOT, commit, write_results

#: An option the fit's warnings advise.
ADVICE = re.compile(r"--law \w+|--restoring \w+|--prior \S+?=\w+\([^()]*\)")


def names(tree: Path) -> list[str]:
    """Every record: ``runs/<stem>`` and ``real/<name>``."""
    sys.path.insert(0, str(tree / "benchmarks"))
    import real

    out = [f"runs/{p.stem}" for p in sorted((tree / "data" / "runs").glob("*.csv"))]
    return out + [f"real/{name}" for name in real.recordings()]


def warnings_of(tree: Path, chosen: list[str]) -> dict[str, Any]:
    """The default fit's warnings on each record of ``chosen``, with the package of
    ``tree`` (imported: run in a subprocess whose PYTHONPATH is ``tree``)."""
    sys.path.insert(0, str(tree / "benchmarks"))
    import real

    from bayestribo import fit, read_run

    out: dict[str, Any] = {}
    for name in chosen:
        kind, _, stem = name.partition("/")
        if kind == "runs":
            path = tree / "data" / "runs" / f"{stem}.csv"
            run = read_run(path)
        else:
            run, _ = real.load(stem)
            path = real.recordings()[stem]
        start = time.process_time()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                fit(run, seed=1)
                status = "fitted"
            except Exception as exc:  # recorded, compared like any answer
                status = f"refused: {type(exc).__name__}"
        cpu = time.process_time() - start
        texts = [[w.category.__name__, str(w.message).replace(str(path), "<run>")] for w in caught]
        options = [o for _, text in texts for o in ADVICE.findall(text)]
        out[name] = {"status": status, "warnings": texts, "advice": options, "cpu_s": cpu}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", type=Path, required=False)
    ap.add_argument("--name", default="advice_unchanged")
    ap.add_argument("--chunk", type=int, default=8, help="records per subprocess")
    ap.add_argument("--only", nargs="*", help="these records (runs/NAME, real/NAME)")
    ap.add_argument("--records", type=Path, help=argparse.SUPPRESS)  # the subprocess's
    ap.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.out is not None:
        chosen = json.loads(a.records.read_text())
        tree = Path(os.environ["PYTHONPATH"])
        a.out.write_text(json.dumps(warnings_of(tree, chosen)))
        return
    everything = a.only or names(ROOT)
    found: dict[str, dict[str, Any]] = {"here": {}, "base": {}}
    with tempfile.TemporaryDirectory() as tmp:
        chunks = [everything[i : i + a.chunk] for i in range(0, len(everything), a.chunk)]
        for i, chunk in enumerate(chunks):
            records = Path(tmp) / "records.json"
            records.write_text(json.dumps(chunk))
            order = (("here", ROOT), ("base", a.base.resolve()))
            for label, tree in order if i % 2 == 0 else order[::-1]:
                path = Path(tmp) / f"{label}.json"
                env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
                cmd = [sys.executable, __file__, "--records", str(records), "--out", str(path)]
                subprocess.run(cmd, check=True, env=env, cwd=tmp)
                found[label].update(json.loads(path.read_text()))
            print(f"chunk {i + 1}/{len(chunks)}", flush=True)
    here, base = found["here"], found["base"]

    def texts(entry: dict[str, Any]) -> list:
        return [entry["status"], entry["warnings"]]

    differ = {
        k: {
            "base": base[k]["warnings"],
            "here": here[k]["warnings"],
            "advice_base": base[k]["advice"],
            "advice_here": here[k]["advice"],
            "same_options": sorted(base[k]["advice"]) == sorted(here[k]["advice"]),
        }
        for k in here
        if texts(here[k]) != texts(base[k])
    }
    ratios = [
        here[k]["cpu_s"] / base[k]["cpu_s"]
        for k in here
        if base[k]["cpu_s"] > 0 and here[k]["status"] == "fitted"
    ]
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
        "cpu_ratio_median": statistics.median(ratios) if ratios else None,
        "cpu_ratio_range": [min(ratios), max(ratios)] if ratios else None,
        "here": here,
    }
    print(f"{payload['identical']} of {len(here)} identical; differ: {sorted(differ)}")
    print(f"CPU here/base: median {payload['cpu_ratio_median']}")
    print(write_results(a.name, payload))


if __name__ == "__main__":
    main()
