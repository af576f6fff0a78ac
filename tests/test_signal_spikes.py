"""Isolated spikes (:mod:`bayestribo.signal.spikes`) on closed-form decays.

The signals are damped cosines written out here, not the package's simulator. A spike
is one sample moved by 30 % of the release amplitude, as a sensor's dropout does.
"""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.signal.spikes import bridged, find_spikes


def _decay(samples_per_period: float, periods: float, zeta: float, phase: float) -> np.ndarray:
    wt = np.arange(round(periods * samples_per_period)) * 2.0 * np.pi / samples_per_period
    return 1e-3 * np.exp(-zeta * wt) * np.cos(wt + phase)


@pytest.mark.parametrize("half_cycle", [0, 1, 6, 25])
@pytest.mark.parametrize("sign", [-1.0, 1.0])
def test_a_spike_where_the_signal_moves_fastest_is_found(half_cycle: int, sign: float) -> None:
    # 32.6 Hz at 10 kHz (307 samples a period), white noise of 1.5 µm, a spike at a zero
    # crossing: there the signal changes by 20 µm a sample, and the running median,
    # shifted by one sample's change about the spike, once hid it behind a curvature 50×
    # too large
    spp = 10_000 / 32.6
    at = round((half_cycle / 2 + 0.25) * spp)
    x = _decay(spp, 20, 0.004, 0.0)
    x += 1.5e-6 * np.random.default_rng(half_cycle).standard_normal(x.size)
    spiked = x.copy()
    spiked[at] += sign * 3e-4
    assert find_spikes(spiked).tolist() == [at]
    assert find_spikes(x).size == 0
    np.testing.assert_allclose(bridged(spiked, np.array([at]))[at], x[at], atol=5e-5)


@pytest.mark.parametrize("samples_per_period", [5, 8, 10, 20, 300])
@pytest.mark.parametrize("zeta", [0.0, 0.05])
@pytest.mark.parametrize("phase", [0.0, 0.3, 1.1])
def test_a_smooth_decay_has_no_spikes_at_any_sample_rate(
    samples_per_period: int, zeta: float, phase: float
) -> None:
    x = _decay(samples_per_period, 40, zeta, phase)
    assert find_spikes(x).size == 0
    assert find_spikes(np.round(x / 5e-5) * 5e-5).size == 0  # on 20 steps a swing


def test_two_spikes_a_few_samples_apart_are_both_found() -> None:
    x = _decay(300, 10, 0.01, 0.0)
    spiked = x.copy()
    spiked[[400, 406]] += 3e-4
    assert find_spikes(spiked).tolist() == [400, 406]
