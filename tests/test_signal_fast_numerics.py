"""The fast numerics of the signal analysis against slow, obviously right references.

Each routine that was made faster for large records (a 1 MHz record of a million
samples) is held to the computation it replaced: the whole zero-padded transform, the
pseudo-inverse projections of copied blocks, scipy's Welch estimate, numpy's polyfit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.signal

from bayestribo.signal import clipping, motion, period, spectrum

_rng = np.random.default_rng(5)


def _decay(n: int, rate: float = 10_000.0) -> tuple[np.ndarray, np.ndarray]:
    """A noisy free decay of 32.6 Hz with an offset, a drift and a 50 Hz line."""
    t = np.arange(n) / rate + 0.37
    x = (
        1.5e-3
        + 2e-6 * t
        + 1e-3 * np.exp(-2.0 * t) * np.cos(2.0 * math.pi * 32.6 * t)
        + 3e-7 * np.sin(2.0 * math.pi * 50.0 * t)
        + 1e-7 * _rng.standard_normal(n)
    )
    return t, x


@pytest.mark.parametrize("n", [1000, 4097, 30_001])
def test_the_fine_bins_are_those_of_the_padded_transform(n: int) -> None:
    _, x = _decay(n)
    d = np.diff(x)
    d -= d.mean()
    fine = period.PADDING * (1 << math.ceil(math.log2(x.size)))
    reference = np.abs(np.fft.rfft(d, fine))
    bins = np.array([1, 7, fine // 8 + 3, fine // 2 - 1, fine // 2])
    got = period._fine_spectrum(d, bins, fine)
    np.testing.assert_allclose(got, reference[bins], rtol=1e-9, atol=1e-12 * reference.max())


def test_the_period_is_the_padded_spectrums_peak() -> None:
    """The period from the coarse spectrum and the fine bins about its peak is the one
    of the whole padded spectrum's peak, interpolated alike."""
    t, x = _decay(20_000)
    d = np.diff(x)
    d -= d.mean()
    n = 1 << math.ceil(math.log2(4 * x.size))
    spec = np.abs(np.fft.rfft(d, n))
    spec[0] = 0.0
    k = int(np.argmax(spec))
    a, b, c = np.log(spec[k - 1 : k + 2])
    expected = n * (t[1] - t[0]) / (k + 0.5 * (a - c) / (a - 2 * b + c))
    assert period._spectral_period(t, x) == pytest.approx(expected, rel=1e-12)


def _block_fits_by_pseudo_inverse(t, s, starts, size, omega):
    tt = t[:size] - t[0]
    tt = tt - tt.mean()
    basis1 = np.column_stack([np.ones(size), tt])
    basis2 = np.column_stack([basis1, np.cos(omega * tt), np.sin(omega * tt)])
    rows = s[starts[:, None] + np.arange(size)[None, :]]
    res1 = rows - (rows @ np.linalg.pinv(basis1).T) @ basis1.T
    res2 = rows - (rows @ np.linalg.pinv(basis2).T) @ basis2.T
    return np.mean(res1 * res1, axis=1), np.mean(res2 * res2, axis=1)


@pytest.mark.parametrize("omega", [0.0, 2.0 * math.pi * 32.6])
def test_the_block_fits_are_the_pseudo_inverse_projections(omega: float, monkeypatch) -> None:
    t, x = _decay(12_000)
    size = 613
    starts = np.r_[np.arange(0, x.size - size + 1, size // 2), x.size - size]
    monkeypatch.setattr(motion, "_CHUNK", 3 * size)  # several chunks of blocks
    var1, var2 = motion._block_fits(t, x, starts, size, omega)
    ref1, ref2 = _block_fits_by_pseudo_inverse(t, x, starts, size, omega)
    np.testing.assert_allclose(var1, ref1, rtol=1e-9)
    if omega:
        np.testing.assert_allclose(var2, ref2, rtol=1e-6)


@pytest.mark.parametrize(
    ("n", "nper", "nfft"), [(5000, 1024, 1024), (5000, 5000, 8192), (777, 100, 128), (64, 64, 65)]
)
def test_welch_is_scipys(n: int, nper: int, nfft: int, monkeypatch) -> None:
    _, x = _decay(n)
    monkeypatch.setattr(spectrum, "_WELCH_CHUNK", 2 * nper)  # several batches of segments
    _, reference = scipy.signal.welch(
        x, 1e4, window="hann", nperseg=nper, nfft=nfft, detrend="constant"
    )
    got = spectrum.welch(x, 1e4, nper, nfft)
    np.testing.assert_allclose(got, reference, rtol=1e-9, atol=1e-12 * reference.max())


def test_the_curvatures_are_polyfits() -> None:
    t, x = _decay(8000)
    half_width = 25
    index = np.array([3, 40, 1000, 2500, 7990, 7999])  # the ends cut some windows
    got = clipping._curvatures(t, x, index, half_width)
    for j, i in enumerate(index):
        w = min(half_width, i, x.size - 1 - i)
        if w < 1:
            assert np.isnan(got[j])
            continue
        c2 = np.polyfit(t[i - w : i + w + 1] - t[i], x[i - w : i + w + 1], 2)[0]
        assert got[j] == pytest.approx(abs(2.0 * c2), rel=1e-8)
