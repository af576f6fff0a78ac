"""The digitiser in the record: a quantised channel (its step found, the noise at least
step/√12), and time stamps jittered about a regular clock (read on the clock)."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.io.run import Run
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.noise import noise_model
from bayestribo.signal.quantisation import QUANTISATION_NOISE_FACTOR, quantisation_step
from bayestribo.synthetic import simulate
from bayestribo.synthetic.setup import Sensor


@pytest.mark.parametrize("step", [1e-3, 2.5e-6, 0.1])
def test_the_step_of_rounded_values_is_found(step):
    rng = np.random.default_rng(1)
    x = np.round(np.cumsum(rng.normal(0, 3 * step, 500)) / step) * step
    assert quantisation_step(x) == pytest.approx(step, rel=1e-9)


@pytest.mark.parametrize(("bits", "span", "decimals"), [(12, 4.0, 6), (10, 2.0, 6), (12, 1.0, 7)])
def test_a_step_that_is_no_round_number_written_in_decimals_is_found(bits, span, decimals):
    # an ADC's step in the file's unit (4 mm over 12 bits: 0.9765625 µm) written with a
    # few decimals: the smallest change carries the text's rounding, which a change of
    # fifty or more steps a sample multiplies; the step is refined from the changes
    step = span / 2**bits
    rng = np.random.default_rng(3)
    t = np.arange(4000) / 400.0
    motion = 0.45 * span * np.exp(-0.2 * t) * np.cos(2 * np.pi * 10.0 * t)
    x = np.round(np.round(motion / step + 0.2 * rng.normal(size=t.size)) * step, decimals)
    assert np.max(np.abs(np.diff(x))) / step > 50
    assert quantisation_step(x) == pytest.approx(step, rel=1e-5)


def test_continuous_values_have_no_step():
    rng = np.random.default_rng(2)
    assert quantisation_step(rng.normal(0, 1e-6, 1000)) is None
    # a noise-free motion at rest is flat but moves in continuous steps
    assert quantisation_step(np.r_[np.zeros(100), np.sin(np.arange(300) / 7.0)]) is None
    assert quantisation_step([1.0, 1.0, 1.0]) is None


def test_a_digitiser_coarser_than_the_stated_resolution_sets_the_noise():
    """A displacement rounded to 2 µm (an 8-bit digitiser on a 0.5 mm range), flat at
    rest, and a data sheet resolution of 0.15 µm: the noise used is the rounding
    error, 2 µm/√12, not 0 (the rest) and not 0.15 µm."""
    step = 2e-6
    run = simulate(sensor=Sensor(displacement_noise_m=0.0, velocity_noise_m_per_s=1.5e-8), seed=3)
    rounded = Run(
        run.time,
        np.round(run.displacement / step) * step,
        run.velocity,
        dict(run.metadata),
    )
    decay = energy_decay(rounded.time, rounded.displacement, rounded.velocity, rig=rounded.rig())
    assert decay.noise.displacement_step == pytest.approx(step, rel=1e-9)
    assert decay.noise.velocity_step is None
    model = noise_model(decay, dict(rounded.metadata))
    assert model.displacement == pytest.approx(step * QUANTISATION_NOISE_FACTOR, rel=1e-6)
    assert model.displacement > 3 * model.nominal_displacement
    assert "quantised in steps of 2e-06" in model.describe()


def test_jittered_time_stamps_are_the_regular_clock_and_a_gap_is_bridged():
    """±2 µs of jitter on a 10 kHz time column (a logger's software stamps): read, the
    samples taken on the regular grid the stamps scatter about, and the fit is the
    fit of the record without jitter. A missing sample is bridged and said; a gap of a
    third of a period is refused, naming it."""
    from bayestribo import fit
    from bayestribo.errors import BayestriboError, GapWarning

    run = simulate(seed=4)
    rng = np.random.default_rng(1)
    stamps = run.time + rng.uniform(-2e-6, 2e-6, run.time.size)
    jittered = Run(stamps, run.displacement, run.velocity, dict(run.metadata))
    decay = energy_decay(stamps, run.displacement, run.velocity, rig=run.rig())
    assert 1e-6 < decay.noise.timing_jitter_s < 1.3e-6  # uniform ±2 µs: 2/√3 µs
    np.testing.assert_allclose(np.diff(decay.t), 1e-4, rtol=1e-6)
    a, b = fit(run, seed=1), fit(jittered, seed=1)
    for name in ("zeta", "mu_k"):
        sa, sb = a.summary()[name], b.summary()[name]
        assert abs(sa.mean - sb.mean) < 0.1 * sa.sd, name
    # a missing sample is bridged on the grid (bayestribo._clock), said, and the fit is
    # the fit of the whole record; a gap of a third of a period is refused, naming it
    gap = np.delete(np.arange(run.time.size), 3000)
    with pytest.warns(GapWarning, match=r"1 sample\(s\) after sample 2999"):
        c = fit(
            Run(run.time[gap], run.displacement[gap], run.velocity[gap], dict(run.metadata)), seed=1
        )
    for name in ("zeta", "mu_k"):
        sa, sc = a.summary()[name], c.summary()[name]
        assert abs(sa.mean - sc.mean) < 0.1 * sa.sd, name
    long = np.delete(np.arange(run.time.size), np.arange(3000, 3100))
    with pytest.raises(BayestriboError, match=r"100 samples are missing after sample 2999"):
        fit(Run(run.time[long], run.displacement[long], run.velocity[long], dict(run.metadata)))


def test_a_swing_no_rig_makes_is_refused_with_the_factor_that_fixes_it():
    """Millimetres read as metres on both channels (they then agree with each other):
    a 1.2 m swing at 32.6 Hz, 250 m/s. Refused, naming mm and the option. A stiff rig,
    a 0.3 mm swing at 1 kHz (1200 g, 1.9 m/s), is not refused."""
    from bayestribo import fit
    from bayestribo.errors import RecordingError

    run = simulate(seed=2)
    wrong = Run(run.time, run.displacement * 1e3, run.velocity * 1e3, dict(run.metadata))
    with pytest.raises(RecordingError, match=r"likely in mm .*--scale x=0.001 --scale v=0.001"):
        fit(wrong, seed=1)
    micro = Run(run.time, run.displacement * 1e6, run.velocity * 1e6, dict(run.metadata))
    with pytest.raises(RecordingError, match="likely in µm"):
        fit(micro, seed=1)
    from bayestribo.signal.decay import _check_plausible

    _check_plausible(np.array([3e-4, -2.9e-4]), 1000.0, None)  # no error
