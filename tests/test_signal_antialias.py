"""A declared first-order anti-alias filter undone on both channels (its gain, its lag
and its smoothing of the friction's kinks), not only its gain divided out."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from test_signal_integration import F_HZ, OMEGA, X0, _motion

from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run
from bayestribo.signal.sensor import sensor_calibration, undo_first_order

FS = 10_000.0
ONE_POLE = {"kind": "butterworth", "order": 1, "cutoff_Hz": 5 * F_HZ}


def _record() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Viscous + Coulomb decay from X0 (released at 0.1 s), closed form half cycle by
    half cycle, and both channels through the bilinear one-pole at 5 f (at rest at the
    start)."""
    t = np.arange(0, 0.8, 1 / FS)
    x, v = _motion(t, release=0.1)
    b, a = scipy.signal.butter(1, ONE_POLE["cutoff_Hz"], fs=FS)
    zi = scipy.signal.lfilter_zi(b, a)
    xf = scipy.signal.lfilter(b, a, x, zi=zi * x[0])[0]
    vf = scipy.signal.lfilter(b, a, v, zi=zi * v[0])[0]
    return t, x, v, xf, vf


def test_the_channels_before_a_first_order_filter_are_recovered():
    """At 5 f the filter moves the displacement by up to 20 % of the swing (its lag);
    undone, the channels are within 3e-4 of it (the record's filter is the digital,
    bilinear one; the analog one-pole is undone: the difference, about 1e-4 of the
    swing, is a tenth of the noise of a vibrometer at 10 times its resolution)."""
    t, x, v, xf, vf = _record()
    moving = slice(int(0.15 * FS), int(0.5 * FS))
    assert np.max(np.abs(xf - x)[moving]) > 0.1 * X0
    xu, vu = undo_first_order(t, xf, vf, ONE_POLE, 1 / F_HZ)
    assert np.max(np.abs(xu - x)[moving]) < 3e-4 * X0
    assert np.max(np.abs(vu - v)[moving]) < 3e-4 * OMEGA * X0
    with pytest.raises(ValueError, match="first-order"):
        undo_first_order(t, xf, vf, {**ONE_POLE, "order": 2}, 1 / F_HZ)


def test_a_prepared_run_holds_its_channels_before_the_declared_filter():
    t, x, _, xf, vf = _record()
    meta = {"filter": ONE_POLE, "displacement_resolution_m": 1.5e-7}
    meta["velocity_resolution_m_per_s"] = 1.5e-8
    prepared = prepare(Run(time=t, displacement=xf, velocity=vf, metadata=meta))
    assert prepared.filter_undone
    moving = slice(int(0.15 * FS), int(0.5 * FS))
    assert np.max(np.abs(prepared.run.displacement - x)[moving]) < 3e-4 * X0
    sensor = sensor_calibration(meta, F_HZ, filter_undone=True)
    assert sensor.gain == 1.0 and "undone on both channels" in sensor.describe()
    assert sensor_calibration(meta, F_HZ).gain < 0.99
