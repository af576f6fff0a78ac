"""A gyroscope's export read as the angular velocity of the axis that swings, and a
velocity alone whose stop's turning point the noise splits in two analysed, not refused."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import ReadingWarning
from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run
from bayestribo.signal.split_stop import split_stop


def _torsion(seed: int, fs: float = 100.0):
    """A torsion oscillator (1.5 Hz, ζ = 0.01, friction angle 0.004 rad, static 0.006
    rad) released from 0.35 rad after 1 s, 3 s kept after the stop: time [s] and the
    angular velocity [rad/s], closed form half cycle by half cycle."""
    f, zeta, th_c, th_s, th0 = 1.5, 0.01, 0.004, 0.006, 0.35 + 0.002 * seed
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - zeta**2)
    starts, eqs, amps = [], [], []
    x, t0 = th0, 1.0
    while abs(x) > th_s:
        e = th_c * np.sign(x)
        starts.append(t0)
        eqs.append(e)
        amps.append(x - e)
        x = e - (x - e) * np.exp(-zeta * w * np.pi / wd)
        t0 += np.pi / wd
    t = np.arange(round((t0 + 3.0) * fs)) / fs
    om = np.zeros(t.size)
    k = np.searchsorted(starts, t, side="right") - 1
    moving = (k >= 0) & (t < t0)
    tau = t[moving] - np.asarray(starts)[k[moving]]
    om[moving] = (
        -np.asarray(amps)[k[moving]] * np.exp(-zeta * w * tau) * (w**2 / wd) * np.sin(wd * tau)
    )
    return t, om


def test_the_axis_that_swings_is_read_as_the_angular_velocity(tmp_path):
    t, om = _torsion(0)
    rng = np.random.default_rng(32)
    deg = np.degrees(om)
    cols = [rng.normal(0, 0.15, t.size), rng.normal(0, 0.15, t.size), deg + 0.4]
    cols[2] = cols[2] + rng.normal(0, 0.15, t.size)
    path = tmp_path / "gyro.csv"
    head = '"Time (s)","Gyroscope x (deg/s)","Gyroscope y (deg/s)","Gyroscope z (deg/s)"'
    rows = [f"{a:.3f},{b:.5f},{c:.5f},{d:.5f}" for a, b, c, d in zip(t, *cols, strict=True)]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = read_run(path)
    np.testing.assert_allclose(run.velocity, np.radians(cols[2]), rtol=1e-4, atol=1e-7)
    assert run.metadata["length_unit"] == "rad"
    said = [str(w.message) for w in caught if issubclass(w.category, ReadingWarning)]
    assert any("gyroscope's z axis" in s for s in said), said


def test_axes_that_swing_alike_are_not_guessed(tmp_path):
    t, om = _torsion(0)
    deg = np.degrees(om)
    path = tmp_path / "askew.csv"
    head = "Time (s),Gyroscope x (rad/s),Gyroscope y (rad/s),Gyroscope z (rad/s)"
    rows = [
        f"{a:.3f},{0.6 * b:.5f},{0.8 * b:.5f},{0.01 * b:.5f}" for a, b in zip(t, deg, strict=True)
    ]
    path.write_text(head + "\n" + "\n".join(rows) + "\n")
    with pytest.raises(Exception, match="other quantities"):
        read_run(path)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_velocity_alone_whose_stop_is_split_by_the_noise_is_analysed(seed):
    t, om = _torsion(seed)
    rng = np.random.default_rng(100 + seed)
    run = Run(
        time=t,
        velocity=om + math.radians(0.4) + rng.normal(0, math.radians(0.15), t.size),
        metadata={"natural_frequency_Hz": 1.5, "length_unit": "rad"},
    )
    decay = prepare(run).decay
    stop = t[np.flatnonzero(om)[-1]]
    # the analysis reaches the stop: within half of a half period (0.33 s), not ended a
    # turning point before it
    assert decay.end_time == pytest.approx(stop, abs=0.15)


def test_split_stop():
    half = 1 / 3
    tt = np.arange(8) * half
    vals = 0.1 * (-0.8) ** np.arange(8)
    assert not split_stop(tt, vals, 1e-3)
    split_t = np.append(tt, tt[-1] + 0.03)
    assert split_stop(split_t, np.append(vals, vals[-1]), 1e-3)
    # the second of the pair at another level, or too late, is not the stop's
    assert not split_stop(split_t, np.append(vals, vals[-1] + 0.01), 1e-3)
    assert not split_stop(np.append(tt, tt[-1] + 0.2), np.append(vals, vals[-1]), 1e-3)
