"""The adequacy checks on short records: which checks run, which cannot, and why.

Records (independent simulations, nothing from the package):

* ``coarse3-<i>``: the 3-step placements of ``benchmarks/coarse_placements.py`` (both
  channels rounded to a third of their swing on levels placed at random, placement
  ``i``), analysed on two oscillations by the fit (``signal.coarse.coarse_window``);
* ``cut-<n>``: the paper's rig (``benchmarks/_chain.py``) recorded for ``n + 1``
  periods after the release (the first skipped), ending in motion, noise 10x the
  vibrometer's resolution;
* ``stop-<mu>``: the paper's rig with μ_k = ``mu``, sticking within a few oscillations;
* ``seismometer-<seed>``: the seismometer's velocity alone fading after about ten half
  cycles (``benchmarks/seismometer.py``, the clean case, seeds 0-9); ``seismometer-cut<T>``:
  seed 0 cut ``T`` seconds after the record's start, in motion (released at 10 s, 15 s
  period);
* ``paper-velocity-<seed>``: the paper's rig's velocity alone (the package's simulator),
  long enough for every check.

Each is checked by :func:`bayestribo.adequacy.check_adequacy` (the command ``bayestribo
check``): refused (the message) or each check's outcome (passed, failed, not run with
its statement), the verdict and whether it calls the law adequate; ``--fit`` also fits
it (:func:`bayestribo.fit`) and ``--auto`` compares the laws (``law="auto"``), each
refused or answered with its warnings.

``--level`` instead measures the constancy test on windows of one oscillation (the
default window of a decay of 3-6 oscillations with a recorded displacement) on records
of the law (:data:`LEVEL_CASES`: ``cut-4`` to ``cut-6`` with both channels and with the
displacement alone, the seismometer's velocity alone cut at 85-115 s, and at 130 and
160 s on windows of two): how often it rejects at α/3 (1.7 %) and at 5 %.

Run: ``python benchmarks/short_checks.py [--fit] [--auto] [--output short_checks]`` or
``python benchmarks/short_checks.py --level --output short_checks_level``; writes
``benchmarks/results/<output>.json``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _chain import F_HZ, apply_chain, metadata, record  # noqa: E402
from _machine import commit, write_results  # noqa: E402


def coarse3(index: int) -> Any:
    """Placement ``index`` of ``coarse_placements.py --steps 3`` as a Run."""
    from bayestribo.io.run import Run

    t, x, v = record(10_000.0, 0.1, 0.1)
    rng = np.random.default_rng([77, index])
    xs, vs = apply_chain(t, x, v, 10_000.0, seed=[77, index, 1], noise=10.0)
    ux, uv = rng.uniform(-0.5, 0.5, 2)
    qx, qv = np.ptp(x) / 3.0, np.ptp(v) / 3.0
    xs = (np.round(xs / qx + ux) - ux) * qx
    vs = (np.round(vs / qv + uv) - uv) * qv
    return Run(time=t, displacement=xs, velocity=vs, metadata=metadata())


def cut(oscillations: int, seed: int = 0) -> Any:
    """The paper's rig recorded for ``oscillations + 1`` periods, ending in motion."""
    from bayestribo.io.run import Run

    t, x, v = record(10_000.0, 0.1, 0.0, duration=(oscillations + 1.0) / F_HZ)
    xs, vs = apply_chain(t, x, v, 10_000.0, seed=[78, seed], noise=10.0)
    return Run(time=t, displacement=xs, velocity=vs, metadata=metadata())


def stop(mu_k: float, seed: int = 0) -> Any:
    """The paper's rig with friction ``mu_k``, sticking after a few oscillations."""
    from bayestribo.io.run import Run

    t, x, v = record(10_000.0, 0.1, 0.1, mu_k=mu_k)
    xs, vs = apply_chain(t, x, v, 10_000.0, seed=[79, seed], noise=10.0)
    return Run(time=t, displacement=xs, velocity=vs, metadata=metadata())


def seismometer(seed: int, duration_s: float | None = None) -> Any:
    """The seismometer's clean velocity alone (``benchmarks/seismometer.py``), cut
    ``duration_s`` after its start (in motion) if given."""
    from seismometer import record as seismo_record

    from bayestribo.io.run import Run

    t, v = seismo_record(seed)
    keep = t < (duration_s if duration_s is not None else np.inf)
    return Run(time=t[keep], velocity=v[keep], metadata={"length_unit": "arbitrary"})


def paper_velocity(seed: int) -> Any:
    """The paper's rig's velocity alone, :func:`bayestribo.synthetic.recording.simulate`
    with ``seed`` (a record of the law long enough for every check)."""
    from bayestribo.io.run import Run
    from bayestribo.synthetic.recording import simulate

    run = simulate(seed=seed)
    return Run(time=run.time, velocity=run.velocity, metadata=dict(run.metadata))


CASES: dict[str, Callable[[], Any]] = {
    **{f"coarse3-{i}": (lambda i=i: coarse3(i)) for i in range(20)},
    **{f"cut-{n}": (lambda n=n: cut(n)) for n in (2, 3, 4)},
    **{f"stop-{mu:g}": (lambda mu=mu: stop(mu)) for mu in (0.3, 0.5, 0.8)},
    **{f"seismometer-{s}": (lambda s=s: seismometer(s)) for s in range(10)},
    **{f"paper-velocity-{s}": (lambda s=s: paper_velocity(s)) for s in range(10)},
    **{f"seismometer-cut{d:g}": (lambda d=d: seismometer(0, d)) for d in (65.0, 85.0, 115.0)},
}


