"""The public steps of the single-run pipeline: fit is exactly their composition."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from bayestribo import simulate
from bayestribo.inference import (
    build_posterior,
    fit,
    prepare,
    sample,
    summarise,
)
from bayestribo.inference.sampling import FIT_INDEPENDENCE, FIT_INDEPENDENCE_LIMIT
from bayestribo.inference.spec import FitSpec


@pytest.fixture(scope="module")
def run():
    return simulate(seed=11)


def test_fit_is_the_composition_of_the_four_steps(run):
    settings = FitSpec(max_steps=1000).sampler_settings()  # the fit's own rule
    assert settings.independence == FIT_INDEPENDENCE and settings.debias
    assert settings.independence_limit == FIT_INDEPENDENCE_LIMIT
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


def _no_refit(*_):
    raise AssertionError("a nested law refitted on a run with friction and drag")


def test_fit_is_the_composition_of_the_named_stages(run):
    # prepare, build, start, sample, check, the boundaries, summarise: each stage's typed
    # output is the next one's input, and together they are fit to the bit
    from bayestribo.inference.boundary import boundary_mixture
    from bayestribo.inference.chains import sample_from
    from bayestribo.inference.checks import FitChecks, check
    from bayestribo.inference.start import Start, find_start
    from bayestribo.inference.summarising import Summary, summary

    settings = FitSpec(max_steps=1000).sampler_settings()  # the fit's own rule
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = fit(run, seed=4, max_steps=1000)
        rng = np.random.default_rng(4)
        prepared = prepare(run)
        posterior = build_posterior(prepared.data, friction=prepared.contact)
        start = find_start(posterior, prepared.decay)
        sampled = sample_from(start, settings=settings, seed=rng)
        checks = check(prepared, sampled)
        # the default law's boundaries (no friction, no viscous damping): improbable on
        # this run, so nothing is refitted and the draws are the sample's, recorded
        mixed, boundary = boundary_mixture(checks.sampled, _no_refit, _no_refit)
        assert mixed is checks.sampled and boundary is not None and not boundary["mixed"]
        summarised = summary(prepared, sampled, seed=rng, recorded_seed=4, checks=checks)
        summarised = dataclasses.replace(
            summarised, record=summarised.record.replace(boundary=boundary)
        )
    assert isinstance(start, Start) and isinstance(checks, FitChecks)
    assert isinstance(summarised, Summary)
    assert sampled.posterior is start.posterior  # the second pass's, as sampled
    steps = summarised.result()
    for name in ("zeta", "mu_k", "mu_s", "y0"):
        np.testing.assert_array_equal(
            whole.idata.posterior[name].values, steps.idata.posterior[name].values
        )
    # what the fit records, but the spec and the time that fit adds (and ArviZ's own
    # attributes, such as when the InferenceData was made: no record of the fit)
    whole_record, steps_record = whole.record, steps.record
    expected = {
        k: v
        for k, v in whole_record.to_attrs().items()
        if k not in whole_record.extra and k not in ("spec_json", "seconds")
    }
    got = {k: v for k, v in steps_record.to_attrs().items() if k not in steps_record.extra}
    assert got == expected


def test_a_fixed_parameter_is_reported_at_its_value(run):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, seed=2, max_steps=600, fixed={"zeta": 0.0})
    assert np.all(result.idata.posterior["zeta"].values == 0.0)
    assert result.idata.posterior["mu_k"].values.std() > 0
