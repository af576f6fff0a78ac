"""A record sampled too slowly for its oscillation is told so, not told its units.

At 80 Hz a 32.6 Hz decay holds 2.45 samples a period: the integral of the velocity over
a sample is no measure of the displacement's change, and the channel check read a gain
of 2.3 and advised giving each column its unit, which, followed, reads the same file
the same way. The record is an independent simulation (``_law_recording.py``).
"""

from __future__ import annotations

import math

import pytest
from _law_recording import law_recording

from bayestribo.errors import RecordingError
from bayestribo.io.run import Run
from bayestribo.signal.channels import check_channels


def _decimated(rate_hz: float) -> Run:
    omega = 2.0 * math.pi * 32.6
    run = law_recording(
        lambda v: 2.0 * 0.0236 * omega * v, friction=0.0294 * 0.31 / 0.035, duration_s=1.0
    )
    step = round(5000.0 / rate_hz)
    return Run(run.time[::step], run.displacement[::step], run.velocity[::step], run.metadata)


@pytest.mark.parametrize("rate_hz", [80.0, 100.0])
def test_too_few_samples_a_period_is_said(rate_hz) -> None:
    with pytest.raises(RecordingError, match=r"dominant period is [0-9.]+ samples long") as e:
        check_channels(_decimated(rate_hz), "slow.csv")
    assert "unit" not in str(e.value).split("record it at")[0]


def test_a_record_sampled_well_passes() -> None:
    check_channels(_decimated(1000.0), "fast.csv")
