"""A coarse digitiser (steps the noise does not dither): the increments' variances from
the rounding itself, the analysis ended after the last resolved turning point, y0 known to
half a step."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from _coarse_decay import coarse_record

from bayestribo.errors import RecordingError
from bayestribo.inference.priors import default_priors
from bayestribo.signal.coarse import (
    DITHER_STEPS,
    MIN_COARSE_TURNING_POINTS,
    RESOLVED_STEPS,
    CoarseWindow,
    coarse_steps,
    coarse_window,
    quantised_increments,
    resolved_end,
    resolved_turning_points,
    swing_end,
)
from bayestribo.signal.coverage import ShortAnalysisWarning
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import (
    increment_noise,
    increment_weights,
    integrate_increments,
    pi_data,
)
from bayestribo.signal.noise import noise_model

ZETA = 0.02


def _decay_motion(tau: np.ndarray, amplitude: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
    """A viscous decay (natural frequency 1 in τ) from ``amplitude`` at τ = 0."""
    wd = math.sqrt(1.0 - ZETA**2)
    env = amplitude * np.exp(-ZETA * tau)
    y = env * (np.cos(wd * tau) + ZETA / wd * np.sin(wd * tau))
    yp = -env / wd * np.sin(wd * tau)
    return y, yp


def test_a_channel_is_coarse_when_its_noise_does_not_dither_its_steps():
    assert coarse_steps((1.0, 1.0), (1.0 / math.sqrt(12.0), 2.0)) == (1.0, None)
    assert coarse_steps((None, 1.0), (0.3, DITHER_STEPS)) == (None, 1.0)
    assert coarse_steps((1.0, None), (DITHER_STEPS * 1.01, 0.1)) == (None, None)


def test_the_resolved_turning_points_end_at_the_last_amplitude_above_the_limit():
    values = RESOLVED_STEPS * np.array([9.0, -7.0, 5.0, -3.0, 2.5, -0.9, 1.0, -0.5, 0.4])
    # one reading below the limit (-0.9, rounded) does not end them
    assert resolved_turning_points(values, 1.0, (1.0, None)) == 7
    # the velocity's amplitude is ω|Y|: at ω = 0.25 a step of 1 resolves |Y| >= 4
    assert resolved_turning_points(values, 0.25, (None, RESOLVED_STEPS)) == 3
    assert resolved_turning_points(values, 1.0, (100.0, None)) == 0
    assert resolved_turning_points(values, 1.0, (None, None)) == values.size


def test_the_rounding_variances_match_the_spread_of_rounded_records():
    """A decay of 10 steps across its swing at 300 samples a period, rounded with 400
    placements of the levels: the spread of its increments is what
    quantised_increments says (within its Monte Carlo error), and several times what
    the white formula with the rounding's q/√12 gives."""
    h = 2 * math.pi / 300
    tau = np.arange(0, 12 * math.pi + h / 2, h)
    y, yp = _decay_motion(tau)
    step = 1.0
    edges, weights = increment_weights(tau.size, h, 12)
    bias, variance, neighbours = quantised_increments(
        y, yp, edges, weights, (step, step), n_replicates=400, seed=1
    )
    clean = integrate_increments(y, edges, weights)
    clean_e = integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
    assert clean.shape == bias.shape == variance.shape
    assert neighbours.shape == (edges.size - 2,)
    rng = np.random.default_rng(7)
    errors = []
    for _ in range(400):
        u = rng.uniform(-0.5, 0.5, 2)
        yq = np.round(y + u[0]) - u[0]
        ypq = np.round(yp + u[1]) - u[1]
        e = 0.5 * (yq * yq + ypq * ypq)
        observed = integrate_increments(e, edges, weights)
        errors.append(observed - clean_e - bias)
    errors = np.array(errors)
    # Sheppard's bias: q²/24 per channel per unit τ
    sums = np.array([w.sum() for w in weights])
    assert bias == pytest.approx(2 * sums / 24.0, rel=1e-12)
    assert np.mean(errors) == pytest.approx(0.0, abs=3 * np.sqrt(np.mean(variance) / errors.size))
    ratio = np.mean(errors**2, axis=0) / variance
    assert np.all((ratio > 0.7) & (ratio < 1.4))
    _, white = increment_noise(
        tau, y, yp, edges, weights, step / math.sqrt(12), step / math.sqrt(12)
    )
    assert np.median(variance / white) > 3


