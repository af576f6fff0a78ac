"""The halves' z from posterior draws, its Monte Carlo error carried
(bayestribo.inference.halves_statistic)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from bayestribo.inference.halves_statistic import (
    CLEAR_SDS,
    SwingDifference,
    swing_difference,
    threshold,
    verdict_is_clear,
)


def test_z_carries_each_means_monte_carlo_variance():
    rng = np.random.default_rng(0)
    d1 = rng.normal(1.0, 0.2, (300, 3))
    d2 = rng.normal(0.5, 0.4, (500, 3))
    got = swing_difference(d1, d2, 300.0, 125.0)
    # written out by hand: s1²(1 + 1/n1) + s2²(1 + 1/n2) under the difference of means
    v1, v2 = np.var(d1, axis=0, ddof=1), np.var(d2, axis=0, ddof=1)
    expected = (d1.mean(0) - d2.mean(0)) / np.sqrt(v1 * (1 + 1 / 300) + v2 * (1 + 1 / 125))
    np.testing.assert_allclose(got.z, expected, rtol=1e-12)
    assert got.largest == pytest.approx(np.max(np.abs(expected)), rel=1e-12)
    assert got.p_value == pytest.approx(min(1.0, 6 * scipy.stats.norm.sf(got.largest)))
    # fewer effective draws, a smaller |z|: the means are less certain
    assert np.all(np.abs(swing_difference(d1, d2, 30.0, 12.5).z) < np.abs(got.z))


def test_its_monte_carlo_sd_is_the_spread_of_z_over_fresh_draws():
    # two fixed skewed "posteriors" (lognormal: kurtosis 4.6), z of all their draws the
    # reference; z from 200 draws of each scatters about it by z_mc_sd
    rng = np.random.default_rng(1)
    p1 = np.exp(rng.normal(0.0, 0.3, 200_000))[:, None]
    p2 = 1.55 + np.exp(rng.normal(0.0, 0.3, 200_000))[:, None]
    reference = swing_difference(p1, p2, p1.shape[0], p2.shape[0]).z[0]
    assert 3.0 < abs(reference) < 6.0  # where the sds' own error counts
    errors = []
    for _ in range(2000):
        d1 = p1[rng.integers(0, p1.shape[0], 200)]
        d2 = p2[rng.integers(0, p2.shape[0], 200)]
        got = swing_difference(d1, d2, 200.0, 200.0)
        errors.append((got.z[0] - reference) / got.z_mc_sd[0])
    # 2000 replicates: the sd of the standardised errors to about 2 % (1.6 % sd)
    assert np.std(errors) == pytest.approx(1.0, abs=0.08)
    assert abs(np.mean(errors)) < 0.1


def test_a_verdict_is_clear_only_beyond_its_monte_carlo_error():
    limit = threshold(8, 1e-3)
    assert limit == pytest.approx(scipy.stats.norm.isf(1e-3 / 16))

    def difference(z: float, mc: float) -> SwingDifference:
        return SwingDifference(np.array([z] + [0.0] * 7), np.full(8, mc), abs(z), 1.0)

    assert verdict_is_clear(difference(limit + CLEAR_SDS * 0.1 + 0.01, 0.1), 1e-3)
    assert verdict_is_clear(difference(limit - CLEAR_SDS * 0.1 - 0.01, 0.1), 1e-3)
    assert not verdict_is_clear(difference(limit + 0.2, 0.1), 1e-3)
    assert not verdict_is_clear(difference(limit - 0.2, 0.1), 1e-3)


@pytest.mark.parametrize(
    ("first", "second", "n1", "n2", "field"),
    [
        (np.zeros(5), np.zeros((5, 1)), 5, 5, "first, second"),
        (np.zeros((5, 2)), np.zeros((5, 3)), 5, 5, "first, second"),
        (np.zeros((1, 2)), np.zeros((5, 2)), 5, 5, "first, second"),
        (np.zeros((5, 2)), np.zeros((5, 2)), 1.0, 5, "first_draws, second_draws"),
    ],
)
def test_bad_draws_are_refused_by_name(first, second, n1, n2, field):
    with pytest.raises(ValueError, match=field):
        swing_difference(first, second, n1, n2)


@pytest.mark.validation
def test_weighted_draws_at_the_weighted_limit_scatter_by_their_monte_carlo_sd():
    """Each half's draws from a surrogate shifted by half a posterior sd (importance
    weights' cv about 0.5, up to the halves' limit ``MAX_WEIGHTED_CV``, kept only where
    they hold as ``weights_at`` keeps them), weighted to the exact posterior and counted
    by Kish's number: z scatters about the exact posteriors' z by its Monte Carlo sd;
    the same draws unweighted are off by more than half of it."""
    from bayestribo.inference.correction import MAX_PARETO_K, MAX_WEIGHTED_CV
    from bayestribo.inference.loo import psis

    rng = np.random.default_rng(1)
    sd1, sd2, mean2 = 0.3, 0.4, 1.6
    reference = -mean2 / np.sqrt(sd1**2 + sd2**2)

    def half(mean: float, sd: float) -> tuple[np.ndarray, np.ndarray, float] | None:
        x = rng.normal(mean - 0.5 * sd, sd, 200)
        log_w = scipy.stats.norm.logpdf(x, mean, sd) - scipy.stats.norm.logpdf(
            x, mean - 0.5 * sd, sd
        )
        w = np.exp(log_w - log_w.max())
        k = float(np.ravel(psis(log_w[None], 1.0)[1])[0])
        if not (np.std(w) / np.mean(w) <= MAX_WEIGHTED_CV and k <= MAX_PARETO_K):
            return None
        return x[:, None], w, float(w.sum() ** 2 / np.sum(w * w))

    weighted, unweighted, cvs = [], [], []
    while len(weighted) < 2000:
        first, second = half(0.0, sd1), half(mean2, sd2)
        if first is None or second is None:
            continue
        cvs.append(np.sqrt(first[0].size / first[2] - 1.0))
        got = swing_difference(first[0], second[0], first[2], second[2], (first[1], second[1]))
        weighted.append((got.z[0] - reference) / got.z_mc_sd[0])
        plain = swing_difference(first[0], second[0], first[2], second[2])
        unweighted.append((plain.z[0] - reference) / plain.z_mc_sd[0])
    assert 0.4 < np.median(cvs) <= MAX_WEIGHTED_CV
    # 2000 replicates: the sd to about 1.6 %; the weighted means' own bias (of order
    # 1/n) is a fifth of a Monte Carlo sd
    assert np.std(weighted) == pytest.approx(1.0, abs=0.1)
    assert abs(np.mean(weighted)) < 0.3
    assert abs(np.mean(unweighted)) > 0.5
