"""Records whose swings are a few times their noise a sample, many samples a period.

A seismometer at 10 Hz with an 8.9 s period holds 89 samples a period; its swings of
0.05-0.2 V stand a few times over its 0.005-0.014 V of noise a sample, short of the
ten noise standard deviations a raw turning point must stand out by. Such records were
refused ("found 0 usable extrema", "no motion found"); they are analysed averaged in
bins of consecutive samples (``bayestribo/signal/binning.py``). The records here are
simulated independently of the package: the closed form of a linear oscillator with
viscous damping and Coulomb friction, half cycle by half cycle (0.11 Hz, 10 Hz, white
noise). ``benchmarks/binned_records.py`` measures the coverage over seeds
(``results/binned_records.json``).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import bayestribo
from bayestribo.errors import BinnedRecordWarning, RecordingError
from bayestribo.io.run import Run
from bayestribo.signal.binning import (
    BINNED_PERIOD_SAMPLES,
    MIN_BINNED_SAMPLES,
    bin_gain,
    bin_size,
    binned,
)
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.peaks import estimate_noise

FREQUENCY, RATE, AMPLITUDE = 0.11, 10.0, 0.1


def _record(
    zeta: float, x_c: float, cycles: float, noise: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and displacement [arbitrary] of a free decay from a turning point of
    ``AMPLITUDE`` at t = -0.7 s, each half cycle the damped oscillation about its centre
    ±x_c (the friction opposing the motion), stuck once a turning point is within x_c;
    white noise of sd ``noise`` seeded by ``seed``."""
    omega = 2.0 * math.pi * FREQUENCY
    omega_d = omega * math.sqrt(1.0 - zeta * zeta)
    half = math.pi / omega_d
    t = np.arange(0.0, cycles / FREQUENCY, 1.0 / RATE)
    x = np.empty(t.size)
    x0, t0 = AMPLITUDE, -0.7
    while t0 <= t[-1]:
        if abs(x0) <= x_c:
            x[t >= t0] = x0
            break
        centre = math.copysign(x_c, x0)
        inside = (t >= t0) & (t < t0 + half)
        s = t[inside] - t0
        x[inside] = centre + (x0 - centre) * np.exp(-zeta * omega * s) * (
            np.cos(omega_d * s) + zeta * omega / omega_d * np.sin(omega_d * s)
        )
        x0 = centre - (x0 - centre) * math.exp(-zeta * omega * half)
        t0 += half
    return t, x + np.random.default_rng(seed).normal(0.0, noise, t.size)


def test_the_bin_leaves_twenty_samples_a_period_and_64_in_all():
    assert bin_size(89.0, 600) == 89 // BINNED_PERIOD_SAMPLES == 7
    assert bin_size(89.0, 200) == 200 // MIN_BINNED_SAMPLES == 3
    assert bin_size(23.9, 10_000) is None  # no bin of 2 leaves 12 samples a period
    assert bin_size(89.0, 100) is None  # 64 binned samples need 128
    assert bin_size(float("nan"), 600) is None


def test_a_sinusoid_binned_keeps_its_amplitude_and_its_times():
    per = 89.0
    t = np.arange(0.0, 80.0, 0.1)
    x = 0.3 + np.sin(2.0 * math.pi * t / (per * 0.1) + 0.4)
    tb, (xb, nothing), bins = binned(t, (x, None), 4, per)
    assert nothing is None and bins.size == 4 and tb.size == t.size // 4
    assert np.allclose(np.diff(tb), 0.4) and tb[0] == pytest.approx(0.15)
    # the oscillation's gain through the bin divided out: the sinusoid at the bins'
    # mean times (the constant is divided by the gain too, 3e-3 of it)
    expect = 0.3 / bins.gain + np.sin(2.0 * math.pi * tb / (per * 0.1) + 0.4)
    assert np.max(np.abs(xb - expect)) < 1e-9
    assert bins.gain == pytest.approx(bin_gain(4, per)) and 0.996 < bins.gain < 0.997