@pytest.mark.parametrize("placement", [0.0, 0.37])
def test_a_coarse_record_ends_its_analysis_at_the_last_resolved_swing(placement):
    """10 steps across the swing on both channels: the velocity reads 0 cycles before
    the pin sticks, so the end of motion is not observed. The analysis ends at the last
    turning point it resolves (Π truncated there), and the increments' variances
    cover their errors (the white formula left them 4 to 10 times too small). With the
    levels off the zero, the velocity's rest reads the level nearest its zero: taken
    for an offset, it moved every moving sample by a third of a step (residuals of ±5
    standard deviations alternating with the half cycles)."""
    t, x, v, (qx, _), _ = coarse_record(placement=placement)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ShortAnalysisWarning)
        decay = energy_decay(t, x, v)
    assert decay.noise.displacement_step == pytest.approx(qx, rel=1e-9)
    assert decay.motion_ended is False
    assert decay.velocity_offset == 0.0
    assert decay.stop_time is not None and decay.end_time < decay.stop_time
    # the last sample analysed is the last the displacement reaches a step from its
    # equilibrium (the velocity's steps, ω × the displacement's, end it no sooner)
    about = x - decay.equilibrium - decay.equilibrium_drift * (t - decay.start_time)
    last = np.flatnonzero(np.abs(about) >= RESOLVED_STEPS * qx)[-1]
    assert decay.end_time <= t[last]
    assert decay.end_time >= decay.peaks.t[-1]  # its last resolved turning point or after
    noise = noise_model(decay, {})
    data = pi_data(decay, noise)
    assert data.rounding == pytest.approx(qx / decay.scaling.length_scale, rel=1e-9)
    assert not data.spectral
    # the increments' errors against the record before rounding
    sl = np.searchsorted(t, decay.t)
    sc = decay.scaling
    _, x_, v_, _, _ = coarse_record(steps=1e9)
    y = (x_[sl] - decay.equilibrium - decay.equilibrium_drift * (decay.t - decay.start_time)) / (
        sc.length_scale
    )
    yp = v_[sl] / (sc.length_scale * sc.omega)
    h = float(decay.tau[1] - decay.tau[0])
    edges, weights = increment_weights(decay.tau.size, h, data.preparation["grid_points"])
    assert np.allclose(decay.tau[edges], data.tau_grid)
    true = integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
    z = (data.increments - true) / np.sqrt(data.variance)
    assert np.mean(z**2) < 4.0


def test_the_resolved_end_is_the_last_sample_every_coarse_channel_reaches_a_step():
    x = np.array([3.0, -2.0, 1.5, -0.5, 1.2, 0.2, 0.1])
    v = np.array([0.0, 3.0, -2.0, 1.0, -0.5, 0.2, 0.1])
    assert resolved_end((x, v), (RESOLVED_STEPS, None), 1) == 4
    assert resolved_end((x, v), (RESOLVED_STEPS, RESOLVED_STEPS), 1) == 3
    assert resolved_end((x, v), (None, None), 2) == 2


def test_a_coarse_displacement_widens_the_prior_of_y0():
    priors = default_priors(7.0, y0_sd=0.9)
    assert priors.priors["y0"].sigma == pytest.approx(0.9)
    assert default_priors(7.0).priors["y0"].sigma == pytest.approx(0.07)
    with pytest.raises(ValueError, match="y0_sd"):
        default_priors(7.0, y0_sd=-1.0)


