"""A slow rig's short rests: the ``coulomb_both`` rig of ``unseen_rigs.py`` over seeds and rests.

Each record is ``unseen_rigs.py``'s own closed-form viscous + Coulomb simulation (not
the package's model): a 1 Hz spring, ζ = 0.01, μ_k = 0.02, μ_s = 0.04, friction
displacement 5 % of the 50 mm release, both channels at 1 kHz (σ_x = 50 µm, σ_v =
0.5 mm/s), held ``pre`` seconds at rest before the release and recorded ``post``
seconds past the stop. It is written as a CSV with its sidecar (load, mass,
frequency) and fitted with :func:`bayestribo.fit` (default law, ``seed=1``), as a user
would. With z = (posterior mean − truth) / posterior sd, each record is *refused* (an
exception, its message kept), *covered* (both 95 % intervals, ζ and μ_k, hold the
truth), *flagged* (not covered, and a ``MisfitWarning``, ``ConvergenceWarning``,
``PriorBoundWarning`` or ``ChannelCalibrationWarning`` said so), *missed* (not covered,
no such warning) or, among those, *silently wrong* (|z| > 3.29 for ζ or μ_k); a
warning counts as such when its class is one of them or derives from one
(``ShortAnalysisWarning`` is a ``MisfitWarning``), as in ``misspecification.py``.

Run: ``python benchmarks/short_rests.py [--seeds 25 53] [--rests 1:2 0.2:0.2 ...]
[--output short_rests] [--retable]`` with ``PYTHONPATH`` on the tree whose package is measured;
writes ``benchmarks/results/<output>.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import provenance, write_results
from unseen_rigs import rig

#: The rig of ``unseen_rigs.py``'s ``coulomb_both`` case (its rests set per record).
RIG = {
    "f": 1.0,
    "zeta": 0.01,
    "mu_k": 0.02,
    "N": 1.0,
    "m": 0.2,
    "x0": 0.05,
    "fs": 1000,
    "nx": 5e-5,
    "nv": 5e-4,
}
#: Rests before the release and after the stop [s]: the case's own (1 s, 2 s) first.
RESTS = ("1:2", "0.2:0.2", "0.2:2", "2:0.2", "1:1.2", "2:2", "0.5:0.5", "0.2:1", "1:0.5")
FLAGS = {"MisfitWarning", "ConvergenceWarning", "PriorBoundWarning", "ChannelCalibrationWarning"}
Z_SILENT = 3.29


def one(seed: int, pre: float, post: float, folder: Path) -> dict[str, Any]:
    """Write and fit one record; its outcome."""
    import bayestribo

    r = rig(seed, t_pre=pre, t_post=post, **RIG)
    path = folder / f"strong_friction_{seed}_{pre:g}_{post:g}.csv"
    rows = [f"{a:.3f},{b:.6e},{c:.6e}" for a, b, c in zip(r["t"], r["x"], r["v"], strict=True)]
    path.write_text("time_s,displacement_m,velocity_m_per_s\n" + "\n".join(rows) + "\n")
    path.with_suffix(".json").write_text(json.dumps(r["meta"]))
    out: dict[str, Any] = {"seed": seed, "pre_s": pre, "post_s": post}
    start = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = bayestribo.fit(path, seed=1)
        except Exception as exc:  # a refusal is an outcome
            out["refused"] = f"{type(exc).__name__}: {exc}"[:300]
            result = None
    out["warnings"] = sorted({type(w.message).__name__ for w in caught})
    out["fit_cpu_seconds"] = time.process_time() - start
    if result is None:
        return out
    summary = result.summary()
    out["converged"] = bool(result.converged)
    for name in ("zeta", "mu_k"):
        s = summary[name]
        truth = r["truth"][name]
        lo, hi = s.interval
        out[name] = {
            "mean": s.mean,
            "sd": s.sd,
            "interval": [lo, hi],
            "truth": truth,
            "z": (s.mean - truth) / s.sd,
            "covered": bool(lo <= truth <= hi),
        }
    return out


def flagged(names: list[str]) -> bool:
    """Whether any of the warnings ``names`` is one of :data:`FLAGS` or a subclass of one
    (a ``ShortAnalysisWarning`` is a ``MisfitWarning``: the command exits 1)."""
    import bayestribo.errors

    for name in names:
        kind = getattr(bayestribo.errors, name, None)
        if kind is not None and any(c.__name__ in FLAGS for c in kind.__mro__):
            return True
    return False


def classify(run: dict[str, Any]) -> str:
    """refused, covered, flagged, missed or silently_wrong."""
    if "refused" in run:
        return "refused"
    if run["zeta"]["covered"] and run["mu_k"]["covered"]:
        return "covered"
    if flagged(run["warnings"]):
        return "flagged"
    z = max(abs(run["zeta"]["z"]), abs(run["mu_k"]["z"]))
    return "silently_wrong" if z > Z_SILENT else "missed"


def table(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Per rest: the outcomes' counts, coverage of each parameter and its z's mean and sd."""
    out: dict[str, Any] = {}
    for key in dict.fromkeys(f"{r['pre_s']:g}:{r['post_s']:g}" for r in runs):
        rows = [r for r in runs if f"{r['pre_s']:g}:{r['post_s']:g}" == key]
        kinds = [classify(r) for r in rows]
        fitted = [r for r in rows if "refused" not in r]
        entry: dict[str, Any] = {"runs": len(rows)}
        for kind in ("refused", "covered", "flagged", "missed", "silently_wrong"):
            entry[kind] = kinds.count(kind)
        entry["warned"] = sum(flagged(r["warnings"]) for r in fitted)
        for name in ("zeta", "mu_k"):
            zs = [r[name]["z"] for r in fitted]
            n = len(zs)
            entry[f"{name}_covered"] = sum(r[name]["covered"] for r in fitted)
            if n > 1:
                mean = sum(zs) / n
                sd = math.sqrt(sum((z - mean) ** 2 for z in zs) / (n - 1))
                entry[f"{name}_z_mean"] = mean
                entry[f"{name}_z_sd"] = sd
        entry["refusals"] = sorted({r["refused"][:80] for r in rows if "refused" in r})
        out[key] = entry
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", nargs=2, type=int, default=[25, 53], help="first, past-last")
    parser.add_argument("--rests", nargs="+", default=list(RESTS), help="PRE:POST [s]")
    parser.add_argument("--output", default="short_rests", help="results/<output>.json")
    parser.add_argument(
        "--retable", action="store_true", help="summarise results/<output>.json's runs again"
    )
    args = parser.parse_args()
    if args.retable:
        path = Path(__file__).resolve().parent / "results" / f"{args.output}.json"
        stored = json.loads(path.read_text())
        stored["table"] = table(stored["runs"])
        path.write_text(json.dumps(stored, indent=2) + "\n")
        return
    import bayestribo

    load = os.getloadavg()
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for rest in args.rests:
            pre, post = (float(p) for p in rest.split(":"))
            for seed in range(*args.seeds):
                runs.append(one(seed, pre, post, Path(tmp)))
                print(json.dumps(runs[-1]), flush=True)
    settings = {
        "seeds": list(range(*args.seeds)),
        "rests_s": args.rests,
        "rig": RIG,
        "package": str(Path(bayestribo.__file__).resolve().parent),
    }
    results = {
        **provenance("bayestribo.fit", settings, load),
        "table": table(runs),
        "runs": runs,
    }
    print("wrote", write_results(args.output, results))


if __name__ == "__main__":
    main()
