"""How far the Monte Carlo of an accelerometer record's increment noise moves a fit.

The covariance of an integrated record's increments is estimated from Monte Carlo
draws of the sensor's noise (:mod:`bayestribo.signal.increment_correlation`), seeded
by the record's own bytes (:func:`bayestribo.inference.preparation.data_seed`): the
same record always gets the same draws, and a record changed by any amount gets
others. Here one dry-friction record of ``acceleration.py`` (the gain stated exact) is
fitted with the seed offset ``--draws`` times, everything else alike, and the spread
of the posterior means of ζ and μ_k is given in units of their posterior sd.

Run::

    python benchmarks/acceleration_mc_seed.py --records 2 25 27 38 44 --draws 8

writes ``benchmarks/results/acceleration_mc_seed.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _accel_sim as sim
import acceleration

RESULTS = Path(__file__).resolve().parent / "results"


def spread(record: int, draws: int) -> dict:
    """Posterior means and sds of ζ and μ_k over ``draws`` Monte Carlo seeds."""
    import bayestribo
    import bayestribo.inference.preparation as preparation

    rig, settings, _ = acceleration.draw("coulomb", record)
    x0 = settings.pop("x0")
    rec = sim.record(rig, x0, **settings)
    meta = {
        "load_N": rig.load,
        "mass_kg": rig.mass,
        "natural_frequency_Hz": rig.f_Hz,
        "gain_uncertainty": 0.0,
    }
    own_seed = preparation.data_seed
    rows = []
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = Path(tmp) / "accel.csv"
        rows_out = np.column_stack([rec["time"], rec["acceleration"]])
        np.savetxt(
            path, rows_out, delimiter=",", header="time_s,acceleration_m_per_s2", comments=""
        )
        (Path(tmp) / "accel.json").write_text(json.dumps(meta))
        run = bayestribo.read_run(path)
        try:
            for k in range(draws):
                preparation.data_seed = lambda d, k=k: (own_seed(d) + 7919 * k) % 2**32
                s = bayestribo.fit(run).summary()
                rows.append([s["zeta"].mean, s["zeta"].sd, s["mu_k"].mean, s["mu_k"].sd])
        finally:
            preparation.data_seed = own_seed
    a = np.array(rows)
    return {
        "record": record,
        "zeta_mean_spread_over_sd": float(a[:, 0].std(ddof=1) / a[:, 1].mean()),
        "zeta_sd_range_over_mean": [
            float(a[:, 1].min() / a[:, 1].mean()),
            float(a[:, 1].max() / a[:, 1].mean()),
        ],
        "mu_k_mean_spread_over_sd": float(a[:, 2].std(ddof=1) / a[:, 3].mean()),
        "fits": a.tolist(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, nargs="+", default=[2, 25, 27, 38, 44])
    parser.add_argument("--draws", type=int, default=8)
    args = parser.parse_args(argv)
    if args.draws < 2:
        parser.error(f"--draws: expected at least 2, got {args.draws}")
    out = [spread(r, args.draws) for r in args.records]
    for row in out:
        print({k: v for k, v in row.items() if k != "fits"}, flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "acceleration_mc_seed.json").write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
