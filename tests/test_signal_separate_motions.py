"""A record holding two runs back to back: the second is not the first's rest.

Two free decays on the paper's rig, one after the other in one file, the mass pulled
back to its hold between them (a smooth ramp of 0.25 s): the second run's motion lay in
the first's rest after its stop, whose noise it made 253 times the sensor's resolution
(the velocity's 185 000 times), and the fit answered with exit 0, no warning and an
interval of ζ of [0, 0.077] (the truth 0.0236, the sensor resolving it to 1e-4). The
largest motion is now analysed with the rests beside it, and the other is said and
left out.

The record is an independent simulation (``_law_recording.py``: ``solve_ivp`` half
cycle by half cycle with the stick rule).
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
from _law_recording import law_recording

from bayestribo.cli import main
from bayestribo.errors import SeparateMotionWarning
from bayestribo.io import write_run
from bayestribo.io.run import Run

ZETA, MU_K, LOAD, MASS, F_HZ = 0.0236, 0.0294, 0.31, 0.035, 32.6


def _two_runs() -> Run:
    omega = 2.0 * math.pi * F_HZ

    def one(seed: int, rest_s: float) -> Run:
        return law_recording(
            lambda v: 2.0 * ZETA * omega * v,
            friction=MU_K * LOAD / MASS,
            duration_s=1.0,
            rest_before_s=rest_s,
            seed=seed,
        )

    a, b = one(1, 0.1), one(2, 0.5)
    dt = float(a.time[1] - a.time[0])
    xb, vb = b.displacement.copy(), b.velocity.copy()
    # the mass pulled back from the first run's rest to the second's hold
    ramp_n = int(0.25 / dt)
    rest = float(np.median(a.displacement[-200:]))
    ramp = rest + (xb[0] - rest) * 0.5 * (1.0 - np.cos(np.pi * np.arange(ramp_n) / ramp_n))
    xb[:ramp_n] += ramp - xb[0]
    vb[:ramp_n] += np.gradient(ramp, dt)
    t = np.concatenate([a.time, a.time[-1] + dt + b.time])
    meta = {**a.metadata, "natural_frequency_Hz": F_HZ}
    return Run(t, np.concatenate([a.displacement, xb]), np.concatenate([a.velocity, vb]), meta)


def test_a_second_run_is_left_out_of_the_firsts_rest(tmp_path, capsys) -> None:
    path = write_run(_two_runs(), tmp_path / "two_runs.csv")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(["fit", str(path), "--json"])
    err = capsys.readouterr().err
    record = json.loads(buf.getvalue())
    assert status == 0, err
    assert "holds another motion than its largest" in err, err
    for name, truth in (("zeta", ZETA), ("mu_k", MU_K)):
        low, high = record["parameters"][name]["interval"]
        assert low <= truth <= high, (name, low, high)
    # the width a sensor resolving the motion gives (the single run's), not the other
    # run's motion taken for noise
    low, high = record["parameters"]["zeta"]["interval"]
    assert high - low < 0.001, (low, high)


def test_the_warning_is_its_own_kind() -> None:
    import warnings

    from bayestribo.signal.decay import energy_decay

    run = _two_runs()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    assert any(issubclass(w.category, SeparateMotionWarning) for w in caught)


def test_one_run_is_not_split() -> None:
    import warnings

    from bayestribo.signal.decay import energy_decay

    omega = 2.0 * math.pi * F_HZ
    run = law_recording(
        lambda v: 2.0 * ZETA * omega * v, friction=MU_K * LOAD / MASS, duration_s=2.0, seed=3
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    assert not any(issubclass(w.category, SeparateMotionWarning) for w in caught)
