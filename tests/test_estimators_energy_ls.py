"""Least squares on the retrograde energy integral Π (Eq. 39-42), both models."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_estimators_signals import F_HZ, sampled

from bayestribo.errors import RecordingError
from bayestribo.estimators import energy_data, energy_least_squares
from bayestribo.model.scaling import Rig

RIG = Rig(natural_frequency_Hz=F_HZ)  # Ω known, ℓ = 1 signal unit


def _scales(zeta, mu, y0):
    # total damping as an equivalent ζ (friction acts like ζ_eq = 2μ/(πY), Eq. 32) and
    # total dissipation as an equivalent friction (viscous like μ_eq = πζY/2)
    return zeta + 2 * mu / (math.pi * y0), mu + math.pi * zeta * y0 / 2


# The simulated records start at rest at a turning point, with no release transient:
# nothing to skip (skip_oscillations=0), so every turning point counts.
S0 = {"skip_oscillations": 0}

# (ζ, μ_k, Y_0): many oscillations, few oscillations, friction- and viscous-dominated
REGIMES = [
    (0.0236, 0.0294, 10.0),  # the paper's values, 36 turning points
    (0.001, 0.01, 10.0),  # light damping, 300 turning points
    (0.01, 0.0, 10.0),  # viscous only
    (0.1, 0.1, 10.0),  # heavy, 10 turning points
    (0.01, 0.1, 1.0),  # friction-dominated, 6 turning points
    (0.001, 0.1, 1.0),  # friction only in practice, 6 turning points
]


@pytest.mark.parametrize(("zeta", "mu", "y0"), REGIMES)
def test_exact_model_recovers_noise_free_runs(zeta, mu, y0):
    t, x, v = sampled(zeta, mu, y0)
    est = energy_least_squares(t, x, v, rig=RIG, model="exact", **S0)
    z_scale, m_scale = _scales(zeta, mu, y0)
    # the model is exact; what remains is locating the start (first turning point,
    # sub-sample) and the end of motion (rest tail) on a 2 kHz grid (Δτ = 0.1) and the
    # trapezoidal Π: 1 % of the total damping scale bounds both parameters
    assert abs(est.zeta - zeta) <= 0.01 * z_scale
    assert abs(est.friction_displacement - mu) <= 0.01 * m_scale
    # Δ_Π (Eq. 42) small against Π(0) for an exact model
    assert est.delta_pi < 1e-3 * est.details["y0"] ** 2 / (4 * z_scale)


@pytest.mark.parametrize(("zeta", "mu", "y0"), REGIMES[:4])
def test_averaged_model_within_its_approximation_error(zeta, mu, y0):
    # many oscillations (>= 10 turning points): the averaged law (Eq. 32-41) neglects
    # the ripple of E within each cycle, a relative error O(ζ_tot); bound 5 % of
    # the damping scales
    t, x, v = sampled(zeta, mu, y0)
    est = energy_least_squares(t, x, v, rig=RIG, model="averaged", **S0)
    z_scale, m_scale = _scales(zeta, mu, y0)
    assert abs(est.zeta - zeta) <= 0.05 * z_scale
    assert abs(est.friction_displacement - mu) <= 0.05 * m_scale
    assert "Eq. 41 corrected" in est.notes


def test_exact_beats_averaged_with_few_oscillations():
    # 6 turning points, μ_k/Y_0 = 0.1: the averaging assumption (slow amplitude) fails
    t, x, v = sampled(0.01, 0.1, 1.0)
    ex = energy_least_squares(t, x, v, rig=RIG, model="exact", **S0)
    av = energy_least_squares(t, x, v, rig=RIG, model="averaged", **S0)
    assert abs(ex.zeta - 0.01) < abs(av.zeta - 0.01) / 10
    assert ex.delta_pi < av.delta_pi / 10


@pytest.mark.parametrize("signals", ["x", "v", "xv"])
def test_displacement_only_velocity_only_and_both(signals):
    t, x, v = sampled(0.0236, 0.0294, 10.0, noise_x=1e-3, noise_v=1e-3 * 2 * math.pi * F_HZ)
    est = energy_least_squares(
        t, x if "x" in signals else None, v if "v" in signals else None, rig=RIG, model="exact"
    )
    # noise 1e-3 of Y_0 = 10 on ~2000 samples: Π averages it away; the derived signal
    # (Savitzky-Golay derivative, trapezoidal integral) adds ~1e-3 relative
    assert est.zeta == pytest.approx(0.0236, rel=0.01)
    assert est.friction_displacement == pytest.approx(0.0294, rel=0.02)


def test_without_rig_frequency_comes_from_the_record():
    t, x, v = sampled(0.0236, 0.0294, 10.0)
    est = energy_least_squares(t, x, v, model="exact")
    # Ω = π/(T_half √(1-ζ²)) with the weighted peak-time slope: ~1e-4
    assert est.details["omega"] == pytest.approx(2 * math.pi * F_HZ, rel=1e-3)
    assert est.zeta == pytest.approx(0.0236, rel=0.01)


def test_offset_and_lead_in_are_handled():
    t, x, _ = sampled(0.0236, 0.0294, 10.0, offset=5.0, lead=0.3)
    est = energy_least_squares(t, x, None, rig=RIG, model="exact")
    assert est.zeta == pytest.approx(0.0236, rel=0.01)
    assert est.friction_displacement == pytest.approx(0.0294, rel=0.02)


def test_rig_with_load_reports_mu_k():
    rig = Rig(natural_frequency_Hz=F_HZ, mass_kg=0.035, load_N=0.31)
    ell = rig.scaling().length_scale
    t, x, v = sampled(0.0236, 0.0294, 10.0)
    est = energy_least_squares(t, x * ell, v * ell, rig=rig, model="exact")
    assert est.mu_k == pytest.approx(0.0294, rel=0.01)
    assert est.friction_displacement == pytest.approx(0.0294 * ell, rel=0.01)
    assert est.mu_k_se is not None and est.mu_k_se > 0


def test_covariance_is_a_covariance():
    t, x, v = sampled(0.0236, 0.0294, 10.0, noise_x=1e-3, seed=4)
    est = energy_least_squares(t, x, v, rig=RIG)
    cov = est.covariance
    assert cov.shape == (3, 3)
    np.testing.assert_allclose(cov, cov.T, rtol=1e-10, atol=0)
    assert np.all(np.linalg.eigvalsh(cov) > 0)
    assert est.parameters == ("zeta", "mu", "y0")
    assert est.zeta_se == pytest.approx(math.sqrt(cov[0, 0]))


def test_energy_data_pi_is_the_retrograde_integral():
    t, x, v = sampled(0.01, 0.0, 10.0)
    d = energy_data(t, x, v, rig=RIG)
    # without friction E decays as e^{-2ζτ} on average: Π(0) ≈ E(0)/(2ζ) (1 %: ripple
    # and the finite window, which ends after ~12/ζ)
    assert d.pi[0] == pytest.approx(d.energy[0] / (2 * 0.01), rel=0.02)
    assert d.pi[-1] == 0.0
    assert np.all(np.diff(d.pi) <= 1e-12)


def test_errors():
    t, x, _ = sampled(0.02, 0.03, 10.0)
    with pytest.raises(RecordingError, match="displacement x or a velocity v"):
        energy_least_squares(t)
    with pytest.raises(ValueError, match="model"):
        energy_least_squares(t, x, model="quadratic")
    with pytest.raises(ValueError, match="max_points"):
        energy_least_squares(t, x, max_points=3)
    t_bad = t.copy()
    t_bad[100] = t_bad[99]
    with pytest.raises(RecordingError, match="increasing"):
        energy_least_squares(t_bad, x)


def test_eq40_41_corrected_constant_against_quadrature():
    # Π_app(τ) = ∫_τ^{T_f} ½(Λe^{-ζθ} - Γ)² dθ (Eq. 35, 38, 39); the fit relies on the
    # closed form Eq. 40 with A = (Γ²/ζ)(3/4 - ½ ln(Γ/Λ)), not the printed 3/4 - ln(Γ/Λ)
    from scipy.integrate import quad

    from bayestribo.model import averaged_pi

    zeta, mu, y0 = 0.0236, 0.0294, 10.0
    gam = 2 * mu / (math.pi * zeta)
    lam = y0 + gam
    t_f = -math.log(gam / lam) / zeta
    for tau in (0.0, 50.0, 0.9 * t_f):
        ref = quad(lambda s: 0.5 * (lam * math.exp(-zeta * s) - gam) ** 2, tau, t_f)[0]
        assert float(averaged_pi(tau, y0, zeta, mu)) == pytest.approx(ref, rel=1e-9)
        eq40 = (
            lam**2 / (4 * zeta) * math.exp(-2 * zeta * tau)
            - lam * gam / zeta * math.exp(-zeta * tau)
            - gam**2 / 2 * tau
        )
        a_corrected = gam**2 / zeta * (0.75 - 0.5 * math.log(gam / lam))
        a_printed = gam**2 / zeta * (0.75 - math.log(gam / lam))
        assert eq40 + a_corrected == pytest.approx(ref, rel=1e-9)
        assert abs(eq40 + a_printed - ref) > 1.0