def test_turning_points_on_a_coarse_digitisers_levels_give_a_law_free_answer():
    """Turning points rounded to levels a step apart repeat their swings exactly: the
    local fit's curvature is not determined, its mean is (it was a singular matrix)."""
    from bayestribo.inference.dissipation import turning_point_dissipation
    from bayestribo.model.laws import PhysicalScale

    # the swings near 4 are all 4: the local fit's x is 0 throughout
    turning = np.array([4.0, 4, 4, 4, 4, 4, 4, 4, 1, 1, 1, 1]) * (-1.0) ** np.arange(12)
    found = turning_point_dissipation(turning, np.array([4.0]), PhysicalScale())
    assert found is not None
    assert np.all(np.isfinite(found["mean"])) and np.all(np.isfinite(found["sd"]))


def test_channels_rounded_to_five_steps_are_one_motion():
    """Both channels rounded to a fifth of their swing, the levels off the zero: the
    windows whose change is a step or so are the rounding's; over the others the
    displacement follows the velocity's integral (over all moving windows the small
    swings brought the correlation below 0.9 and the record was refused as two
    motions)."""
    from bayestribo.io.run import Run
    from bayestribo.signal.channels import channel_consistency, check_channels

    t, x, v, _, _ = coarse_record(steps=5.0, placement=0.37)
    run = Run(time=t, displacement=x, velocity=v, metadata={})
    check_channels(run)
    assert channel_consistency(run).correlation > 0.95


@pytest.mark.parametrize("placement", [-0.45, -0.35, 0.25, 0.35, 0.45])
def test_a_coarse_displacement_gives_the_frequency_of_its_velocitys_zeros(placement):
    """5 steps across the swing: the decrement read off turning points on the levels is
    no measurement (it made the natural frequency 1.4 times the record's); the damped
    frequency of the turning times is taken, within the rounding's timing error."""
    t, x, v, _, _ = coarse_record(steps=5.0, placement=placement)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = energy_decay(t, x, v)
    assert decay.natural_frequency_Hz == decay.damped_frequency_Hz
    assert decay.natural_frequency_Hz == pytest.approx(32.6, rel=0.01)


@pytest.mark.parametrize("placement", [-0.45, -0.15, 0.0, 0.25, 0.45])
def test_five_steps_across_the_swing_keep_every_swing_of_two_steps(placement):
    """5 steps across the swing: a swing between levels two steps apart is a turning
    point, and the motion across three levels is not a rest (its range of two steps
    was within the band of four noise sd, q/√12 each, and the analysis ended after 5
    turning points: the record was refused for want of 7). Every leading swing whose
    true peak-to-peak height is 2.5 steps or more reads two steps or more after rounding
    (at most half a step off at each end), so each is found."""
    t, x, v, (qx, _), _ = coarse_record(steps=5.0, placement=placement)
    _, x_true, v_true, _, _ = coarse_record(steps=1e12)
    moving = (t > 0.1) & (np.abs(v_true) > 0)
    turns = np.flatnonzero(np.diff(np.sign(v_true[moving])) != 0)
    values = np.concatenate([[2e-3], x_true[moving][turns]])
    swings = np.abs(np.diff(values))
    clear = int(np.argmin(swings >= 2.5 * qx))  # the leading swings of 2.5 steps or more
    assert clear >= 8
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = energy_decay(t, x, v)
    assert decay.noise.displacement_step == pytest.approx(qx, rel=1e-9)
    assert decay.peaks.stop_time is None or decay.peaks.stop_time > decay.peaks.t[-1]
    # turning points 2 to `clear` of the motion (the release's is 0; the first
    # oscillation, 1 and 2, is skipped) are analysed: at least clear - 1 of them
    assert len(decay.peaks) >= clear - 1


