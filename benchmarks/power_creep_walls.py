"""Where HarmOsc3's `power` posterior lies: thin bands between rows the law cannot compute.

A power-law drag below α = 1 ends its motion by an overdamped creep to rest, whose ∫E
the integrator takes from the quasi-static balance (within a factor 2) only where it
is below 1e-8 of Π(0) (``_CREEP_SHARE`` in ``bayestribo/model/laws/_core.py``); a row
with a larger creep is outside the law's domain (NaN). On HarmOsc3, a record of
Coulomb friction that the drag misfits, the density rises across those rows: the
posterior is a set of thin bands between them.

One fit of ``power`` on HarmOsc3 (seed 1, after a warm-up fit on the bundled run),
recording where the sampler started (the optimiser's optimum, the Laplace sd), the
fit's draws (mean, sd, best log density), and the exact posterior at the best draw of
the first quadratic surrogate checked against it (seeded), refined by the least
squares. Along the segments between these points the log density is evaluated at 401
points: which rows are finite, and the density at both ends. Also the fit's CPU time
over the default fit's, and whether it is reported converged (and why not).

``--creep-share X`` runs the same in a copy of the package whose creep rule accepts
a creep up to X of Π(0) (a temporary folder, its own law cache): what the rule
decides. Since branch ``creep-pi`` the package integrates the creep
(``bayestribo/model/laws/_creep.py``) and has no such rule: ``--creep-share`` then
needs ``PYTHONPATH`` at a tree before it (main at 6827d02), whose package is copied.

Run (a few minutes)::

    python benchmarks/power_creep_walls.py --output every_law_speed7_h3_power_walls
    python benchmarks/power_creep_walls.py --creep-share 0.1 \\
        --output every_law_speed7_h3_power_walls_share01
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import commit, write_results

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"


def _scan(posterior: Any, a: np.ndarray, b: np.ndarray, n: int = 401) -> dict[str, Any]:
    t = np.linspace(0.0, 1.0, n)
    lp = np.asarray(posterior(a[None] + t[:, None] * (b - a)[None]), dtype=float)
    finite = np.isfinite(lp)
    bands = int(np.sum(np.diff(finite.astype(int)) == 1) + int(finite[0]))
    return {
        "finite_fraction": float(finite.mean()),
        "finite_bands": bands,
        "pattern_every_4th": "".join("1" if f else "0" for f in finite[::4]),
        "log_density_ends": [float(lp[0]), float(lp[-1])],
        "log_density_best": float(np.max(lp[finite])) if finite.any() else None,
    }


def measure(seed: int) -> dict[str, Any]:
    import real

    import bayestribo
    import bayestribo.inference.law_frame as law_frame
    from bayestribo import fit, read_run
    from bayestribo.inference.chains import _first_surrogate
    from bayestribo.inference.sampling import run_ensembles
    from bayestribo.inference.start import initial_walkers, refine
    from bayestribo.inference.surrogate import check
    from bayestribo.inference.types import DEFAULT_SETTINGS

    name = next(n for n in real.recordings() if "HarmOsc3" in n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = real.load(name)[0]
        bundled = read_run(BUNDLED)
        fit(bundled, law="viscous+coulomb", seed=seed)
        fit(bundled, law="power", seed=seed)
    starts: list[Any] = []
    sample_from = law_frame.sample_from

    def recorded(start: Any, **kwargs: Any) -> Any:
        starts.append(start)
        return sample_from(start, **kwargs)

    law_frame.sample_from = recorded
    cpu = {}
    results = {}
    for law in ("viscous+coulomb", "power"):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t = time.process_time()
            results[law] = fit(run, law=law, seed=seed)
            cpu[law] = time.process_time() - t
        cpu[law + "_warnings"] = sorted({w.category.__name__ for w in caught})
    law_frame.sample_from = sample_from
    result = results["power"]
    start = starts[-1]
    posterior = start.posterior
    names = list(posterior.names)
    draws = np.column_stack([result.samples(n) for n in names])
    mean = draws.mean(axis=0)
    # the first surrogate's draws, checked against the exact posterior (seeded)
    rng = np.random.default_rng(seed)
    first = _first_surrogate(posterior, start.theta, start.cov)
    best = refined = None
    if first is not None:
        walkers = initial_walkers(
            first,
            start.theta,
            start.cov,
            start.ratio_range,
            DEFAULT_SETTINGS.n_ensembles,
            DEFAULT_SETTINGS.n_walkers,
            rng,
        )
        surrogate_run = run_ensembles(first, walkers, DEFAULT_SETTINGS, seed=seed)
        checked = check(posterior, first, surrogate_run.chains.reshape(-1, len(names)), rng)
        best = checked.best
        if best is not None:
            refined, _ = refine(posterior, best)

    def point(theta: np.ndarray | None) -> dict[str, Any] | None:
        if theta is None:
            return None
        lp = float(posterior(np.asarray(theta, dtype=float)[None])[0])
        return {"values": dict(zip(names, map(float, theta), strict=True)), "log_density": lp}

    diag = result.diagnostics
    out: dict[str, Any] = {
        "package_tree": str(Path(bayestribo.__file__).resolve().parents[1]),
        "package_commit": commit(Path(bayestribo.__file__).resolve().parents[1]),
        "seed": seed,
        "recording": name,
        "cpu_s": {k: v for k, v in cpu.items() if not k.endswith("_warnings")},
        "power_over_default": cpu["power"] / cpu["viscous+coulomb"],
        "warnings": {k: v for k, v in cpu.items() if k.endswith("_warnings")},
        "converged": bool(result.converged),
        "reasons": list(diag.get("reasons", [])),
        "n_steps": int(diag.get("n_steps", 0)),
        "ess_min": float(diag.get("ess_min", float("nan"))),
        "surrogate": diag.get("surrogate"),
        "names": names,
        "start": point(start.theta),
        "laplace_sd": dict(zip(names, map(float, np.sqrt(np.diag(start.cov))), strict=True)),
        "draws_mean": point(mean),
        "draws_sd": dict(zip(names, map(float, draws.std(axis=0)), strict=True)),
        "first_surrogate_best_checked": point(best),
        "refined_from_it": point(refined),
        "segments": {
            "start_to_draws_mean": _scan(posterior, start.theta, mean),
        },
    }
    if refined is not None:
        out["segments"]["draws_mean_to_refined"] = _scan(posterior, mean, refined)
        out["refined_minus_draws_mean_in_draws_sd"] = dict(
            zip(names, map(float, (refined - mean) / draws.std(axis=0)), strict=True)
        )
    return out


def _in_copy(share: float, argv: list[str]) -> None:
    """Run this script on a copy of the package whose creep rule is ``share``."""
    folder = Path(tempfile.mkdtemp(prefix="creep_share_"))
    try:
        import bayestribo  # the package imported: PYTHONPATH's tree

        shutil.copytree(Path(bayestribo.__file__).parent, folder / "bayestribo")
        core = folder / "bayestribo" / "model" / "laws" / "_core.py"
        text, n = re.subn(
            r"^_CREEP_SHARE = .*$", f"_CREEP_SHARE = {share!r}", core.read_text(), flags=re.M
        )
        if n != 1:
            raise SystemExit("_CREEP_SHARE not found once in _core.py")
        core.write_text(text)
        env = dict(os.environ, PYTHONPATH=str(folder), BAYESTRIBO_CACHE_DIR=str(folder / "cache"))
        subprocess.run(
            [sys.executable, __file__, *argv, "--in-copy", str(share)], env=env, check=True
        )
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default="every_law_speed7_h3_power_walls")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--creep-share", type=float, default=None)
    parser.add_argument("--in-copy", type=float, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.creep_share is not None and args.in_copy is None:
        _in_copy(args.creep_share, ["--output", args.output, "--seed", str(args.seed)])
        return
    out = measure(args.seed)
    out["creep_share"] = args.in_copy if args.in_copy is not None else 1e-8
    if args.in_copy is not None:
        out["copied_from_commit"] = commit(ROOT)
    out["load_average"] = os.getloadavg()
    write_results(args.output, out)
    print({k: out[k] for k in ("power_over_default", "converged", "reasons", "draws_mean")})


if __name__ == "__main__":
    main()
