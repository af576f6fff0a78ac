"""Feeny-Liang successive-peak decrement (Eq. 20-21) against exact responses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_estimators_signals import F_HZ, exact_peaks, exact_signal, sampled

from bayestribo.errors import RecordingError
from bayestribo.estimators import feeny_liang
from bayestribo.estimators._common import velocity_peak_factor
from bayestribo.model.scaling import Rig
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
    if len(pk) < 4:
        return
    est = feeny_liang(pk)
    # Eq. 20-21 are exact for the piecewise solution: only rounding remains
    assert est.zeta == pytest.approx(zeta, rel=1e-7)
    assert est.friction_displacement == pytest.approx(mu, abs=1e-9 * y0)
    est1 = feeny_liang(pk, p=1)
    assert est1.zeta == pytest.approx(zeta, rel=1e-7)


def test_printed_eq21_sign_is_a_misprint():
    pk = exact_peaks(10.0, 0.02, 0.03)
    y = pk.value
    # as printed: ln((-Y_2p - Y_2p+1)/(Y_0 + Y_1)) has a negative argument
    assert (-y[2] - y[3]) / (y[0] + y[1]) < 0
    # corrected: the sums decay by exp(-2πpβ)
    beta = 0.02 / math.sqrt(1 - 0.02**2)
    assert (y[2] + y[3]) / (y[0] + y[1]) == pytest.approx(math.exp(-2 * math.pi * beta))


@pytest.mark.parametrize("zeta", [0.001, 0.05, 0.2])
def test_velocity_peak_factor_matches_dense_exact_velocity(zeta):
    # one half-cycle of the exact velocity from Y_0 = 1 without friction: its extremum
    # is -K Y_0 (Eq. 17 maximised), K = exp(-β atan(1/β))
    w = math.sqrt(1 - zeta**2)
    tau = np.linspace(0, math.pi / w, 200_001)
    _, yp = exact_signal(tau, 1.0, zeta, 0.0)
    beta = zeta / w
    # dense grid: the extremum is flat, sampling error ~ (Δτ)² ≈ 2.5e-10
    assert -yp.min() == pytest.approx(velocity_peak_factor(beta), rel=1e-8)


# regimes: (ζ, μ_k, Y_0) with many (>= 30) or few (~10) turning points
REGIMES = [
    (0.0236, 0.0294, 10.0),
    (0.001, 0.01, 10.0),
    (0.01, 0.0, 10.0),
    (0.1, 0.1, 10.0),
    (0.05, 0.05, 3.0),
]


@pytest.mark.parametrize(("zeta", "mu", "y0"), REGIMES)
@pytest.mark.parametrize("kind", ["displacement", "velocity"])
def test_sampled_noise_free_signals(zeta, mu, y0, kind):
    t, x, v = sampled(zeta, mu, y0)
    pk = find_peaks(t, x if kind == "displacement" else v, kind=kind)
    est = feeny_liang(pk)
    # sub-sample peak values: relative bias ~3e-4 (cancels in β) plus the kink term
    # 0.05 μ²/|Y| at the smallest peaks; bound 1e-3 ζ + 1e-4 on ζ (the kink term over
    # n ~ 10 half-cycles: 0.05·0.1²/(0.2·10π) ≈ 8e-5) and 5e-3 μ + 1e-5 Y_0 on x_c
    assert abs(est.zeta - zeta) <= 1e-3 * zeta + 1e-4
    assert abs(est.friction_displacement - mu) <= 5e-3 * mu + 1e-5 * y0
    # Ω from the peak spacing (no rig given)
    assert est.details["omega"] == pytest.approx(2 * math.pi * F_HZ, rel=1e-3)


def test_rig_gives_mu_k_from_friction_displacement():
    # ℓ = N/k: with x in metres, μ_k = x_c k / N
    rig = Rig(natural_frequency_Hz=F_HZ, mass_kg=0.035, load_N=0.31)
    ell = rig.scaling().length_scale
    pk0 = exact_peaks(10.0, 0.0236, 0.0294)
    pk = Peaks(t=pk0.t / rig.omega, value=pk0.value * ell)
    est = feeny_liang(pk, rig)
    assert est.mu_k == pytest.approx(0.0294, rel=1e-7)
    assert est.friction_displacement == pytest.approx(0.0294 * ell, rel=1e-7)


def test_noisy_standard_errors_are_statistically_consistent():
    # 200 noisy copies of exact peaks: the spread of ζ matches the reported SE
    pk0 = exact_peaks(10.0, 0.01, 0.02)
    rng = np.random.default_rng(11)
    sigma = 0.005
    zs, ses = [], []
    for _ in range(200):
        pk = Peaks(t=pk0.t, value=pk0.value + sigma * rng.standard_normal(len(pk0)))
        e = feeny_liang(pk)
        zs.append(e.zeta)
        ses.append(e.zeta_se)
    # unbiased within 4 standard errors of the mean of 200
    assert abs(np.mean(zs) - 0.01) < 4 * np.std(zs) / math.sqrt(200)
    # the Jacobian SE treats the sums as independent (they are): ratio within 25 %
    # (sampling error of a standard deviation from 200 draws is 5 %)
    assert np.std(zs) == pytest.approx(np.mean(ses), rel=0.25)


def test_errors():
    pk = exact_peaks(10.0, 0.02, 0.03)
    with pytest.raises(RecordingError, match="at least 4 peaks"):
        feeny_liang(Peaks(t=pk.t[:3], value=pk.value[:3]))
    with pytest.raises(RecordingError, match="p must be an integer"):
        feeny_liang(pk, p=0)
    with pytest.raises(RecordingError, match="needs at least 202 peaks"):
        feeny_liang(pk, p=100)
    bad = pk.value.copy()
    bad[2:4] = -bad[2:4]  # sums of opposite sign
    with pytest.raises(RecordingError, match="not positive"):
        feeny_liang(Peaks(t=pk.t, value=bad), p=1)
