"""Non-successive peaks (Eq. 22-25) against exact responses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_estimators_signals import exact_peaks, sampled

from bayestribo.errors import RecordingError
from bayestribo.estimators import nonsuccessive_peaks
from bayestribo.estimators.nonsuccessive import default_pq, eq24_friction
from bayestribo.signal.peaks import Peaks, find_peaks


@settings(max_examples=60, deadline=None)
@given(
    zeta=st.floats(0.001, 0.1),
    mu=st.floats(0.0, 0.1),
    y0=st.floats(2.0, 20.0),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_exact_turning_points_give_exact_parameters(zeta, mu, y0, sign):
    pk = exact_peaks(sign * y0, zeta, mu)
    if len(pk) < 5:
        return
    est = nonsuccessive_peaks(pk)
    # Eq. 24-25 (corrected) are exact for the piecewise solution; Brent to 1e-12
    assert est.zeta == pytest.approx(zeta, rel=1e-6)
    assert est.friction_displacement == pytest.approx(mu, abs=1e-8 * y0)


def test_eq23_as_printed_is_wrong_for_p_above_1():
    zeta, mu = 0.02, 0.03
    pk = exact_peaks(10.0, zeta, mu)
    beta = zeta / math.sqrt(1 - zeta**2)
    y = pk.value
    for p in (1, 2, 5):
        # corrected Eq. 24 returns μ_k exactly
        assert eq24_friction(beta, y[0], y[2 * p], p) == pytest.approx(mu, rel=1e-9)
        printed = (
            1
            + math.exp(-2 * math.pi * beta)
            + 2 * sum(math.exp(-i * math.pi * beta) for i in range(1, 2 * p))
        )
        mu_printed = (y[0] * math.exp(-2 * math.pi * p * beta) - y[2 * p]) / printed
        if p == 1:  # Eq. 22: the two forms agree
            assert mu_printed == pytest.approx(mu, rel=1e-9)
        else:
            assert abs(mu_printed / mu - 1) > 1e-3


@pytest.mark.parametrize(("p", "q"), [(1, 2), (3, 10), (10, 4)])
def test_any_p_q_pair(p, q):
    pk = exact_peaks(10.0, 0.0236, 0.0294)
    est = nonsuccessive_peaks(pk, p=p, q=q)
    assert est.zeta == pytest.approx(0.0236, rel=1e-6)
    assert est.details["p"] == min(p, q) and est.details["q"] == max(p, q)


@pytest.mark.parametrize(
    ("zeta", "mu", "y0"), [(0.0236, 0.0294, 10.0), (0.001, 0.01, 10.0), (0.1, 0.1, 10.0)]
)
@pytest.mark.parametrize("kind", ["displacement", "velocity"])
def test_sampled_noise_free_signals(zeta, mu, y0, kind):
    t, x, v = sampled(zeta, mu, y0)
    pk = find_peaks(t, x if kind == "displacement" else v, kind=kind)
    est = nonsuccessive_peaks(pk)
    # three peaks only: their sub-sample bias (see test_signal_peaks) enters without
    # averaging; bound 2e-3 ζ + 2e-4 on ζ and 5e-3 μ + 2e-5 Y_0 on x_c
    assert abs(est.zeta - zeta) <= 2e-3 * zeta + 2e-4
    assert abs(est.friction_displacement - mu) <= 5e-3 * mu + 2e-5 * y0


def test_no_root_is_reported_clearly():
    # Y_0 = 1, Y_2 = Y_4 = 0.5 (p = 1, q = 2): Eq. 25 reduces to
    # (r² - 0.5)(1 + r²) = r⁴ - 0.5, i.e. r² = 0: only β = ∞, no root in [-0.05, 1]
    t = np.arange(5.0)
    value = np.array([1.0, -0.7, 0.5, -0.5, 0.5])
    with pytest.raises(RecordingError, match="no root"):
        nonsuccessive_peaks(Peaks(t=t, value=value))


def test_standard_errors_are_statistically_consistent():
    pk0 = exact_peaks(10.0, 0.01, 0.02)
    sigma = 0.003
    rng = np.random.default_rng(7)
    zs, ses, ms, mses = [], [], [], []
    for _ in range(200):
        pk = Peaks(
            t=pk0.t,
            value=pk0.value + sigma * rng.standard_normal(len(pk0)),
            value_noise=sigma,
        )
        e = nonsuccessive_peaks(pk)
        zs.append(e.zeta)
        ses.append(e.zeta_se)
        ms.append(e.friction_displacement)
        mses.append(e.friction_displacement_se)
    # linear propagation is accurate for small noise: spread within 20 % of the SE
    # (sampling error of a standard deviation from 200 draws: 5 %)
    assert np.std(zs) == pytest.approx(np.mean(ses), rel=0.2)
    assert np.std(ms) == pytest.approx(np.mean(mses), rel=0.2)
    assert abs(np.mean(zs) - 0.01) < 4 * np.std(zs) / math.sqrt(200)


def test_bad_arguments():
    pk = exact_peaks(10.0, 0.02, 0.03)
    with pytest.raises(RecordingError, match="p and q must differ"):
        nonsuccessive_peaks(pk, p=2, q=2)
    with pytest.raises(RecordingError, match="integer >= 1"):
        nonsuccessive_peaks(pk, p=0, q=2)
    with pytest.raises(RecordingError, match="needs more than"):
        nonsuccessive_peaks(pk, p=1, q=500)
    with pytest.raises(RecordingError, match="at least 5"):
        default_pq(4)