def test_binned_white_noise_is_white_and_smaller_by_the_root_of_the_bin():
    rng = np.random.default_rng(3)
    noise = rng.normal(0.0, 1.0, 400_000)
    t = np.arange(noise.size) * 0.1
    _, (nb,), bins = binned(t, (noise,), 4, 1e9)  # a period so long the gain is 1
    assert bins.gain == pytest.approx(1.0, abs=1e-12)
    # sd 1/2 within its sampling error (±0.22 % at 100 000 means, 5 sd)
    assert abs(np.std(nb) - 0.5) < 5 * 0.5 / math.sqrt(2 * nb.size)
    lag1 = float(np.corrcoef(nb[:-1], nb[1:])[0, 1])
    assert abs(lag1) < 5 / math.sqrt(nb.size)
    assert estimate_noise(nb) == pytest.approx(0.5, rel=0.02)


def test_a_noisy_record_of_many_samples_a_period_is_answered_binned():
    """Refused before (swings within 10 noise sd a sample): 6 cycles of a viscous
    decay, its noise 8 % of the first amplitude."""
    t, x = _record(0.07, 0.0, 6.0, 0.008, seed=2)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        decay = energy_decay(t, x)
    binned_said = [str(w.message) for w in said if w.category is BinnedRecordWarning]
    assert len(binned_said) == 1
    assert "bins of 7 consecutive samples" in binned_said[0]
    assert "on its raw samples the record was refused" in binned_said[0]
    assert np.allclose(np.diff(decay.t), 0.7) and len(decay.peaks) >= 6
    # the noise measured from the bins: the simulated sd a sample over √7 (the
    # oscillation's gain of 0.991 divided out)
    expect = 0.008 / math.sqrt(7) / bin_gain(7, 1 / FREQUENCY / 0.1)
    assert decay.noise.displacement == pytest.approx(expect, rel=0.25)


def test_the_fit_of_a_binned_record_holds_the_truth():
    t, x = _record(0.07, 0.002, 6.0, 0.006, seed=5)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        result = bayestribo.fit(Run(t, x, None, {"length_unit": "arbitrary"}))
    assert any(w.category is BinnedRecordWarning for w in said)
    assert result.converged
    lo, hi = result.interval("zeta")
    assert lo <= 0.07 <= hi
    lo, hi = result.interval("friction_displacement")
    assert lo <= 0.002 <= hi


def test_a_decay_buried_in_the_noise_is_refused_binned_too_and_says_both():
    """Noise 20 % of the first amplitude: the bins leave its swings within the noise."""
    t, x = _record(0.07, 0.0, 6.0, 0.02, seed=2)
    with pytest.raises(RecordingError) as refused:
        energy_decay(t, x)
    text = str(refused.value)
    assert text.startswith("release: no motion found")
    assert "averaged in bins of 7 samples (92 a period), the record is refused too" in text


def test_few_samples_a_period_are_not_binned():
    """At 30 samples a period no bin leaves 20: the refusal is the raw record's."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 120.0, 1.0 / 3.3)
    x = 0.0005 * np.sin(2.0 * math.pi * FREQUENCY * t) + rng.normal(0.0, 0.01, t.size)
    with pytest.raises(RecordingError) as refused:
        energy_decay(t, x)
    assert "bins" not in str(refused.value)


@pytest.mark.validation
@pytest.mark.parametrize("x_c", [0.0, 0.002])
def test_binned_intervals_cover_over_seeds(x_c):
    """Over 10 seeds (noise 5 % of the first amplitude, which main refused in most) at
    least 8 are answered, and the answers' 95 % intervals hold ζ and x_c together in all
    but two (at a joint coverage of 90 %, three misses or more in 10 have probability
    0.07)."""
    answered = missed = 0
    for seed in range(10):
        t, x = _record(0.07, x_c, 6.0, 0.005, seed=100 + seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                result = bayestribo.fit(Run(t, x, None, {"length_unit": "arbitrary"}))
            except RecordingError:
                continue
        answered += 1
        lo, hi = result.interval("zeta")
        flo, fhi = result.interval("friction_displacement")
        missed += not (lo <= 0.07 <= hi and flo <= x_c <= fhi)
    assert answered >= 8 and missed <= 2
