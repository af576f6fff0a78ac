"""The public steps of the single-run pipeline: fit is exactly their composition."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo import simulate
from bayestribo.inference import (
    SamplerSettings,
    build_posterior,
    fit,
    prepare,
    sample,
    summarise,
)


@pytest.fixture(scope="module")
def run():
    return simulate(seed=11)


def test_fit_is_the_composition_of_the_four_steps(run):
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=1000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = fit(run, seed=4, max_steps=1000)
        rng = np.random.default_rng(4)
        prepared = prepare(run)  # its Monte Carlo seeded from the data, not from rng
        posterior = build_posterior(prepared.data, friction=prepared.contact)
        sampled = sample(posterior, prepared.decay, settings=settings, seed=rng)
        steps = summarise(prepared, sampled, seed=rng, recorded_seed=4)
    for name in ("zeta", "mu_k", "mu_s", "y0"):
        np.testing.assert_array_equal(
            whole.idata.posterior[name].values, steps.idata.posterior[name].values
        )
    np.testing.assert_array_equal(
        whole.idata.posterior_predictive["pi"].values, steps.idata.posterior_predictive["pi"].values
    )
    assert whole.idata.posterior.attrs["seed"] == steps.idata.posterior.attrs["seed"] == 4


def test_a_fixed_parameter_is_reported_at_its_value(run):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, seed=2, max_steps=600, fixed={"zeta": 0.0})
    assert np.all(result.idata.posterior["zeta"].values == 0.0)
    assert result.idata.posterior["mu_k"].values.std() > 0
