"""A creep seen on one channel: false alarms and detections of ``signal/creep_shape.py``.

Every record is prepared (:func:`bayestribo.inference.prepare`, where the rest after the
stop is tested) and counted as *creeping* when a :class:`~bayestribo.errors.CreepWarning`
is raised. Nothing is fitted. Records:

* **bundled**: every run of ``data/runs/`` (and ``data/runs/oil/``), as recorded (both
  channels), with the displacement alone and with the velocity alone;
* **real**: every recording of ``../shared/external-data`` read as
  ``benchmarks/real.py`` reads it (``real.load``): the AppStat2020 positions alone,
  the spring and disc positions (with the software's velocity where the package
  accepts it), and the spring and disc positions alone;
* **drift**: one channel of the paper's rig (``_chain.py``: ``solve_ivp``, the contact
  sticks where its swings end, nothing from the package) at 10 kHz or 1 kHz, 0.1 s of
  rest before the release or none, 0.1-3 s of rest after the stop, four laws (ζ, μ_k),
  white noise 10x the vibrometer's resolution, and one of: an offset that drifts
  linearly (either direction, 1-300 times the white noise's sd over the record,
  log-uniform), an offset that wanders as a random walk (rms 1-30 times the white
  noise's sd, log-uniform), 1/f noise (``_chain.apply_chain``'s, rms 1-5 times), 50 Hz
  hum (1-5 times), a digitiser's steps (10-100 across the swing), or nothing; the
  effect runs over the whole record, the rest before the release included.
  ``--drift-records`` records (360), each once with its displacement alone and once
  with its velocity alone; records 0-179 were seen while the test's limits were set,
  180-359 were not (``summary["drift fresh/..."]`` counts those alone);
* **seismometer**: ``benchmarks/seismometer.py``'s velocity alone (a viscous decay that
  fades into the noise), clean and with its random-walk offset;
* **creep**: the 5 Hz Stribeck records of ``stribeck_verdict.py --rig creep``
  (``_creep_sim.py``: ``solve_ivp``, friction regularised as tanh(v/0.1 mm/s), the
  mass creeps towards the equilibrium after its last half cycle), strengths 0.3, 1, 3,
  ``--creep-seeds`` seeds each, with both channels, the displacement alone and the
  velocity alone. ``true_move_sd``: the noise-free displacement's move over the last
  3 s of the record, in the displacement noise's sd.

Run::

    PYTHONPATH=<tree> nice -n 10 timeout 3600 python benchmarks/creep_one_channel.py \\
        --workers 2 --output creep_one_channel

Writes ``benchmarks/results/<output>.json``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _machine import commit, niced_worker, write_results  # noqa: E402
from _tree import require_this_tree  # noqa: E402

RUNS = HERE.parent / "data" / "runs"
ENTROPY = 3939
#: Laws of the drift records: (ζ, μ_k).
LAWS = ((0.0236, 0.0294), (0.01, 0.03), (0.005, 0.05), (0.03, 0.01))
EFFECTS = ("none", "linear", "walk", "pink", "hum", "steps")


def _prepare(run: Any) -> dict[str, Any]:
    """Prepare ``run``; the warnings' classes, the noise's source, a refusal."""
    from dataclasses import asdict

    from bayestribo.errors import CreepWarning
    from bayestribo.inference import prepare
    from bayestribo.signal import creep_shape

    out: dict[str, Any] = {}
    paths: list[Any] = []
    measure = creep_shape.rest_path

    def spy(*a: Any, **k: Any) -> Any:
        path = measure(*a, **k)
        paths.append(path)
        return path

    creep_shape.rest_path = spy
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            prepared = prepare(run)
            noise = prepared.decay.noise
            out.update(
                noise_source=noise.source,
                noise_displacement=noise.displacement,
                noise_velocity=noise.velocity,
            )
        except Exception as exc:  # a refusal is recorded, not a failure
            out["refused"] = f"{type(exc).__name__}: {str(exc)[:200]}"
        finally:
            creep_shape.rest_path = measure
    # the one-channel test's measurements (None: the rest too short or not tested)
    out["rest_path"] = asdict(paths[-1]) if paths and paths[-1] is not None else None
    out["rest_path_tested"] = bool(paths)
    creeps = [w for w in caught if issubclass(w.category, CreepWarning)]
    out["creep"] = bool(creeps)
    if creeps:
        out["creep_message"] = str(creeps[0].message)[:600]
    out["warnings"] = sorted({w.category.__name__ for w in caught})
    return out


def _variants(run: Any) -> dict[str, Any]:
    from bayestribo import Run

    out = {}
    if run.displacement is not None and run.velocity is not None:
        out["both"] = run
    if run.displacement is not None:
        out["displacement"] = Run(
            time=run.time, displacement=run.displacement, metadata=dict(run.metadata)
        )
    if run.velocity is not None:
        out["velocity"] = Run(time=run.time, velocity=run.velocity, metadata=dict(run.metadata))
    return out


def bundled_job(path: str) -> list[dict[str, Any]]:
    from bayestribo import read_run

    run = read_run(path)
    name = str(Path(path).relative_to(RUNS))
    return [
        {"set": "bundled", "name": name, "channels": k, **_prepare(r)}
        for k, r in _variants(run).items()
    ]


def real_job(name: str) -> list[dict[str, Any]]:
    import real

    run, info = real.load(name)
    out = []
    for k, r in _variants(run).items():
        if k == "velocity":
            continue  # the software's derivative, not a recorded channel
        out.append(
            {"set": "real", "name": name, "channels": k, "read": info["read"], **_prepare(r)}
        )
    return out


def drift_record(index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Record ``index`` of the drift set: t [s], x [m], v [m/s] and what was drawn."""
    import _chain

    rng = np.random.default_rng([ENTROPY, index])
    effect = EFFECTS[index % len(EFFECTS)]
    fs = float(rng.choice([10_000.0, 1_000.0]))
    before = float(rng.choice([0.0, 0.1]))
    after = float(rng.choice([0.1, 0.5, 1.0, 3.0]))
    zeta, mu_k = LAWS[int(rng.integers(len(LAWS)))]
    t, x, v = _chain.record(fs, before, after, zeta=zeta, mu_k=mu_k)
    chain: dict[str, Any] = {}
    size = float(rng.uniform(1.0, 5.0))
    if effect == "pink":
        chain["pink"] = size
    elif effect == "hum":
        chain["hum"] = size
    elif effect == "steps":
        chain["steps"] = float(rng.choice([10.0, 30.0, 100.0]))
    xs, vs = _chain.apply_chain(t, x, v, fs, seed=[ENTROPY, index, 1], **chain)
    sx, sv = 10 * _chain.RESOLUTION_X, 10 * _chain.RESOLUTION_V
    drawn: dict[str, Any] = {"effect": effect, "fs": fs, "rest_before_s": before}
    drawn.update(rest_after_s=after, zeta=zeta, mu_k=mu_k, chain=chain)
    if effect == "linear":
        total = math.exp(rng.uniform(0.0, math.log(300.0))) * float(rng.choice([-1.0, 1.0]))
        ramp = (t - t[0]) / (t[-1] - t[0])
        xs, vs = xs + total * sx * ramp, vs + total * sv * ramp
        drawn["drift_over_record_sd"] = total
    elif effect == "walk":
        rms = math.exp(rng.uniform(0.0, math.log(30.0)))
        for sig, s in ((xs, sx), (vs, sv)):
            walk = np.cumsum(rng.standard_normal(t.size))
            walk -= walk.mean()
            sig += rms * s * walk / walk.std()
        drawn["walk_rms_sd"] = rms
    return t, xs, vs, drawn


