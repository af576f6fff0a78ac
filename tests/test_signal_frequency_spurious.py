"""The frequency a record without a nominal one is said to have: crossings that are not
the oscillation's are not counted.

A beam's second bending mode (6.27 times the first, 3 % of the release) swings the
velocity through zero between its turning points, and a displacement alone in white
noise (1.5 % of the release) crosses zero between them once its derivative is taken:
the zero crossings counted give 48.6 Hz and 120.9 Hz for 32.6 Hz (this test's records),
and the warning said the stiffness used that frequency (it used the turning times'
32.6 Hz), ``bayestribo inspect`` reported it as the oscillation's, and the decay called
it the nominal one.

The records are independent simulations (``_law_recording.py``: ``solve_ivp`` with the
stick rule; the second mode added in closed form).
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo.errors import MetadataWarning
from bayestribo.io.run import Run
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.frequency import (
    _central_difference,
    crossing_frequency,
    oscillation_frequency,
)

F_HZ = 32.6


def _paper_rig(seed: int = 1) -> Run:
    omega = 2.0 * math.pi * F_HZ
    return law_recording(
        lambda v: 2.0 * 0.0236 * omega * v, friction=0.0294 * 0.31 / 0.035, seed=seed
    )


def _second_mode(run: Run) -> Run:
    """The run with a second bending mode from the release: 6.27 f, 3 % of the release,
    ζ = 0.01."""
    t = run.time
    t0 = t[np.argmax(np.abs(run.displacement - run.displacement[0]) > 1e-6)]
    w = 2.0 * math.pi * 6.27 * F_HZ
    s = np.clip(t - t0, 0.0, None)
    envelope = np.where(t >= t0, 0.03e-3 * np.exp(-0.01 * w * s), 0.0)
    return Run(
        t,
        run.displacement + envelope * np.cos(w * s),
        run.velocity - envelope * w * np.sin(w * s),
        {k: v for k, v in run.metadata.items() if k != "natural_frequency_Hz"},
    )


def _noisy_displacement(run: Run) -> Run:
    rng = np.random.default_rng(5)
    x = run.displacement + rng.normal(0.0, 1.5e-5, run.time.size)
    meta = {k: v for k, v in run.metadata.items() if k != "natural_frequency_Hz"}
    return Run(run.time, x, None, meta)


@pytest.mark.parametrize("make", [_second_mode, _noisy_displacement])
def test_spurious_crossings_do_not_make_the_frequency(make) -> None:
    run = make(_paper_rig())
    # the crossings alone count far more than the oscillation's
    if run.velocity is not None:
        crossed = crossing_frequency(run.time, run.velocity)
    else:
        crossed = crossing_frequency(*_central_difference(run.time, run.displacement)[:2])
    assert crossed > 1.4 * F_HZ
    f = oscillation_frequency(run.time, run.displacement, run.velocity)
    assert f == pytest.approx(F_HZ, rel=0.01)


@pytest.mark.parametrize("make", [_second_mode, _noisy_displacement])
def test_the_warning_states_the_frequency_the_stiffness_uses(make) -> None:
    run = make(_paper_rig())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rig = run.rig()
        decay = energy_decay(run.time, run.displacement, run.velocity, rig=rig)
    text = next(str(w.message) for w in caught if issubclass(w.category, MetadataWarning))
    said = float(re.search(r"about ([0-9.]+) Hz", text)[1])
    # the stiffness takes the decay's natural frequency; the warning's figure is its
    # approximation, and neither is the crossings' count
    assert said == pytest.approx(decay.natural_frequency_Hz, rel=0.01)
    assert decay.scaling.omega == pytest.approx(2.0 * math.pi * decay.natural_frequency_Hz)
    # an estimate from the record is not a nominal frequency
    assert rig.frequency_measured and decay.nominal_frequency_Hz is None


def test_a_clean_record_keeps_its_crossings_frequency() -> None:
    run = _paper_rig()
    f = oscillation_frequency(run.time, run.displacement, run.velocity)
    assert f == crossing_frequency(run.time, run.velocity)


def test_a_nominal_frequency_stays_nominal() -> None:
    run = _paper_rig()
    rig = run.with_metadata(natural_frequency_Hz=F_HZ).rig()
    assert not rig.frequency_measured
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=rig)
    assert decay.nominal_frequency_Hz == F_HZ