def _caught(call: Callable[[], Any]) -> tuple[Any, list[str], str | None]:
    """``call()``'s value, the package's warning classes it raised, and the refusal."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            value = call()
        except Exception as exc:  # recorded, never silently dropped
            return None, [], f"{type(exc).__name__}: {exc}"
    names = sorted({w.category.__name__ for w in caught if "bayestribo" in w.category.__module__})
    return value, names, None


def one_case(name: str, *, with_fit: bool, with_auto: bool) -> dict[str, Any]:
    """Check (and fit) one record; what ran, what did not, and the verdicts."""
    from bayestribo import fit
    from bayestribo.adequacy import check_adequacy

    run = CASES[name]()
    out: dict[str, Any] = {"case": name}
    report, _, refused = _caught(lambda: check_adequacy(run))
    if refused is not None:
        out["check_refused"] = refused
    else:
        out["checks"] = {c["key"]: c["passed"] for c in report.checks}
        out["statements"] = {c["key"]: c["statement"] for c in report.checks if c["passed"] is None}
        out["adequate"] = report.adequate
        out["verdict"] = report.verdict
    if with_fit:
        _, flags, refused = _caught(lambda: fit(run, seed=0))
        out["fit"] = {"refused": refused} if refused else {"warnings": flags}
    if with_auto:
        result, flags, refused = _caught(lambda: fit(run, law="auto", seed=0))
        if refused:
            out["auto"] = {"refused": refused}
        else:
            comparison = getattr(result, "law_comparison", None) or {}
            out["auto"] = {
                "warnings": flags,
                "verdict": comparison.get("verdict"),
                "adequate": comparison.get("adequate"),
                "halves": (comparison.get("halves") or {}).get("note"),
            }
    return out


def _displacement_only(run: Any) -> Any:
    from bayestribo.io.run import Run

    return Run(time=run.time, displacement=run.displacement, metadata=run.metadata)


#: The records of the law of ``--level``: name, record of a noise draw, window
#: [oscillations], draws.
LEVEL_CASES: tuple[tuple[str, Callable[[int], Any], int, int], ...] = (
    *((f"cut-{n}", lambda seed, n=n: cut(n, seed), 1, 200) for n in (4, 5, 6)),
    *(
        (f"cut-{n} displacement alone", lambda seed, n=n: _displacement_only(cut(n, seed)), 1, 100)
        for n in (4, 6)
    ),
    *(
        (f"seismometer-cut{d:g}", lambda seed, d=d: seismometer(seed, d), 1, 40)
        for d in (85.0, 100.0, 115.0)
    ),
    *(
        (f"seismometer-cut{d:g}", lambda seed, d=d: seismometer(seed, d), 2, 40)
        for d in (130.0, 160.0)
    ),
)


def constancy_level() -> dict[str, Any]:
    """The constancy test at α/3 over noise draws of records of the law
    (:data:`LEVEL_CASES`): p-values, rejections at α/3 and 5 %, and the draws the
    package refused (with the message)."""
    from bayestribo.adequacy import constancy_test, windowed_fits
    from bayestribo.adequacy.windows import analysed_decay

    out: dict[str, Any] = {}
    for name, make, window, draws in LEVEL_CASES:
        p_values, refused, counts = [], {}, set()
        for seed in range(draws):
            try:
                decay = analysed_decay(make(seed), skip_oscillations=1)
                windows = windowed_fits(decay, window=window, seed=seed)
                p_values.append(constancy_test(windows, alpha=0.05 / 3).p_value)
                counts.add(len(windows))
            except Exception as exc:  # recorded, never silently dropped
                refused[seed] = f"{type(exc).__name__}: {exc}"
        p = np.array(p_values)
        key = f"{name}, windows of {window}"
        out[key] = {
            "draws": draws,
            "tested": int(p.size),
            "windows": sorted(counts),
            "rejected_at_alpha_3": int(np.sum(p < 0.05 / 3)),
            "rejected_at_5pc": int(np.sum(p < 0.05)),
            "refused": refused,
            "p_values": p.tolist(),
        }
        print(key, {k: v for k, v in out[key].items() if k != "p_values"}, flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=sorted(CASES), choices=sorted(CASES))
    parser.add_argument("--fit", action="store_true", help="also fit each record")
    parser.add_argument("--auto", action="store_true", help="also compare the laws")
    parser.add_argument("--output", default=None, help="results/NAME.json")
    parser.add_argument(
        "--level", action="store_true", help="measure the constancy test's level instead"
    )
    args = parser.parse_args(argv)
    if args.level:
        table = constancy_level()
        if args.output:
            print("wrote", write_results(args.output, {"source": commit(), "level": table}))
        return 0
    rows = []
    for name in args.cases:
        rows.append(one_case(name, with_fit=args.fit, with_auto=args.auto))
        print(rows[-1], flush=True)
    if args.output:
        path = write_results(args.output, {"source": commit(), "rows": rows})
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