def drift_job(index: int) -> list[dict[str, Any]]:
    import _chain

    from bayestribo import Run

    t, x, v, drawn = drift_record(index)
    meta = _chain.metadata()
    out = []
    for k, run in (
        ("displacement", Run(time=t, displacement=x, metadata=meta)),
        ("velocity", Run(time=t, velocity=v, metadata=meta)),
    ):
        out.append({"set": "drift", "name": index, "channels": k, **drawn, **_prepare(run)})
    return out


def seismometer_job(case: str, seed: int) -> list[dict[str, Any]]:
    import seismometer

    from bayestribo import Run

    t, v = seismometer.record(seed, **seismometer.CASES[case])
    run = Run(time=t, velocity=v, metadata={"length_unit": "arbitrary"})
    return [
        {"set": "seismometer", "name": f"{case}-{seed}", "channels": "velocity", **_prepare(run)}
    ]


def creep_job(strength: float, seed: int) -> list[dict[str, Any]]:
    import _creep_sim
    from stribeck_verdict import ENTROPY as SV_ENTROPY
    from stribeck_verdict import draw_creep

    from bayestribo import Run

    truth = draw_creep(strength, seed)
    noise_seed = [SV_ENTROPY, round(100 * strength), seed, 1]
    t, x, v = _creep_sim.simulate(truth, noise_seed)
    # the noise-free displacement: the simulator's noise drawn again
    x_true = x - np.random.default_rng(noise_seed).normal(0.0, _creep_sim.NOISE[0], t.size)
    late = t >= t[-1] - 3.0
    move = float(abs(x_true[late][-1] - x_true[late][0])) / _creep_sim.NOISE[0]
    run = Run(time=t, displacement=x, velocity=v, metadata={})
    base = {"set": "creep", "strength": strength, "seed": seed, "true_move_sd": move}
    return [
        {**base, "name": f"{strength:g}-{seed}", "channels": k, **_prepare(r)}
        for k, r in _variants(run).items()
    ]


