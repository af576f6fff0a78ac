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
Real-corpus recordings whose files are not found are listed as absent. Side by side
with another commit: run this file with ``PYTHONPATH`` on that commit's worktree at the
same time (``--output`` another name; the package timed and its commit are recorded),
then ``python benchmarks/auto_ratio.py --compare NEW.json OLD.json``: the ratios, CPU
times and laws of both, and how far the posterior means of ``auto``'s answers moved (in
posterior sds, the same seeds), written to ``NEW_compare.json``. ``--every-law``: each
candidate law alone (``--law NAME``) against the default fit instead (issue 42's second
goal, each within 3x and converged), on the same recordings (``every_law.json``; a
law over 3x by its median ratio over the seeds);
``--laws NAME ...`` those laws only. ``--compare`` of two ``--every-law`` files: per
recording and law the CPU, ratios, convergence and the largest shift of a posterior
mean between the same seeds.
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
from _machine import commit, provenance, write_results  # noqa: E402

EXTERNAL = ROOT.parent / "shared" / "external-data"


def _corpus_module() -> Any:
    spec = importlib.util.spec_from_file_location(
        "_real_corpus", ROOT / "tests" / "_real_corpus.py"
    )
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


def run(argv: list[str]) -> tuple[int, float, str | None, dict[str, list[float]]]:
    """Exit code, process CPU seconds, the law and each parameter's posterior mean and
    sd of ``bayestribo fit ARGV --json`` (and ``"converged"``: the sampler's verdict,
    under the key ``"_converged"``)."""
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
    law, means = None, {}
    with contextlib.suppress(ValueError, KeyError, TypeError, AttributeError):
        out = json.loads(stdout.getvalue())
        law = out["law"]
        means = {
            name: [float(p["mean"]), float(p["sd"])]
            for name, p in (out.get("parameters") or {}).items()
            if p.get("sampled") and p.get("mean") is not None and p.get("sd") is not None
        }
        means["_converged"] = bool(out["diagnostics"]["converged"])
    return int(code or 0), seconds, law, means


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--external", type=Path, default=EXTERNAL)
    parser.add_argument("--only", nargs="*", help="recordings to fit (default: all)")
    parser.add_argument(
        "--output",
        help="results/OUTPUT.json (default auto_ratio, every_law with --every-law, and "
        "NEW_compare with --compare)",
    )
    parser.add_argument(
        "--every-law",
        action="store_true",
        help="time every candidate law alone against the default fit instead of auto "
        "(issue 42's second goal: each within 3x, converged)",
    )
    parser.add_argument(
        "--laws",
        nargs="*",
        help="with --every-law: these candidate laws only (default: every one)",
    )
    parser.add_argument(
        "--compare",
        nargs=2,
        type=Path,
        metavar=("NEW", "OLD"),
        help="compare two result files (no fitting): writes --output",
    )
    args = parser.parse_args(argv)
    if args.compare:
        return compare(*args.compare, args.output or f"{args.compare[0].stem}_compare")
    cmds, absent = commands(args.external)
    if args.only:
        cmds = {k: v for k, v in cmds.items() if k in args.only}
    load_start = os.getloadavg()
    if args.every_law:
        return every_law(
            cmds, args.seeds, args.output or "every_law", load_start, only_laws=args.laws
        )
    for name, cmd in cmds.items():  # warm: every kernel compiled or loaded
        run([*cmd, "--seed", "99"])
        run([*cmd, "--seed", "99", "--law", "auto"])
        print(f"warm {name}", flush=True)
    fits: dict[str, list[dict[str, Any]]] = {name: [] for name in cmds}
    for seed in args.seeds:
        for name, cmd in cmds.items():
            d_code, d_cpu, d_law, _ = run([*cmd, "--seed", str(seed)])
            a_code, a_cpu, a_law, a_means = run([*cmd, "--seed", str(seed), "--law", "auto"])
            a_means.pop("_converged", None)
            row = {
                "seed": seed,
                "default_exit": d_code,
                "default_cpu_seconds": d_cpu,
                "default_law": d_law,
                "auto_exit": a_code,
                "auto_cpu_seconds": a_cpu,
                "auto_law": a_law,
                "auto_posterior": a_means,
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
    import bayestribo

    package = Path(bayestribo.__file__).resolve().parents[1]
    path = write_results(
        args.output or "auto_ratio",
        {
            **provenance(
                "bayestribo.cli.main", {"seeds": args.seeds, "only": args.only}, load_start
            ),
            "package": str(package),
            "package_commit": commit(package, short=True),
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


def every_law(
    cmds: dict[str, list[str]],
    seeds: list[int],
    output: str,
    load_start: tuple,
    only_laws: list[str] | None = None,
) -> int:
    """Every candidate law alone (``--law NAME``) against the default fit, per
    recording and seed: CPU, exit code, converged, the ratio to the default fit and the
    posterior mean and sd of each sampled parameter (``only_laws``: these laws)."""
    import bayestribo
    from bayestribo.model.laws.candidates import candidate_laws

    unknown = sorted(set(only_laws or ()) - set(candidate_laws()))
    if unknown:
        raise SystemExit(
            f"--laws: {unknown} are not candidate laws; expected some of {list(candidate_laws())}"
        )
    laws = [law for law in candidate_laws() if not only_laws or law in only_laws]
    for name, cmd in cmds.items():  # warm: every law's kernels loaded (auto optimises all)
        run([*cmd, "--seed", "99"])
        run([*cmd, "--seed", "99", "--law", "auto"])
        print(f"warm {name}", flush=True)
    rows: dict[str, list[dict[str, Any]]] = {name: [] for name in cmds}
    for seed in seeds:
        for name, cmd in cmds.items():
            _, d_cpu, _, _ = run([*cmd, "--seed", str(seed)])
            for law in laws:
                code, cpu, _, means = run([*cmd, "--seed", str(seed), "--law", law])
                converged = means.pop("_converged", None)
                rows[name].append(
                    {
                        "seed": seed,
                        "law": law,
                        "cpu_seconds": cpu,
                        "default_cpu_seconds": d_cpu,
                        "ratio": cpu / d_cpu,
                        "exit": code,
                        "converged": converged,
                        "posterior": means,
                    }
                )
                print(
                    f"{name:<28} seed {seed} {law:<28} {cpu:6.2f} s  {cpu / d_cpu:5.1f}x "
                    f"(default {d_cpu:.2f} s) exit {code} converged {converged}",
                    flush=True,
                )
    summary = {}
    for name, fits in rows.items():
        # each law by its median ratio over the seeds: one fit slowed by the process
        # (a collection of its garbage, a kernel loaded) is not the law's cost
        median = {
            law: statistics.median(r["ratio"] for r in fits if r["law"] == law) for law in laws
        }
        over = sorted(law for law, ratio in median.items() if ratio > 3.0)
        unconverged = sorted({r["law"] for r in fits if r["converged"] is False})
        worst = max(median, key=median.__getitem__)
        summary[name] = {
            "worst_ratio": median[worst],
            "worst_law": worst,
            "over_3x": over,
            "not_converged": unconverged,
            "median_ratio": median,
        }
        print(
            f"{name:<28} worst {summary[name]['worst_ratio']:5.1f}x "
            f"({summary[name]['worst_law']}); over 3x: {over}; not converged: {unconverged}"
        )
    package = Path(bayestribo.__file__).resolve().parents[1]
    path = write_results(
        output,
        {
            **provenance("bayestribo.cli.main", {"seeds": seeds, "every_law": True}, load_start),
            "package": str(package),
            "package_commit": commit(package, short=True),
            "commands": cmds,
            "laws": list(laws),
            "summary": summary,
            "fits": rows,
        },
    )
    print(f"wrote {path}")
    return 0


def compare(new_path: Path, old_path: Path, output: str) -> int:
    """Two result files side by side: per recording the median ratio and CPU of each,
    the laws, and the largest shift of ``auto``'s posterior means (in the larger
    posterior sd, per seed the same law in both)."""
    new, old = (json.loads(Path(p).read_text()) for p in (new_path, old_path))
    if "laws" in new and "laws" in old:
        return _compare_every_law(new, old, new_path, old_path, output)
    rows: dict[str, Any] = {}
    for name, fits in new["fits"].items():
        before = {r["seed"]: r for r in old["fits"].get(name, [])}
        pairs = [(r, before[r["seed"]]) for r in fits if r["seed"] in before]
        if not pairs:
            continue
        same = all(a["auto_law"] == b["auto_law"] for a, b in pairs)
        worst = _largest_shift(
            [(a, b) for a, b in pairs if a["auto_law"] == b["auto_law"]], "auto_posterior"
        )
        worst = worst if worst[0] is not None else (0.0, None)
        rows[name] = {
            "new_ratio": statistics.median(a["ratio"] for a, _ in pairs),
            "old_ratio": statistics.median(b["ratio"] for _, b in pairs),
            "new_auto_cpu": statistics.median(a["auto_cpu_seconds"] for a, _ in pairs),
            "old_auto_cpu": statistics.median(b["auto_cpu_seconds"] for _, b in pairs),
            "new_default_cpu": statistics.median(a["default_cpu_seconds"] for a, _ in pairs),
            "old_default_cpu": statistics.median(b["default_cpu_seconds"] for _, b in pairs),
            "same_laws": same,
            "laws": sorted({str(a["auto_law"]) for a, _ in pairs}),
            "largest_shift_sd": worst[0],
            "largest_shift_of": worst[1],
            "seeds": [a["seed"] for a, _ in pairs],
        }
        r = rows[name]
        print(
            f"{name:<28} ratio {r['old_ratio']:5.1f}x -> {r['new_ratio']:5.1f}x  "
            f"auto {r['old_auto_cpu']:5.2f} -> {r['new_auto_cpu']:5.2f} s  "
            f"default {r['old_default_cpu']:4.2f} -> {r['new_default_cpu']:4.2f} s  "
            f"{'same' if same else 'DIFFERENT'} laws {r['laws']}  "
            f"shift {r['largest_shift_sd']:.2f} sd ({r['largest_shift_of']})"
        )
    return _write_comparison(new, old, new_path, old_path, rows, output)


def _compare_every_law(
    new: dict[str, Any], old: dict[str, Any], new_path: Path, old_path: Path, output: str
) -> int:
    """Two ``--every-law`` files side by side: per recording and law, the median CPU
    and ratio of each, the fits converged, and the largest shift of a posterior mean
    between the same seeds (in the larger posterior sd)."""
    rows: dict[str, Any] = {}
    for name, fits in new["fits"].items():
        before = {(r["seed"], r["law"]): r for r in old["fits"].get(name, [])}
        for law in sorted({r["law"] for r in fits}):
            pairs = [(r, before.get((r["seed"], law))) for r in fits if r["law"] == law]
            pairs = [(a, b) for a, b in pairs if b is not None]
            if not pairs:
                continue
            worst = _largest_shift(pairs, "posterior")
            key = f"{name} | {law}"
            rows[key] = {
                "new_cpu": statistics.median(a["cpu_seconds"] for a, _ in pairs),
                "old_cpu": statistics.median(b["cpu_seconds"] for _, b in pairs),
                "new_ratio": statistics.median(a["ratio"] for a, _ in pairs),
                "old_ratio": statistics.median(b["ratio"] for _, b in pairs),
                "new_converged": [a["converged"] for a, _ in pairs],
                "old_converged": [b["converged"] for _, b in pairs],
                "largest_shift_sd": worst[0],
                "largest_shift_of": worst[1],
                "seeds": [a["seed"] for a, _ in pairs],
            }
            r = rows[key]
            shift = "n/a" if r["largest_shift_sd"] is None else f"{r['largest_shift_sd']:.2f} sd"
            print(
                f"{key:<50} {r['old_cpu']:6.2f} -> {r['new_cpu']:6.2f} s  "
                f"{r['old_ratio']:5.1f}x -> {r['new_ratio']:5.1f}x  converged "
                f"{r['old_converged']} -> {r['new_converged']}  shift {shift} "
                f"({r['largest_shift_of']})"
            )
    return _write_comparison(new, old, new_path, old_path, rows, output)


def _largest_shift(pairs: list[tuple[dict, dict]], key: str) -> tuple[float | None, str | None]:
    """The largest difference of a posterior mean (rows' ``key``: name -> [mean, sd])
    between the two fits of each pair, in the larger of their sds, and its parameter;
    (None, None) where no parameter is in both."""
    shifts = []
    for a, b in pairs:
        for q, (mean, sd) in (a.get(key) or {}).items():
            if q in (b.get(key) or {}):
                mean_b, sd_b = b[key][q]
                if max(sd, sd_b) > 0:
                    shifts.append((abs(mean - mean_b) / max(sd, sd_b), q))
    return max(shifts) if shifts else (None, None)


def _write_comparison(
    new: dict[str, Any],
    old: dict[str, Any],
    new_path: Path,
    old_path: Path,
    rows: dict[str, Any],
    output: str,
) -> int:
    """The comparison's rows written with the two files they compare."""
    path = write_results(
        output,
        {
            "new": {"file": str(new_path), "package_commit": new.get("package_commit")},
            "old": {"file": str(old_path), "package_commit": old.get("package_commit")},
            "rows": rows,
        },
    )
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
