"""How far a fit's answer moves with the seed of its increments' noise Monte Carlo.

Where one channel is derived from the other, the increments' variances come from a
Monte Carlo of the recorded channel's noise (300 replicates,
:func:`bayestribo.signal.increments.increment_draws`), seeded by the record's analysed
signals (:func:`bayestribo.inference.preparation.data_seed`, a CRC of their bytes).
A change in the last digits of those signals (a law fitted in the frame of its own
turning times is prepared again at the frequency it finds) draws other numbers. This
script fits one recording by the command a user gives (``benchmarks/auto_ratio.py``'s
list) with the seed replaced by ``data_seed XOR k·0x9E3779B1`` for k = 0..K-1 (k = 0:
the package's own), everything else alike, and reports each parameter's posterior mean
per k and their spread in units of the posterior sd: the part of an answer that is the
Monte Carlo's, which the posterior's own sd does not hold.

Run (by hand)::

    BAYESTRIBO_REAL_CORPUS=/path/to/corpus PYTHONPATH=. python benchmarks/mc_seed_spread.py \\
        --recording rotary-pendulum-90deg --law power --seeds 6

Writes ``benchmarks/results/mc_seed_spread.json`` (``--output NAME``), one entry per
recording and law run (results of earlier runs in the file are kept).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import RESULTS, commit, write_results  # noqa: E402
from auto_ratio import EXTERNAL, commands, run  # noqa: E402

#: Multiplier of k in the seed's change (the golden ratio's 32-bit hash constant).
SPREAD = 0x9E3779B1


def fit_with_seed(argv: list[str], k: int) -> dict[str, Any]:
    """``bayestribo fit ARGV --json`` with the noise Monte Carlo's seed changed by k."""
    import bayestribo.inference.preparation as preparation
    import bayestribo.inference.restoring_error as restoring_error

    original = preparation.data_seed

    def seeded(decay: Any) -> int:
        return original(decay) ^ ((k * SPREAD) & 0xFFFFFFFF)

    try:
        preparation.data_seed = restoring_error.data_seed = seeded
        code, seconds, law, posterior = run(argv)
    finally:
        preparation.data_seed = restoring_error.data_seed = original
    posterior.pop("_converged", None)
    return {"k": k, "exit": code, "cpu_seconds": seconds, "law": law, "posterior": posterior}


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recording", required=True, help="a name of auto_ratio.py's list")
    parser.add_argument("--law", default=None, help="--law given to the fit (default: none)")
    parser.add_argument("--seeds", type=int, default=6, help="Monte Carlo seeds K")
    parser.add_argument("--fit-seed", type=int, default=1, help="the fit's own --seed")
    parser.add_argument("--external", type=Path, default=EXTERNAL)
    parser.add_argument("--output", default="mc_seed_spread")
    args = parser.parse_args(argv)
    cmds, _ = commands(args.external)
    if args.recording not in cmds:
        parser.error(f"--recording: expected one of {sorted(cmds)}, got {args.recording!r}")
    cmd = [*cmds[args.recording], "--seed", str(args.fit_seed)]
    if args.law:
        cmd += ["--law", args.law]
    fits = []
    for k in range(args.seeds):
        fits.append(fit_with_seed(cmd, k))
        print(k, fits[-1]["law"], fits[-1]["exit"], fits[-1]["posterior"], flush=True)
    spread = {}
    for name in fits[0]["posterior"]:
        means = [f["posterior"][name][0] for f in fits if name in f["posterior"]]
        sds = [f["posterior"][name][1] for f in fits if name in f["posterior"]]
        sd = statistics.median(sds)
        spread[name] = {
            "sd_of_means_in_posterior_sd": statistics.stdev(means) / sd if sd > 0 else None,
            "range_in_posterior_sd": (max(means) - min(means)) / sd if sd > 0 else None,
            "posterior_sd_median": sd,
        }
        print(f"{name}: means spread {spread[name]['sd_of_means_in_posterior_sd']:.2f} sd")
    import bayestribo

    package = Path(bayestribo.__file__).resolve().parents[1]
    path = RESULTS / f"{args.output}.json"
    runs = json.loads(path.read_text())["runs"] if path.exists() else {}
    key = f"{args.recording} {args.law or 'default'}"
    runs[key] = {
        "command": cmd,
        "package_commit": commit(package, short=True),
        "load_average": list(os.getloadavg()),
        "fits": fits,
        "spread": spread,
    }
    write_results(args.output, {"runs": runs})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