def _count(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in sorted({(r["set"], r["channels"]) for r in rows}):
        sel = [r for r in rows if (r["set"], r["channels"]) == key]
        out[f"{key[0]}/{key[1]}"] = {
            "records": len(sel),
            "refused": sum("refused" in r for r in sel),
            "creep": sum(r["creep"] for r in sel),
            "creep_names": [r["name"] for r in sel if r["creep"]],
        }
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--drift-records", type=int, default=360)
    parser.add_argument("--creep-seeds", type=int, default=20)
    parser.add_argument("--seismometer-seeds", type=int, default=5)
    parser.add_argument(
        "--sets", nargs="+", default=["bundled", "real", "drift", "seismometer", "creep"]
    )
    parser.add_argument("--output", default="creep_one_channel")
    args = parser.parse_args(argv)
    package = require_this_tree()
    jobs: list[tuple[Any, ...]] = []
    if "bundled" in args.sets:
        jobs += [(bundled_job, str(p)) for p in sorted(RUNS.rglob("*.csv"))]
    if "real" in args.sets:
        import real

        jobs += [(real_job, name) for name in real.recordings()]
    if "drift" in args.sets:
        jobs += [(drift_job, i) for i in range(args.drift_records)]
    if "seismometer" in args.sets:
        jobs += [
            (seismometer_job, c, s)
            for c in ("clean", "drift")
            for s in range(1, args.seismometer_seeds + 1)
        ]
    if "creep" in args.sets:
        jobs += [(creep_job, s, k) for k in range(1, args.creep_seeds + 1) for s in (0.3, 1.0, 3.0)]
    start = time.time()
    rows: list[dict[str, Any]] = []
    with ProcessPoolExecutor(args.workers, initializer=niced_worker) as pool:
        for got in pool.map(_call, jobs):
            rows.extend(got)
            for r in got:
                flag = "CREEP" if r["creep"] else ("refused" if "refused" in r else "")
                print(r["set"], r["name"], r["channels"], flag, flush=True)
    summary = _count(rows)
    fresh = [{**r, "set": "drift fresh"} for r in rows if r["set"] == "drift" and r["name"] >= 180]
    summary.update(_count(fresh))
    creep_rows = [r for r in rows if r["set"] == "creep"]
    for channels in ("displacement", "velocity") if creep_rows else ():
        # detection where the two channels' test finds the creep
        both = {r["name"] for r in creep_rows if r["channels"] == "both" and r["creep"]}
        one = [r for r in creep_rows if r["channels"] == channels and r["name"] in both]
        summary[f"creep/{channels}"]["found_where_both_channels_find_it"] = [
            sum(r["creep"] for r in one),
            len(one),
        ]
    results = {
        "package": package,
        "package_commit": commit(HERE.parent),
        "settings": vars(args),
        "wall_s": time.time() - start,
        "summary": summary,
        "rows": rows,
    }
    path = write_results(args.output, results)
    import json

    print(json.dumps(summary, indent=1))
    print(path)


def _call(job: tuple[Any, ...]) -> list[dict[str, Any]]:
    fn, *a = job
    try:
        return fn(*a)
    except Exception as exc:  # a record the set could not build is recorded
        return [
            {
                "set": fn.__name__,
                "name": str(a),
                "channels": "-",
                "creep": False,
                "refused": f"job: {type(exc).__name__}: {exc}",
            }
        ]


if __name__ == "__main__":
    main()
