"""Short free decays answered: records that stop or end within three oscillations.

Records (independent simulations, ``benchmarks/_chain.py``: solve_ivp half cycle by
half cycle on the paper's rig, ζ = 0.0236, 10 kHz, noise 10x the vibrometer's
resolution; run ``i`` draws its noise from ``[80, i]``):

* ``stop-0.5``, ``stop-0.8``: μ_k = 0.5 or 0.8 (the paper's high-friction loads): the
  pin sticks within two or three oscillations of the release, 0.1 s of rest after it;
* ``cut-2``: μ_k = 0.0294, the record ending in motion 3 periods after the release (2
  periods after the skipped one), as ``short_checks.py``'s ``cut-2``;
* ``end-2.1``: the same ending 2.1 periods after the release (4 turning points; a
  record of 2 periods holds 3, its fourth at its last sample, and is refused);
* ``seismometer-100``: ``benchmarks/seismometer.py``'s clean velocity alone (seed ``i +
  30``, so that seed 37 is run 7), cut 100 s after its start (ζ = 0.08, no contact).

Each is fitted by :func:`bayestribo.fit` with seed ``i`` and tallied as in
``coarse_placements.py``: refused (the message), covered (the 95 % intervals of every
parameter hold the truth), flagged (not covered, a MisfitWarning or one of its
subclasses said so), missed, silently wrong (|z| > 3.29 unflagged), and z's mean and sd.

``--prepared`` instead prepares every bundled run (``data/runs/*.csv``) and every
recording in ``/work/shared/external-data`` (read as ``real.py`` reads them) by
:func:`bayestribo.inference.preparation.prepare`, the default fit's, and records a
SHA-256 of each one's analysed window, Π increments and their variances (or its
refusal): two packages whose digests agree give the same default fits, seed for seed.

Run: ``python benchmarks/short_decay.py [--runs 20] [--cases stop-0.5 stop-0.8 cut-2]
[--output short_decay]`` or ``python benchmarks/short_decay.py --prepared --output
short_decay_prepared``; writes ``benchmarks/results/<output>.json``. The package is
the one on ``PYTHONPATH`` (its directory and commit are recorded).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _chain import F_HZ, MU_K, ZETA, apply_chain, metadata, record  # noqa: E402
from _machine import commit, write_results  # noqa: E402
from _outcome import against_truth, flags_of  # noqa: E402
from coarse_placements import FLAGS, summarise  # noqa: E402


def _paper(mu_k: float, duration: float | None) -> Callable[[int], Any]:
    def make(index: int) -> Any:
        from bayestribo.io.run import Run

        t, x, v = record(10_000.0, 0.1, 0.1, mu_k=mu_k, duration=duration)
        xs, vs = apply_chain(t, x, v, 10_000.0, seed=[80, index], noise=10.0)
        return Run(time=t, displacement=xs, velocity=vs, metadata=metadata())

    return make


def _seismometer(cut_s: float) -> Callable[[int], Any]:
    def make(index: int) -> Any:
        from seismometer import record as seismo_record

        from bayestribo.io.run import Run

        t, v = seismo_record(index + 30)
        keep = t < cut_s
        return Run(time=t[keep], velocity=v[keep], metadata={"length_unit": "arbitrary"})

    return make


#: name: (record of run i, the truth of the fitted parameters)
CASES: dict[str, tuple[Callable[[int], Any], dict[str, float]]] = {
    "stop-0.5": (_paper(0.5, None), {"zeta": ZETA, "mu_k": 0.5}),
    "stop-0.8": (_paper(0.8, None), {"zeta": ZETA, "mu_k": 0.8}),
    "cut-2": (_paper(MU_K, 3.0 / F_HZ), {"zeta": ZETA, "mu_k": MU_K}),
    "end-2.1": (_paper(MU_K, 2.1 / F_HZ), {"zeta": ZETA, "mu_k": MU_K}),
    "seismometer-100": (_seismometer(100.0), {"zeta": 0.08}),
}


def one_run(case: str, index: int) -> dict[str, Any]:
    """Simulate and fit run ``index`` of ``case``; the refusal or each parameter's z."""
    from bayestribo import fit

    make, truth = CASES[case]
    run = make(index)
    out: dict[str, Any] = {"case": case, "index": index}
    start = time.process_time()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(run, seed=index)
    except Exception as exc:  # recorded, never silently dropped
        out["refused"] = f"{type(exc).__name__}: {exc}"
        return out
    out["cpu_s"] = time.process_time() - start
    out["flags"] = flags_of(caught, FLAGS)
    out.update(against_truth(result, truth))
    return out


def prepared_digests() -> dict[str, str]:
    """File name -> SHA-256 of its prepared data (or ``refused: <message>``)."""
    import hashlib

    from real import load, recordings

    from bayestribo.inference.preparation import prepare

    files: dict[str, Callable[[], Any]] = {
        path.name: (lambda path=path: path)
        for path in sorted((HERE.parent / "data" / "runs").glob("*.csv"))
    }
    # the external recordings read as benchmarks/real.py reads them
    files.update({name: (lambda name=name: load(name)[0]) for name in recordings()})
    out: dict[str, str] = {}
    for name, run in files.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                p = prepare(run())
        except Exception as exc:  # recorded, never silently dropped
            out[name] = f"refused: {type(exc).__name__}: {exc}"
            continue
        h = hashlib.sha256()
        d = p.decay
        h.update(np.array([d.start_time, d.end_time, len(d.peaks)], dtype=float).tobytes())
        for field in ("tau", "energy", "pi"):
            h.update(np.ascontiguousarray(getattr(d, field), dtype=float).tobytes())
        for value in vars(p.data).values():
            if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                h.update(np.ascontiguousarray(value).tobytes())
        out[name] = h.hexdigest()
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--cases", nargs="+", choices=sorted(CASES), default=sorted(CASES))
    parser.add_argument("--output", default="short_decay", help="results/NAME.json")
    parser.add_argument(
        "--prepared", action="store_true", help="digests of the bundled runs' prepared data"
    )
    args = parser.parse_args(argv)
    import bayestribo

    package = Path(bayestribo.__file__).resolve().parent.parent
    results: dict[str, Any] = {
        "source": commit(),
        "package": str(package),
        "package_commit": commit(package),
        "cases": {},
    }
    if args.prepared:
        results["prepared"] = prepared_digests()
        print(results["prepared"])
        print(f"wrote {write_results(args.output, results)}")
        return 0
    for case in args.cases:
        rows = [one_run(case, i) for i in range(args.runs)]
        for r in rows:
            print(r, flush=True)
        table = summarise(rows, CASES[case][1])
        print(case, table, flush=True)
        results["cases"][case] = {"truth": CASES[case][1], "table": table, "runs": rows}
    print(f"wrote {write_results(args.output, results)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
