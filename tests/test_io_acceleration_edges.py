"""An accelerometer's record: the release and the stop from the acceleration, and the
last swings under its threshold.

The velocity integrated from an acceleration carries the integral's noise, a random
walk held at the rests and free next to them, which wanders well beyond its rest noise
next to the stop: found in the velocity, the stop came late, or the velocity's levels
next to the edges were taken for an offset that drifts. The acceleration's noise is
white: the release and the stop are taken from it (``Integration.release_s``,
``stop_s``), and last swings that peak under its threshold are found as lobes of its
mean over an eighth of a period (:func:`bayestribo.signal.motion.lobes_after_stop`).

Independent records: ``tests/_accelerometer_decay.py`` (``solve_ivp`` half cycle by
half cycle with sticking, the acceleration averaged over each sample interval).
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import warnings

import numpy as np
import pytest
from _accelerometer_decay import Decay, accelerometer

from bayestribo.cli import main
from bayestribo.io import read_run
from bayestribo.io.acceleration import motion_edges

#: (record, noise seed): a 60 Hz decay over nine cycles that sticks (before the
#: acceleration's edges, its velocity's offset was said to drift, exit 1, on this seed);
#: a 20 Hz decay whose last swings, 2-10 µm, peak at 1.5-8 σ of the acceleration (before:
#: its offset said to drift and μ_s/μ_k 4.8 [1.5, 9.8] where it is 1, exit 1; with the
#: acceleration's stop but not its lobes, 9.0 [6.7, 9.9] on another draw, exit 0).
CASES = {
    "fast": (Decay(), 1),
    "slow": (Decay(f0=20.0, zeta=0.005, friction=1e-6, x0=2e-4, hold=0.5, duration=2.5), 3),
}


@functools.cache
def _file(name: str, directory: str) -> tuple[str, float]:
    case, seed = CASES[name]
    t, a, _, stopped = accelerometer(case, seed)
    path = f"{directory}/{name}.csv"
    np.savetxt(
        path,
        np.column_stack([t, a]),
        delimiter=",",
        header="time_s,acceleration_m_per_s2",
        comments="",
    )
    return path, stopped


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    directory = str(tmp_path_factory.mktemp("accelerometer"))
    return {name: _file(name, directory) for name in CASES}


@pytest.mark.parametrize("name", list(CASES))
def test_the_stop_is_the_accelerations_never_before_the_last_turning_point(files, name):
    path, stopped = files[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = read_run(path)
    release, stop = motion_edges(dict(run.metadata))
    case = CASES[name][0]
    assert release == pytest.approx(case.hold, abs=2.0 / case.rate)
    # late by an eighth of a period at most, never early: the sticking turning point
    # stays inside the motion
    assert stopped - 2.0 / case.rate <= stop <= stopped + 0.125 / case.f0 + 2.0 / case.rate


@pytest.mark.parametrize("name", list(CASES))
def test_the_fit_covers_the_truth_and_says_nothing_wrong(files, name):
    path, _ = files[name]
    buf = io.StringIO()
    with warnings.catch_warnings(record=True) as said, contextlib.redirect_stdout(buf):
        warnings.simplefilter("always")
        status = main(["fit", path, "--json"])
    assert status == 0, [str(w.message)[:300] for w in said]
    assert not any("offset" in type(w.message).__name__.lower() for w in said)
    found = json.loads(buf.getvalue())["parameters"]
    case = CASES[name][0]
    for key, truth in (
        ("zeta", case.zeta),
        ("friction_displacement", case.friction),
        ("mu_s_ratio", 1.0),
    ):
        lo, hi = found[key]["interval"]
        assert lo <= truth <= hi, (key, found[key])
    assert not math.isnan(found["zeta"]["mean"])


def test_a_mains_line_on_the_acceleration_leaves_the_fade_a_fade(tmp_path):
    # the slow decay under a 50 Hz line of 2.5 times the noise: the acceleration's
    # threshold stops 0.1 s before the last swings, where the velocity sees its swings
    # fade into the noise; taken for the stop, μ_s/μ_k came out 7.3 [1.8, 9.9] where it
    # is 1, exit 0. The fade is kept: μ_s/μ_k unconstrained, ζ and x_c covered
    case, seed = CASES["slow"]
    t, a, _, _ = accelerometer(case, seed)
    a = a + 2.5 * case.noise * np.sin(2.0 * math.pi * 50.0 * t + 0.3)
    path = tmp_path / "hum.csv"
    np.savetxt(
        path,
        np.column_stack([t, a]),
        delimiter=",",
        header="time_s,acceleration_m_per_s2",
        comments="",
    )
    buf = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stdout(buf):
        warnings.simplefilter("ignore")
        status = main(["fit", str(path), "--json"])
    assert status == 0
    found = json.loads(buf.getvalue())["parameters"]
    for key, truth in (
        ("zeta", case.zeta),
        ("friction_displacement", case.friction),
        ("mu_s_ratio", 1.0),
    ):
        lo, hi = found[key]["interval"]
        assert lo <= truth <= hi, (key, found[key])


@pytest.mark.parametrize("bad", ["soon", float("nan"), True, [1.0]])
def test_an_edge_that_is_not_a_number_is_refused_naming_the_field(bad):
    from bayestribo.errors import RunFormatError

    with pytest.raises(RunFormatError, match=r"acceleration\.stop_s"):
        motion_edges({"acceleration": {"release_s": 0.3, "stop_s": bad}})
    assert motion_edges({"acceleration": {"release_s": 0.3, "stop_s": None}}) == (0.3, None)
    assert motion_edges({"acceleration": {"column": "a"}}) is None