@pytest.mark.parametrize("placement", [-0.3, 0.0, 0.45])
def test_a_coarse_velocity_alone_is_answered_and_said_to_be_uncalibrated(placement):
    """The velocity alone, rounded to a tenth of its swing: its integral's last turning
    points are the rounding's (they broke the half period and the record was refused
    at two placements of three). The decay fades where the velocity resolves no swing,
    and the record is answered, with a CoarseSignalWarning: the rounding accumulates in
    the integral, which the noise model does not hold."""
    from bayestribo.errors import CoarseSignalWarning, MisfitWarning

    t, _, v, _, _ = coarse_record(steps=10.0, placement=placement)
    with pytest.warns(CoarseSignalWarning, match="integral of the velocity"):
        decay = energy_decay(t, None, v)
    assert len(decay.peaks) >= 6
    assert issubclass(CoarseSignalWarning, MisfitWarning)  # the fit's exit status is 1


@pytest.mark.parametrize("placement", [-0.3, 0.0, 0.25, 0.35, 0.45])
def test_three_steps_across_the_swing_are_answered_and_said_to_be_too_few(placement):
    """3 steps across the swing: the swings sink below two steps within three
    oscillations, but the first ones stand out and shrink, a decay. Every placement is
    answered (at 0.25 and 0.35 the record was refused for want of one or two turning
    points), on at least two oscillations, with CoarseSignalWarnings: the steps across
    the swing, and the turning points analysed where the record lacks some."""
    from bayestribo.errors import CoarseSignalWarning

    t, x, v, (qx, _), _ = coarse_record(steps=3.0, placement=placement)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x, v)
    said = [str(w.message) for w in caught if issubclass(w.category, CoarseSignalWarning)]
    assert said and "3 steps" in said[0]
    assert len(decay.peaks) >= MIN_COARSE_TURNING_POINTS
    if len(decay.peaks) < 6:  # fewer than three oscillations: said so
        assert any(
            (f"steps displacement {qx:.3g}" in m and "are asked for" in m)
            or "skipped after the release analysed too" in m
            for m in said
        )


@pytest.mark.parametrize("placement", [0.25, 0.35])
def test_a_coarse_record_asked_for_three_oscillations_is_told_to_keep_the_first(placement):
    """Three steps across the swing, six turning points, ``min_turning_points=6`` asked
    for: one oscillation skipped (the default) leaves too few, the refusal names the
    last swing of two steps, and its advice, followed, gives the analysis."""
    t, x, v, (qx, _), _ = coarse_record(steps=3.0, placement=placement)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(RecordingError, match=r"skip_oscillations=0 \(--skip 0\)") as told:
            energy_decay(t, x, v, min_turning_points=6)
        assert f"quantised in steps of {qx:.3g}" in str(told.value)
        assert re.search(
            r"the swings after turning point \d+ \(t = [0-9.]+ s\) hold fewer", str(told.value)
        )
        left = int(re.search(r"which leaves (\d+) turning points", str(told.value)).group(1))
        decay = energy_decay(t, x, v, skip_oscillations=0, min_turning_points=6)
    assert len(decay.peaks) == left


def test_the_coarse_window_lowers_the_count_then_the_skip_and_nothing_else():
    """Enough turning points: the request stands; one short: two oscillations; short
    of the skipped one: it is analysed, unless it was left out for a reason of its own;
    too few even so: the request stands (the caller refuses)."""
    every = lambda s, n=9: n - s  # noqa: E731 (every turning point resolved)
    assert coarse_window(9, every, 1, 6) == CoarseWindow(1, 6)
    assert coarse_window(6, lambda s: 6 - s, 1, 6).least == MIN_COARSE_TURNING_POINTS
    assert coarse_window(6, lambda s: 6 - s, 1, 6).skip == 1
    lacking = coarse_window(4, lambda s: 4 - s, 1, 6)
    assert (lacking.skip, lacking.least) == (0, MIN_COARSE_TURNING_POINTS)
    assert "skipped after the release analysed too" in lacking.note
    assert coarse_window(4, lambda s: 4 - s, 1, 6, keep_skip=True) == CoarseWindow(1, 6)
    assert coarse_window(3, lambda s: 3 - s, 1, 6) == CoarseWindow(1, 6)
    # the resolved count decides as well as the found one
    assert coarse_window(9, lambda s: 3, 1, 6) == CoarseWindow(1, 6)
    assert coarse_window(9, lambda s: 4, 1, 6).least == MIN_COARSE_TURNING_POINTS


