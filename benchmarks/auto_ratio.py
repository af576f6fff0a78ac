"""``--law auto`` against the default fit, on every recording a user would give it.

Issue 42's first goal: ``bayestribo fit FILE --law auto`` within 10 times the default
fit's time on the bundled runs and on every real recording (``../shared/external-data``
and the real corpus of ``data/real/``). Each recording is fitted by the command a user
gives (``bayestribo.cli.main`` called in this process, its output discarded): the
manifest's last step for a real-corpus recording, without ``--law auto`` for the default
fit and with it for ``auto``. One warm process: every command is run once (seed 99)
before anything is timed, so compiled kernels are loaded; then, per seed, the default
fit and ``auto`` one after the other, each timed in process CPU time
(``time.process_time``), which the load of other processes hardly changes. The ratio
of a seed is its ``auto`` over its default fit; the summary gives the median over
seeds, the exit codes and the law ``auto`` chose.

Run (by hand; about 5 minutes a seed on a quiet machine)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus PYTHONPATH=. \\
        timeout 3600 python benchmarks/auto_ratio.py --seeds 1 2 3

Writes ``benchmarks/results/auto_ratio.json`` (``--output NAME``: ``NAME.json``).
Real-corpus recordings whose files are not found are listed as absent.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import json
import os
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from _machine import provenance, write_results  # noqa: E402

EXTERNAL = ROOT.parent / "shared" / "external-data"


def _corpus_module() -> Any:
    spec = importlib.util.spec_from_file_location("_real_corpus", ROOT / "tests" / "_real_corpus.py")
    module = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(module)
    return module


def commands(external: Path) -> tuple[dict[str, list[str]], list[str]]:
    """Each recording's command (file and options, no ``--law``), and the absent ones."""
    out: dict[str, list[str]] = {
        "bundled glycerol-N0.31-r1": [str(ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv")],
        "bundled air-r1": [str(ROOT / "data" / "runs" / "air-r1.csv")],
    }
    appstat = external / "appstat2020-harmonic-oscillator"
    for p in sorted(appstat.glob("HarmOsc*.txt")):
        out[p.stem] = [str(p), "--columns", "t", "x", "--length-unit", "arbitrary"]
    for p in sorted((external / "smorzamento-spring-disc").glob("*.csv")):
        mass = p.stem.split("_")[-2]
        name = "smorzamento-" + p.stem.rsplit("_", 1)[-1]
        out[name] = [str(p), "--columns", "t", "x", "v", "ignore", "--mass", mass]
    corpus = _corpus_module()
    absent = []
    for rec in corpus.manifest()["recordings"]:
        path = corpus.locate(rec)
        if path is None:
            absent.append(rec["name"])
            continue
        options = [o for o in rec["steps"][-1]["options"]]
        if "--law" in options:
            i = options.index("--law")
            del options[i : i + 2]
        out[rec["name"]] = [str(path), *options]
    return out, absent


def run(argv: list[str]) -> tuple[int, float, str | None]:
    """Exit code, process CPU seconds and the law of ``bayestribo fit ARGV --json``."""
    from bayestribo.cli.main import main

    stdout = io.StringIO()
    cpu = time.process_time()
    with (
        contextlib.redirect_stdout(stdout),
        contextlib.redirect_stderr(io.StringIO()),
        warnings.catch_warnings(),
    ):
        code = main(["fit", *argv, "--json"])
    seconds = time.process_time() - cpu
    law = None
    with contextlib.suppress(ValueError, KeyError, TypeError):
        law = json.loads(stdout.getvalue())["law"]
    return int(code or 0), seconds, law


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--external", type=Path, default=EXTERNAL)
    parser.add_argument("--only", nargs="*", help="recordings to fit (default: all)")
    parser.add_argument("--output", default="auto_ratio")
    args = parser.parse_args(argv)
    cmds, absent = commands(args.external)
    if args.only:
        cmds = {k: v for k, v in cmds.items() if k in args.only}
    load_start = os.getloadavg()
    for name, cmd in cmds.items():  # warm: every kernel compiled or loaded
        run([*cmd, "--seed", "99"])
        run([*cmd, "--seed", "99", "--law", "auto"])
        print(f"warm {name}", flush=True)
    fits: dict[str, list[dict[str, Any]]] = {name: [] for name in cmds}
    for seed in args.seeds:
        for name, cmd in cmds.items():
            d_code, d_cpu, d_law = run([*cmd, "--seed", str(seed)])
            a_code, a_cpu, a_law = run([*cmd, "--seed", str(seed), "--law", "auto"])
            row = {
                "seed": seed,
                "default_exit": d_code,
                "default_cpu_seconds": d_cpu,
                "default_law": d_law,
                "auto_exit": a_code,
                "auto_cpu_seconds": a_cpu,
                "auto_law": a_law,
                "ratio": a_cpu / d_cpu,
            }
            fits[name].append(row)
            print(
                f"{name:<28} seed {seed}  default {d_cpu:6.2f} s (exit {d_code})  "
                f"auto {a_cpu:6.2f} s (exit {a_code}, {a_law})  {a_cpu / d_cpu:5.1f}x",
                flush=True,
            )
    summary = {
        name: {
            "ratio_median": statistics.median(r["ratio"] for r in rows),
            "ratio_range": [min(r["ratio"] for r in rows), max(r["ratio"] for r in rows)],
            "default_cpu_median": statistics.median(r["default_cpu_seconds"] for r in rows),
            "auto_cpu_median": statistics.median(r["auto_cpu_seconds"] for r in rows),
            "auto_laws": sorted({str(r["auto_law"]) for r in rows}),
            "auto_exits": sorted({r["auto_exit"] for r in rows}),
        }
        for name, rows in fits.items()
        if rows
    }
    path = write_results(
        args.output,
        {
            **provenance(
                "bayestribo.cli.main", {"seeds": args.seeds, "only": args.only}, load_start
            ),
            "commands": cmds,
            "absent": absent,
            "summary": summary,
            "fits": fits,
        },
    )
    for name, row in summary.items():
        print(
            f"{name:<28} {row['ratio_median']:5.1f}x "
            f"({row['ratio_range'][0]:.1f}-{row['ratio_range'][1]:.1f})  "
            f"default {row['default_cpu_median']:.2f} s  auto {row['auto_cpu_median']:.2f} s  "
            f"{row['auto_laws']} exits {row['auto_exits']}"
        )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
