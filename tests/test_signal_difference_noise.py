"""The white noise of a channel read off its second differences, motion and all."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from bayestribo.signal.difference_noise import difference_noise

SIGMA = 5e-4


def _decay(samples_per_period: float, periods: float = 6.0) -> np.ndarray:
    """A decaying swing of 0.3 (a velocity [m/s]) with a kink at every zero crossing."""
    n = round(samples_per_period * periods)
    phase = 2.0 * math.pi * np.arange(n) / samples_per_period
    # friction's reversal: the acceleration jumps where the velocity changes sign
    return 0.3 * np.exp(-0.05 * phase) * np.sin(phase) + 2e-4 * np.abs(np.sin(phase))


@pytest.mark.parametrize("seed", range(6))
def test_white_noise_on_a_swing_of_600_sigma_is_read_within_5_percent(seed: int) -> None:
    rng = np.random.default_rng(seed)
    v = _decay(1000.0) + rng.normal(0.0, SIGMA, 6000)
    sigma = difference_noise(v, 1000.0)
    assert sigma is not None
    assert abs(sigma / SIGMA - 1.0) < 0.05


def test_the_swing_read_as_noise_where_few_samples_a_period_is_refused() -> None:
    # 20 samples a period: the sinusoid's second differences are 10 % of its swing
    rng = np.random.default_rng(1)
    v = _decay(20.0, periods=60.0) + rng.normal(0.0, SIGMA, 1200)
    assert difference_noise(v, 20.0) is None


def test_a_noise_coloured_at_the_sample_scale_is_refused() -> None:
    # a one-pole low-pass at a tenth of the sample rate: white noise's second differences
    # shrink 40-fold, so its σ read off them would be far too small
    rng = np.random.default_rng(2)
    a = math.exp(-2.0 * math.pi * 0.1)
    noise = lfilter([1.0 - a], [1.0, -a], rng.normal(0.0, 5.0 * SIGMA, 6000))
    assert difference_noise(_decay(1000.0) + noise, 1000.0) is None


def test_a_channel_on_coarse_steps_is_refused() -> None:
    rng = np.random.default_rng(3)
    v = np.round((_decay(1000.0) + rng.normal(0.0, SIGMA, 6000)) / (20 * SIGMA)) * 20 * SIGMA
    assert difference_noise(v, 1000.0) is None


def test_a_short_record_is_refused() -> None:
    rng = np.random.default_rng(4)
    assert difference_noise(rng.normal(0.0, SIGMA, 400), 1000.0) is None
