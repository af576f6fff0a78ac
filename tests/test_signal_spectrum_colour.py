"""The band-level colour test: white noise's level judged against its χ² range."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal

from bayestribo.signal.spectrum import COLOUR_FACTOR, WHITE_P, band_bounds, noise_spectrum

FS = 5000.0
PERIOD = 1 / 32.6
REST = 462  # the rest a 0.1 s lead-in at 5 kHz leaves (benchmarks/laws.py)


def _white_rests(count: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    return [noise_spectrum([rng.normal(size=REST)], FS, period_s=PERIOD) for _ in range(count)]


def test_bounds_are_skewed_low_for_few_degrees_of_freedom():
    lower, upper = band_bounds(0.3576)  # a 0.1 s rest at 5 kHz
    # the earlier symmetric test, four standard errors in log: exp(∓1.43)
    assert lower < math.exp(-4 * 0.3576) - 0.09
    assert upper > math.exp(4 * 0.3576) - 1.2
    # many degrees of freedom: close to the symmetric normal bounds
    lower, upper = band_bounds(0.02)
    assert lower == pytest.approx(math.exp(-4 * 0.02), abs=2e-3)
    assert upper == pytest.approx(math.exp(4 * 0.02), abs=2e-3)


def test_a_white_rest_with_a_low_band_level_is_not_called_coloured():
    # seed 1436: a white rest whose band level is 0.238 of the white level, which the
    # symmetric four-standard-error test called coloured (its increment variances,
    # from the spectrum, were then 3-4 times too small)
    rest = np.random.default_rng(1436).standard_normal(REST)
    spectrum = noise_spectrum([rest], FS, period_s=PERIOD)
    assert spectrum.colour_ratio < 0.24
    assert abs(math.log(spectrum.colour_ratio)) > 4.0 * spectrum.band_rel_se
    assert not spectrum.coloured


@pytest.mark.validation  # a false-alarm rate over many simulated rests
def test_white_rests_are_not_called_coloured_by_their_band_level():
    # the Ljung-Box test keeps its own 1e-3 (3 expected here): the rests it passes are
    # judged by their band level alone; the symmetric test flagged 2 of them (1 in 700)
    spectra = [s for s in _white_rests(3000, seed=32) if s.white_p >= WHITE_P]
    assert len(spectra) > 2950
    assert sum(s.coloured for s in spectra) == 0


def test_filtered_noise_in_a_long_rest_is_still_coloured():
    # a 500 Hz low-pass at 5 kHz: the band level is twice the white level's
    rng = np.random.default_rng(5)
    sos = scipy.signal.butter(4, 500.0, fs=FS, output="sos")
    rest = scipy.signal.sosfilt(sos, rng.standard_normal(20_000))[1000:]
    spectrum = noise_spectrum([rest], FS, period_s=PERIOD)
    assert spectrum.colour_ratio > COLOUR_FACTOR
    assert spectrum.coloured


@pytest.mark.parametrize(
    ("rel_se", "false_alarm", "word"),
    [
        (0.0, 1e-3, "rel_se"),
        (math.nan, 1e-3, "rel_se"),
        (0.1, 0.0, "false_alarm"),
        (0.1, 1.0, "false_alarm"),
    ],
)
def test_band_bounds_name_the_bad_argument(rel_se, false_alarm, word):
    with pytest.raises(ValueError, match=word):
        band_bounds(rel_se, false_alarm)
