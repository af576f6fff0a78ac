"""The surrogate of a law whose domain ends inside a prior's support
(inference/surrogate.py, ``_domain_priors``): ``quadratic+hysteretic`` cannot move at
η < 0 (a friction ηA below zero), though η's prior runs to -0.45. Its design about a
centre within one node distance of η = 0 used to leave the nodes below zero without Π,
no surrogate was built, and the exact posterior was sampled (13× the default fit on
the AppStat HarmOsc1 record)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from _law_recording import law_recording

from bayestribo import fit
from bayestribo.inference import pipeline
from bayestribo.inference.priors import Uniform
from bayestribo.inference.start import maximum_a_posteriori
from bayestribo.inference.surrogate import SurrogateLikelihood, surrogate_posterior

OMEGA = 2 * math.pi * 32.6
MASS, LOAD = 0.035, 0.31
ELL = LOAD / (MASS * OMEGA**2)
LAW = "quadratic+hysteretic"


@pytest.fixture(scope="module")
def drag_run():
    """Quadratic drag alone (η = 0 in truth) from an independent solve_ivp simulation."""
    return law_recording(
        lambda v: (0.004 / ELL) * v * abs(v),
        x0=1.5e-3,
        duration_s=1.5,
        sample_rate_Hz=2000.0,
        seed=4,
    )


@pytest.fixture(scope="module")
def near_the_edge(drag_run):
    """The exact posterior of ``quadratic+hysteretic`` on ``drag_run`` and a centre at
    its optimum's c₂ and y0 with η at a fifth of its node distance above zero."""
    prepared = pipeline.prepare(drag_run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law=LAW)
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    scale = 2.0 * np.sqrt(np.diag(cov))
    eta = posterior.names.index("eta")
    scale[eta] = max(scale[eta], 1e-4)
    centre = theta.copy()
    centre[eta] = 0.2 * scale[eta]
    return posterior, centre, scale, eta


def test_the_law_does_not_move_below_zero_eta(near_the_edge):
    posterior, centre, scale, eta = near_the_edge
    below = centre.copy()
    below[eta] = -0.5 * scale[eta]
    assert np.isfinite(posterior(centre[None])[0])
    assert posterior(below[None])[0] == -np.inf
    assert isinstance(posterior.priors["eta"], Uniform)
    assert posterior.priors["eta"].low < below[eta]  # inside the prior's support


def test_the_surrogate_prior_ends_at_the_domain_edge(near_the_edge):
    posterior, centre, scale, eta = near_the_edge
    sur = surrogate_posterior(posterior, centre, scale)
    assert sur is not None and isinstance(sur.likelihood, SurrogateLikelihood)
    prior = sur.priors["eta"]
    # the edge is η = 0 (μ(A) = ηA): found within the search's resolution, s/32768,
    # from inside; the prior's upper bound is the exact posterior's
    assert 0.0 <= prior.low <= scale[eta] / 32768.0
    assert prior.high == posterior.priors["eta"].high
    # every other prior is the exact posterior's
    for name in posterior.names:
        if name != "eta":
            assert sur.priors[name] == posterior.priors[name]
    # the exact posterior is zero where the surrogate's is, and finite on its support
    rng = np.random.default_rng(2)
    rows = np.repeat(centre[None], 64, axis=0)
    rows[:, eta] = rng.uniform(-scale[eta], 2.0 * scale[eta], size=64)
    exact, approx = posterior(rows), sur(rows)
    assert np.array_equal(np.isfinite(approx), np.isfinite(exact) & (rows[:, eta] >= prior.low))
    inside = np.isfinite(approx)
    assert 16 < inside.sum() < 64


def test_the_fit_keeps_its_surrogate_at_the_edge(drag_run):
    # the optimum's η lies within a node distance of zero: the fit used to sample the
    # exact posterior (6.6 s of CPU against 0.5 s), now its first surrogate passes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(drag_run, law=LAW, seed=1)
    checked = result.diagnostics["surrogate"]
    assert checked is not None and checked["passed"] and not checked["corrected"]
    assert checked["attempt"] == 1
    assert result.converged
    # its draws stay inside the law's domain, and pile against its edge, the truth
    # η = 0 (their lowest 2.5 % within half a posterior sd of it)
    eta = result.samples("eta")
    assert np.all(eta >= 0.0)
    assert np.quantile(eta, 0.025) < 0.5 * np.std(eta)
