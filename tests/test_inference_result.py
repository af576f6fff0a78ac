"""A fit's result as a user reads it: every quantity summarised with what it is, a table,
and the sampler's statistics in the InferenceData where ArviZ looks for them."""

from __future__ import annotations

import warnings

import emcee
import numpy as np
import pytest

from bayestribo.errors import BayestriboError
from bayestribo.inference import FitResult
from bayestribo.inference.flatness import bound_interval
from bayestribo.inference.quantities import QuantitySummary, unit_words
from bayestribo.summary import ParameterSummary


@pytest.fixture(scope="module")
def result(short_fit) -> FitResult:
    return short_fit  # conftest.py: a converged fit, read back from NetCDF


def test_summary_covers_every_quantity_of_the_posterior(result: FitResult) -> None:
    summary = result.summary()
    assert set(summary) == set(result.idata.posterior.data_vars)
    assert "mu_s_ratio" in summary  # sampled, and in az.summary: in ours too
    for name, s in summary.items():
        assert isinstance(s, QuantitySummary) and isinstance(s, ParameterSummary)
        assert s.name == name and s.symbol and s.label and s.unit
    # sampled: exactly the coordinates with a prior of their own
    assert {n for n, s in summary.items() if s.sampled} == set(result.priors.names)
    assert summary["mu_s_ratio"].symbol == "μ_s/μ_k" and summary["mu_s_ratio"].unit == "1"
    assert summary["friction_displacement"].unit == "m"


def test_summary_honours_prob_and_refuses_a_bad_one(result: FitResult) -> None:
    narrow, wide = result.summary(0.5)["zeta"], result.summary(0.99)["zeta"]
    assert wide.low < narrow.low < narrow.high < wide.high and narrow.prob == 0.5
    # a bound (μ_s/μ_k flat up to the stop) starts at its prior's end at any probability
    narrow, wide = result.summary(0.5)["mu_s_ratio"], result.summary(0.99)["mu_s_ratio"]
    assert narrow.kind == wide.kind == "bound"
    assert wide.low == narrow.low == 1.0 < narrow.high < wide.high and narrow.prob == 0.5
    with pytest.raises(BayestriboError, match="prob"):
        result.summary(95)


