"""Mains lines in a short rest: found when there, not invented from white noise."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.signal.spectrum import LINE_RATIO, line_threshold, noise_spectrum

FS = 5000.0
PERIOD = 1 / 32.6


def test_white_rests_of_a_tenth_of_a_second_show_no_line():
    # 0.1 s at 5 kHz: one periodogram, a neighbourhood of a few bins; a ratio of 10 to
    # its median made a "line" of white noise in 12 % of such rests
    rng = np.random.default_rng(2026)
    found = sum(
        bool(noise_spectrum([rng.normal(size=500)], FS, period_s=PERIOD).lines_Hz)
        for _ in range(400)
    )
    assert found <= 2  # 6e-4 expected per rest: 0.24 in 400


@pytest.mark.parametrize("hz", [50.0, 60.0])
def test_a_mains_line_in_a_short_rest_is_still_found(hz):
    rng = np.random.default_rng(7)
    t = np.arange(500) / FS
    rest = rng.normal(size=500) + 2.0 * np.sin(2 * np.pi * hz * t + 0.3)
    spectrum = noise_spectrum([rest], FS, period_s=PERIOD)
    assert spectrum.coloured
    assert len(spectrum.lines_Hz) == 1 and abs(spectrum.lines_Hz[0] - hz) < 5.0


@pytest.mark.parametrize(
    ("averages", "n_near", "n_hood", "rate"), [(1.0, 3, 8, 0.01), (1.5, 2, 6, 2e-3)]
)
def test_the_line_threshold_is_exceeded_by_white_noise_at_its_rate(averages, n_near, n_hood, rate):
    threshold = line_threshold(averages, n_near, n_hood, false_alarm=rate)
    assert threshold > LINE_RATIO  # a coarse PSD needs more than the floor
    rng = np.random.default_rng(11)
    draws = 40_000
    bins = rng.gamma(averages, 1.0 / averages, size=(draws, n_near + n_hood))
    peak = bins[:, :n_near].max(axis=1)
    # the lower middle order statistic, as line_threshold assumes
    background = np.sort(bins[:, n_near:], axis=1)[:, (n_hood + 1) // 2 - 1]
    seen = np.count_nonzero(peak > threshold * background)
    expected = rate * draws
    assert abs(seen - expected) < 4 * np.sqrt(expected)


def test_a_long_rest_keeps_the_fixed_ratio():
    assert line_threshold(50.0, 3, 50) == LINE_RATIO
