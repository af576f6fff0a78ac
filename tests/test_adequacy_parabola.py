"""The peaks of the predictive check: least-squares parabolas through each extremum's
samples, one stacked solve, against numpy.polyfit peak by peak."""

from __future__ import annotations

import numpy as np

from bayestribo.adequacy.predictive import _parabola_peak


def _by_polyfit(x: np.ndarray, values: np.ndarray) -> np.ndarray:
    out = np.empty(values.shape[:2])
    for p in range(x.shape[0]):
        xp = x[p] - x[p].mean()
        a, b, c = np.polyfit(xp, values[:, p, :].T, 2)
        vertex = -b / (2 * a)
        ok = (a < 0) & (vertex >= xp[0]) & (vertex <= xp[-1])
        out[:, p] = np.where(ok, c - b**2 / (4 * a), values[:, p, :].max(axis=1))
    return out


def test_each_peak_is_its_own_parabolas_vertex_or_its_largest_sample() -> None:
    rng = np.random.default_rng(3)
    draws, peaks, samples = 50, 12, 9
    x = np.sort(rng.uniform(-1e-3, 1e-3, (peaks, samples)), axis=1) + rng.uniform(0, 5, (peaks, 1))
    centre = x.mean(axis=1, keepdims=True) + rng.uniform(-3e-4, 3e-4, (peaks, 1))
    values = 1.0 - 4e5 * (x - centre) ** 2 + rng.normal(0, 1e-3, (draws, peaks, samples))
    values[:, 2, :] *= -1  # opens upwards: the largest sample
    values[:, 5, :] = 1.0 - 4e5 * (x[5] - x[5, -1] - 1e-3) ** 2  # vertex beyond the span
    got = _parabola_peak(x, values)
    np.testing.assert_allclose(got, _by_polyfit(x, values), rtol=1e-12, atol=0)
    np.testing.assert_array_equal(got[:, 2], values[:, 2, :].max(axis=1))
    np.testing.assert_array_equal(got[:, 5], values[:, 5, :].max(axis=1))
