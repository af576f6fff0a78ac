"""A law of several terms taken to its optimum from its laws of one term fewer
(``inference/reduction.py``'s ``nested_starts``, ``inference/start.py``'s
``maximum_from_starts``, the comparison's ``_optimise``).

On the bundled run (viscous damping and Coulomb friction) ``viscous+quadratic`` and
``coulomb+quadratic`` misfit by χ² ~ 1e8; the first guesses' multi-start stopped 3.9 and
0.5 of log density below the optimum the least squares reach from ``viscous`` and
``quadratic`` (``coulomb`` and ``quadratic``) at theirs.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import bayestribo.inference.comparison as comparison
from bayestribo.inference.pipeline import prepare
from bayestribo.inference.reduction import nested_start, nested_starts
from bayestribo.inference.start import (
    find_optimum,
    maximum_from,
    maximum_from_starts,
)


@pytest.fixture(scope="module")
def prepared(bundled_runs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare(bundled_runs / "glycerol-N0.31-r1.csv")


@pytest.fixture(scope="module")
def one_term_optima(prepared):
    """The optima of the laws of one term, by coordinate, as the comparison keeps them."""
    optima = {}
    for law in ("viscous", "coulomb", "quadratic"):
        posterior = comparison._posterior(law, prepared.data, "exact", False)
        theta, _, _ = find_optimum(posterior, prepared.decay)
        optima[law] = dict(zip(posterior.names, theta, strict=True))
    return optima


def test_the_starts_are_the_laws_of_one_term_fewer(prepared, one_term_optima):
    starts = nested_starts("viscous+quadratic", prepared, one_term_optima)
    assert starts is not None and len(starts) == 2
    # in the order of the law's terms: without viscous (quadratic's optimum, ζ small),
    # then without quadratic (viscous's optimum, c2 small)
    assert starts[0]["c2"] == one_term_optima["quadratic"]["c2"]
    assert 0.0 < starts[0]["zeta"] < 1e-5
    assert starts[1]["zeta"] == one_term_optima["viscous"]["zeta"]
    assert 0.0 < starts[1]["c2"] < 1e-5
    # the friction a frictionless law lacks starts small, its ratio at 1.2 (the first
    # start: the law without coulomb, quadratic's optimum)
    start = nested_starts("coulomb+quadratic", prepared, one_term_optima)[0]
    assert start["mu_s_ratio"] == 1.2
    assert 0.0 < start["mu_k"] <= 1e-6 * abs(prepared.data.y0)


def test_no_starts_for_one_term_or_a_missing_nested_optimum(prepared, one_term_optima):
    assert nested_starts("quadratic", prepared, one_term_optima) is None
    # coulomb+power: power has no optimum yet
    assert nested_starts("coulomb+power", prepared, one_term_optima) is None
    # three terms need every law of two
    assert nested_starts("viscous+coulomb+quadratic", prepared, one_term_optima) is None


def test_the_best_start_wins_and_one_start_is_maximum_from(prepared, one_term_optima):
    posterior = comparison._posterior("viscous+quadratic", prepared.data, "exact", False)
    starts = nested_starts("viscous+quadratic", prepared, one_term_optima)
    theta, cov, _ = maximum_from_starts(posterior, starts, prepared.decay)
    lp = float(posterior(theta[None])[0])
    each = [
        maximum_from(posterior, np.array([s[n] for n in posterior.names]), prepared.decay)
        for s in starts
    ]
    lps = [float(posterior(t[None])[0]) for t, _, _ in each]
    assert lp == max(lps)
    np.testing.assert_array_equal(theta, each[int(np.argmax(lps))][0])
    assert np.all(np.isfinite(cov))


@pytest.mark.parametrize(("law", "gain"), [("viscous+quadratic", 3.0), ("coulomb+quadratic", 0.3)])
def test_the_nested_starts_beat_the_multi_start_where_it_stops_short(
    prepared, one_term_optima, law, gain
):
    posterior = comparison._posterior(law, prepared.data, "exact", False)
    multi, _, _ = find_optimum(
        posterior, prepared.decay, also_start_at=nested_start(law, prepared, one_term_optima)
    )
    nested, _, _ = maximum_from_starts(
        posterior, nested_starts(law, prepared, one_term_optima), prepared.decay
    )
    lp_multi = float(posterior(multi[None])[0])
    lp_nested = float(posterior(nested[None])[0])
    assert lp_nested >= lp_multi + gain, (lp_nested, lp_multi)


def test_the_comparison_takes_a_law_of_two_terms_from_its_nested_optima(
    prepared, one_term_optima, monkeypatch
):
    # the comparison's optimiser of a law of two terms whose laws of one term have
    # their optima: no multi-start from the first guesses, the best nested optimum
    def no_multi_start(*args, **kwargs):
        raise AssertionError("the first guesses' multi-start was run")

    monkeypatch.setattr(comparison, "find_optimum", no_multi_start)
    at = comparison._optimise("viscous+quadratic", prepared, "exact", False, dict(one_term_optima))
    posterior = at.posterior
    expected, _, _ = maximum_from_starts(
        posterior, nested_starts("viscous+quadratic", prepared, one_term_optima), prepared.decay
    )
    np.testing.assert_array_equal(at.optimum[0], expected)
    # a law of one term still starts from the first guesses
    with pytest.raises(AssertionError, match="multi-start"):
        comparison._optimise("hysteretic", prepared, "exact", False, dict(one_term_optima))


def test_a_start_whose_optimum_has_no_density_leaves_the_others_to_win(
    prepared, one_term_optima, monkeypatch
):
    # the first start's optimum is not finite (NaN compared as the best kept every later
    # one out, and the fit fell back to the multi-start): the second start's optimum wins
    import bayestribo.inference.start as start_module

    posterior = comparison._posterior("viscous+quadratic", prepared.data, "exact", False)
    starts = nested_starts("viscous+quadratic", prepared, one_term_optima)
    expected, _, _ = maximum_from_starts(posterior, starts[1:], prepared.decay)
    real = start_module._optimise
    calls = []

    def first_fails(*args, **kwargs):
        theta, cov, lp = real(*args, **kwargs)
        calls.append(lp)
        return (theta, cov, np.nan) if len(calls) == 1 else (theta, cov, lp)

    monkeypatch.setattr(start_module, "_optimise", first_fails)
    monkeypatch.setattr(
        start_module, "maximum_a_posteriori", lambda *a: pytest.fail("fell back to the guesses")
    )
    theta, _, _ = maximum_from_starts(posterior, starts, prepared.decay)
    np.testing.assert_array_equal(theta, expected)