def test_r_hat_is_arviz_and_ess_is_emcee_over_the_walkers(result: FitResult) -> None:
    import arviz as az

    summary = result.summary()
    n_walkers = result.diagnostics["n_walkers"]
    for name in ("zeta", "mu_s_ratio", "friction_displacement"):
        draws = np.asarray(result.idata.posterior[name])  # (chain, draw), step-major
        expected_rhat = float(az.rhat(result.idata, var_names=[name])[name])
        assert summary[name].r_hat == pytest.approx(expected_rhat, rel=1e-12)
        # emcee's own estimator of τ over each ensemble's walkers, summed over ensembles
        n_chain, n_draw = draws.shape
        expected_ess = 0.0
        for c in range(n_chain):
            chain = draws[c].reshape(n_draw // n_walkers, n_walkers, 1)
            tau = emcee.autocorr.integrated_time(chain, quiet=True)[0]
            expected_ess += n_draw / tau
        assert summary[name].ess == pytest.approx(expected_ess, rel=1e-6)


def test_to_dataframe_has_one_row_per_quantity_with_its_interval(result: FitResult) -> None:
    frame = result.to_dataframe(prob=0.9)
    summary = result.summary(0.9)
    assert list(frame.index) == list(summary) and frame.index.name == "name"
    for column in ("symbol", "label", "unit", "mean", "sd", "median", "low", "high"):
        assert column in frame.columns
    for column in ("ess", "r_hat", "prob", "kind", "sampled", "unit_words"):
        assert column in frame.columns
    for name in frame.index:
        draws = result.samples(name)
        # the equal-tailed interval's quantiles as the summary defines them: (1 - 0.9)/2
        # is 0.04999999999999999, not 0.05, which moves an interpolated quantile by an ulp
        low, median, high = np.quantile(draws, [(1 - 0.9) / 2, 0.5, (1 + 0.9) / 2])
        if summary[name].kind == "bound":  # not constrained: from the prior's end
            low, high = bound_interval(result, name, draws, 0.9)
        row = frame.loc[name]
        assert (row["low"], row["median"], row["high"]) == (low, median, high)
        assert row["mean"] == np.mean(draws) and row["prob"] == 0.9
        assert row["unit_words"] == unit_words(summary[name].unit)
    assert frame.loc["zeta", "unit_words"] == "dimensionless"
    assert summary["mu_s_ratio"].kind == "bound" and summary["zeta"].kind == "posterior"
    assert frame.loc["mu_s_ratio", "kind"] == "bound" and frame.loc["zeta", "kind"] == "posterior"


def test_sample_stats_hold_the_samplers_log_probability_and_acceptance(result: FitResult) -> None:
    import arviz as az

    stats = result.idata.sample_stats
    posterior = result.idata.posterior
    n_chain, n_draw = posterior["zeta"].shape
    n_walkers = result.diagnostics["n_walkers"]
    assert stats["lp"].shape == (n_chain, n_draw)
    assert np.all(np.isfinite(stats["lp"]))
    assert stats["acceptance_fraction"].dims == ("chain", "walker")
    assert stats["acceptance_fraction"].shape == (n_chain, n_walkers)
    # the walkers' fractions average to the one the diagnostics report
    assert float(stats["acceptance_fraction"].mean()) == pytest.approx(
        result.diagnostics["acceptance_fraction"], rel=1e-12
    )
    walker = np.asarray(stats["walker_index"])
    # step-major: all walkers of one step, then the next step from walker 0
    np.testing.assert_array_equal(walker[0, : 2 * n_walkers], np.tile(np.arange(n_walkers), 2))
    # ArviZ reads the group
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        table = az.summary(result.idata, group="sample_stats", var_names=["lp"], round_to="none")
    assert table.loc["lp", "mean"] == pytest.approx(float(stats["lp"].mean()))


def _no_load_result() -> FitResult:
    """A fit-shaped result of a run without load or mass, in an unstated length unit:
    the sampled friction is the friction displacement (draws made up, no sampler)."""
    import json

    from bayestribo.inference.assemble import FitDraws

    rng = np.random.default_rng(0)
    draws = {
        "zeta": rng.normal(0.01, 1e-3, (2, 400)),
        "mu_s_ratio": 1.0 + rng.exponential(0.5, (2, 400)),
        "friction_displacement": rng.normal(0.02, 2e-4, (2, 400)),
        "static_friction_displacement": rng.normal(0.11, 1e-2, (2, 400)),
        "y0": rng.normal(-1.29, 2e-4, (2, 400)),
    }
    priors = {
        "zeta": {"type": "Uniform", "low": 0.0, "high": 0.3},
        "mu_k": {"type": "Uniform", "low": 0.0, "high": 0.3},
        "mu_s_ratio": {"type": "Uniform", "low": 1.0, "high": 10.0},
        "y0": {"type": "Normal", "mu": -1.29, "sigma": 0.01},
    }
    attrs = {
        "law": "viscous+coulomb",
        "priors_json": json.dumps(priors),
        "metadata_json": json.dumps({"length_unit": "arbitrary"}),
        "diagnostics_json": json.dumps({"converged": True, "n_walkers": 8}),
    }
    empty = np.zeros((2, 400, 1))
    return FitResult(
        draws=FitDraws(draws, attrs, empty, np.zeros((1, 10, 3)), np.zeros(3), np.arange(3.0))
    )


def test_diagnostics_the_sampler_could_not_define_read_undefined_in_the_text() -> None:
    # a chain that did not move leaves τ, the ESS and R-hat undefined (None): the text
    # says so, where formatting None raised TypeError after the fit had run
    import json

    result = _no_load_result()
    result.attrs["diagnostics_json"] = json.dumps(
        {
            "converged": False,
            "reasons": ["a chain did not move"],
            "n_walkers": 8,
            "autocorr_time_max": None,
            "ess_min": None,
            "rhat_max": float("nan"),
        }
    )
    text = result.to_text()
    assert "τ_max undefined, ESS_min undefined, R-hat_max undefined" in text


def test_without_a_load_the_friction_displacement_is_the_sampled_friction() -> None:
    result = _no_load_result()
    summary = result.summary()
    assert summary["friction_displacement"].sampled and summary["mu_s_ratio"].unit == "1"
    assert {n for n, s in summary.items() if s.sampled} == {
        "zeta",
        "friction_displacement",
        "mu_s_ratio",
        "y0",
    }
    assert result.units()["friction_displacement"] == "signal length unit"
    frame = result.to_dataframe()
    assert frame.loc["static_friction_displacement", "unit_words"] == "signal unit"
    table = result._table_lines(0.95)
    row = next(line for line in table if line.startswith("friction as displacement x_c"))
    assert "signal unit" in row


def test_a_law_fitted_at_no_loss_has_an_undefined_slope_in_the_text() -> None:
    # a law whose ΔE(A) is zero at every swing (fitted at its null: η = 0 on a record
    # whose energy hardly falls) has no log-log slope, stored as None: the text says
    # "undefined" where formatting None raised TypeError after `--law auto` had run
    import json

    result = _no_load_result()
    result.attrs["shape_agreement_json"] = json.dumps(
        {
            "max_percent": 100.0,
            "rms_percent": 100.0,
            "max_z": 0.5,
            "law_slope": None,
            "measured_slope": 1.0,
            "measured_slope_se": None,
            "same_shape": True,
        }
    )
    text = result.to_text()
    assert "ΔE(A) of the law as A^undefined, of the turning points as A^1.00 ± undefined" in text
    row = {
        "max_percent": 100.0,
        "law_slope": None,
        "measured_slope": 1.0,
        "measured_slope_se": 17.0,
        "same_shape": True,
    }
    lines = result._departure_lines({"hysteretic": row, "viscous": {**row, "law_slope": 2.0}})
    assert any("hysteretic" in line and "slope undefined" in line for line in lines)
    assert any("viscous" in line and "slope 2.00" in line for line in lines)
