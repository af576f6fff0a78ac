"""Adequacy checks on a real recording: HarmOsc2 (air drag from a cardboard disc).

The AppStat2020 HarmOsc2 recording (spring-mass oscillator, 100 Hz, position only)
is damped by the air drag of a cardboard disc, a force that grows with the square
of the velocity: the equivalent linear damping must fall as the amplitude decays,
and the linear law (constant ζ and friction) must be found inadequate.
"""

from __future__ import annotations

import numpy as np
import pytest
from _paths import APPSTAT

from bayestribo.adequacy import check_adequacy

DATA = APPSTAT / "HarmOsc2.txt"

pytestmark = pytest.mark.skipif(not DATA.exists(), reason=f"real recording not found: {DATA}")


@pytest.fixture(scope="module")
def report():
    from bayestribo.io import read_run

    run = read_run(
        DATA, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
    )
    return check_adequacy(run)


def test_equivalent_damping_falls_with_the_amplitude(report):
    w = report.windows
    # friction is not resolved window by window: the equivalent ζ is fitted
    assert w.extra["friction_mode"] == "fixed"
    assert w.window_oscillations == 6  # about 50 oscillations / 8
    regular = [x for x in w.windows if x.regular]
    assert len(regular) >= 5
    # the largest-amplitude window damps more than the middle ones: compare the
    # first window with the next two (intervals must not overlap)
    first = regular[0]
    assert all(first.zeta_interval[0] > x.zeta_interval[1] for x in regular[1:3])
    assert report.constancy.zeta.change > 0  # larger ζ at larger amplitude
    lo, _ = report.constancy.zeta.change_interval
    assert lo > 0


def test_the_linear_law_is_not_adequate(report):
    assert report.constancy is not None and not report.constancy.constant
    assert report.constancy.p_value < 1e-3
    assert not report.adequate
    assert "not adequate" in report.verdict
    # the record ends while the pin still moves: no measured end of motion
    assert report.extinction.measured is None
    # the peaks are not reproduced by constant parameters
    assert report.predictive.coverage < 0.8
    assert np.isfinite(report.predictive.rms_standardized)