def _viscous_velocity(steps: float, placement: float, zeta: float = 0.005):
    """A viscous decay at 10 kHz (32.6 Hz, from 2 mm, 0.1 s of rest, 3 s in motion: the
    swing falls to 5 % of itself), its velocity alone rounded to 1/``steps`` of its
    swing on levels shifted by ``placement`` of a step."""
    w = 2 * math.pi * 32.6
    wd = w * math.sqrt(1 - zeta**2)
    t = np.arange(0, 3.1, 1e-4)
    s = np.clip(t - 0.1, 0.0, None)
    v = np.where(t >= 0.1, -2e-3 * w * w / wd * np.exp(-zeta * w * s) * np.sin(wd * s), 0.0)
    q = np.ptp(v) / steps
    return t, (np.round(v / q + placement) - placement) * q, q


@pytest.mark.parametrize("placement", [-0.45, -0.3, 0.0, 0.45])
def test_a_velocity_alone_fading_into_its_steps_is_answered_before_its_rounding(placement):
    """The velocity alone rounded to a tenth of its first swing, which decays to a
    twentieth: near the end it swings over a step or two, and its integral's turning
    points, the rounding's (its mean over a cycle changes with the swing), broke the
    half period: the record was refused at -0.3. The analysis ends, with a FadeWarning
    and a ShortAnalysisWarning that says why, at a turning point whose swing the
    velocity still resolves (four steps or so), after twenty turning points or more."""
    from bayestribo.errors import FadeWarning

    t, v, q = _viscous_velocity(10.0, placement)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, None, v)
    assert any(issubclass(w.category, FadeWarning) for w in caught)
    short = [str(w.message) for w in caught if issubclass(w.category, ShortAnalysisWarning)]
    assert all("fades" in m or f"steps of {q:.3g}" in m for m in short)
    w = 2 * math.pi * 32.6
    swing = 2 * w * 2e-3 * np.exp(-0.005 * w * (decay.peaks.t[-1] - 0.1)) / q  # 2ω|Y|
    assert swing > 3.0
    assert len(decay.peaks) >= 20


def test_the_swing_end_is_where_a_period_last_holds_the_steps():
    v = np.round(np.exp(-np.arange(400) / 100.0) * 4 * np.sin(np.arange(400) / 3.0))
    end = swing_end(v, 1.0, 6 * np.pi, 4.0)
    assert end is not None
    assert np.ptp(v[end - 19 : end]) >= 3.5 and np.ptp(v[end : end + 19]) < 3.5
    assert swing_end(np.sin(np.arange(100.0)), 0.1, 6.0, 4.0) is None  # to the end
    with pytest.raises(ValueError, match="step"):
        swing_end(v, 0.0, 6.0, 4.0)


@pytest.mark.parametrize("placement", [-0.3, 0.25])
def test_a_coarse_record_without_two_oscillations_is_refused_saying_what_it_lacks(placement):
    """Two and a half steps across the swing: three or four turning points stand two
    steps out, and fewer than two oscillations of them swing a step or more about the
    equilibrium. The refusal names the step, the last turning point that stands out and
    its time, the two oscillations a coarse record is analysed on, and how many it has
    (an earlier message asked for 7 and said nothing of the two oscillations)."""
    t, x, v, (qx, _), _ = coarse_record(steps=2.5, placement=placement)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(RecordingError) as told:
            energy_decay(t, x, v)
    said = str(told.value)
    assert f"quantised in steps of {qx:.3g}" in said
    assert re.search(r"the swings after turning point \d+ \(t = [0-9.]+ s\) hold fewer", said)
    assert f"analysed on {MIN_COARSE_TURNING_POINTS} turning points at least" in said
    kept = int(re.search(r"about the equilibrium: (\d+) here", said).group(1))
    assert kept < MIN_COARSE_TURNING_POINTS
