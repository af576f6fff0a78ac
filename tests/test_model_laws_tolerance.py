"""The integrator's steps set by the error a caller allows (``Law.pi_grid``'s
``tolerance``), and the likelihood's tolerance from its increments' noise
(``PiLikelihood.integrator_tolerance``): the error against fixed fine steps stays
within a few times what is allowed, the usual steps are kept where nothing more is
allowed, and a noisy record's residuals move by a few hundredths of their sd."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo.inference import pipeline
from bayestribo.inference.likelihood import INTEGRATOR_SHARE
from bayestribo.inference.start import maximum_a_posteriori
from bayestribo.model.laws import get_law
from bayestribo.model.laws.integrator import BASE_ERROR

TAU = np.linspace(0.0, 60.0, 41)
END = 60.0
#: Drags and frictions across the damping the integrator meets (as in its notes).
CASES = [
    ("quadratic", {"c2": 0.005}),
    ("quadratic", {"c2": 0.3}),
    ("power", {"zeta_alpha": 0.01, "alpha": 2.0}),
    ("power", {"zeta_alpha": 0.08, "alpha": 1.4}),
    ("power", {"zeta_alpha": 0.2, "alpha": 2.0}),
    ("coulomb+quadratic", {"mu_k": 0.002, "mu_s_ratio": 1.5, "c2": 0.1}),
    ("viscous+quadratic", {"zeta": 0.02, "c2": 0.05}),
    ("coulomb+power", {"mu_k": 0.001, "mu_s_ratio": 2.0, "zeta_alpha": 0.08, "alpha": 0.9}),
]


def _pi(law: str, values: dict[str, float], **kwargs) -> np.ndarray:
    """Π of one parameter set, the record ending in motion at ``END``."""
    lw = get_law(law)
    vals = {n: np.array([values.get(n, 0.0)]) for n in lw.parameter_names}
    return lw.pi_grid(TAU, vals, np.array([1.0]), 0.0, END, **kwargs)[0]


@pytest.mark.parametrize(("law", "values"), CASES)
def test_the_error_stays_within_a_few_times_the_tolerance(law, values):
    reference = _pi(law, values, steps=1024)
    usual = _pi(law, values)
    # the usual steps: about BASE_ERROR of Π(0) (measured 3e-10 to 5e-9)
    assert np.max(np.abs(usual - reference)) < 3.0 * BASE_ERROR * reference[0]
    for tolerance in (1e-8, 1e-7, 1e-5):
        loose = _pi(law, values, tolerance=tolerance)
        error = np.max(np.abs(loose - reference)) / reference[0]
        # the scheme's error model (∝ ζ_e² h⁴ at the peak speed) holds to within 2.4x
        # on these laws (a power law of α = 2 at 32 steps)
        assert error < 3.0 * tolerance, (tolerance, error)


@pytest.mark.parametrize(("law", "values"), CASES[:4])
def test_no_tolerance_above_the_usual_error_keeps_the_usual_steps(law, values):
    usual = _pi(law, values)
    for tolerance in (None, 1e-15, BASE_ERROR):
        assert np.array_equal(_pi(law, values, tolerance=tolerance), usual)


def test_a_loose_tolerance_takes_fewer_steps_down_to_the_floor_of_32():
    law, values = "power", {"zeta_alpha": 0.2, "alpha": 2.0}
    usual = _pi(law, values)
    looser = _pi(law, values, tolerance=1e-7)
    # steps changed: not the usual numbers ...
    assert not np.array_equal(looser, usual)
    # ... and however much is allowed, never fewer than 32 a half cycle in the record:
    # the record ends in motion (no sum past it), so that is 32 fixed steps' Π
    floor = _pi(law, values, tolerance=1.0)
    np.testing.assert_allclose(floor, _pi(law, values, steps=-32), rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("bad", [0.0, -1e-6, math.nan, math.inf])
def test_a_tolerance_that_is_not_a_positive_number_is_refused(bad):
    with pytest.raises(ValueError, match="tolerance must be a positive number"):
        _pi("quadratic", {"c2": 0.05}, tolerance=bad)


@pytest.fixture(scope="module")
def noisy_quadratic():
    """A quadratic drag and viscous damping (solve_ivp), recorded with 1 % of the
    swing's noise on the displacement and 0.05 % on the velocity (HarmOsc-like)."""
    omega = 2 * math.pi * 32.6
    ell = 0.31 / (0.035 * omega**2)
    run = law_recording(
        lambda v: 2 * 0.004 * omega * v + (0.02 / ell) * v * abs(v),
        x0=1.5e-3,
        duration_s=1.0,
        sample_rate_Hz=2000.0,
        noise_x=1.5e-5,
        noise_v=1.5e-4,
        seed=7,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = pipeline.prepare(run, seed=1)
    return prepared


def test_the_likelihoods_tolerance_is_its_share_of_the_smallest_noise(noisy_quadratic):
    posterior = pipeline.build_posterior(noisy_quadratic.data, law="viscous+quadratic")
    lik = posterior.likelihood
    data = lik.data
    m = data.variance.size
    expected = INTEGRATOR_SHARE * math.sqrt(data.variance.min() / m) / data.increments.sum()
    assert lik.integrator_tolerance == pytest.approx(expected, rel=1e-12)
    assert lik.integrator_tolerance > BASE_ERROR  # the noise allows fewer steps here
    # a coarse model of fixed steps keeps them
    assert replace(lik, steps=32).integrator_tolerance is None
    # correlated noise: the covariance's smallest eigenvalue, below the smallest variance
    corr = 0.9 ** np.abs(np.subtract.outer(np.arange(m), np.arange(m)))
    correlated = replace(lik, data=replace(data, correlation=corr))
    sd = np.sqrt(data.variance)
    smallest = np.linalg.eigvalsh(sd[:, None] * corr * sd[None, :])[0]
    assert correlated.integrator_tolerance == pytest.approx(
        INTEGRATOR_SHARE * math.sqrt(smallest / m) / data.increments.sum(), rel=1e-9
    )
    assert correlated.integrator_tolerance < lik.integrator_tolerance


def test_the_residuals_move_by_a_few_hundredths_of_their_sd(noisy_quadratic):
    posterior = pipeline.build_posterior(noisy_quadratic.data, law="viscous+quadratic")
    lik = posterior.likelihood
    theta, cov, _ = maximum_a_posteriori(posterior, noisy_quadratic.decay)
    rng = np.random.default_rng(3)
    rows = rng.multivariate_normal(theta, 4.0 * cov, size=40)
    rows[:, :2] = np.abs(rows[:, :2])  # ζ, c2 >= 0
    params = posterior.physical(rows)["params"]
    loose = lik.model_increments(params)
    usual = replace(lik, steps=0)
    object.__setattr__(usual, "integrator_tolerance", None)  # the usual steps
    strict = usual.model_increments(params)
    assert not np.array_equal(loose, strict)  # fewer steps were taken
    moved = (loose - strict) / np.sqrt(lik.data.variance)
    # each Π within ~INTEGRATOR_SHARE/√m of the smallest sd (a few times that at most):
    # the bias of all m increments together, the most it can move the posterior (in
    # its sds), within 6 times the share
    assert np.max(np.linalg.norm(moved, axis=1)) < 6.0 * INTEGRATOR_SHARE
