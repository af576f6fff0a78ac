"""The independence move taken out where it does not mix (seeded).

* :func:`~bayestribo.inference.independence.mixing_tau` is the autocorrelation time of
  a chain that jumps with probability p to an independent draw (measured on such
  chains, within the estimator's error);
* where a check's τ passes the limit, the move is taken out, every step before is
  discarded, the run ends with the DE moves alone, and its draws sample the target;
  the mix is the DE moves' own again;
* without a limit the move stays in; τ is debiased only by the fit's rule
  (``debias``) with the move in the mix;
* on a curved ridge no Student-t fits, the fit's limit takes the move out and the
  draws still sample the target.

Tolerances are Monte Carlo errors from the effective sample size the run reports
(5 of them: a one-in-a-million miss for a mean).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

import bayestribo.inference.sampling as sampling
from bayestribo.errors import BayestriboError
from bayestribo.inference.independence import mixing_tau
from bayestribo.inference.sampling import (
    FIT_INDEPENDENCE_LIMIT,
    SamplerSettings,
    autocorr_time,
    run_ensembles,
)

MEAN = np.array([1.0, -2.0, 0.5])
SD = np.array([1.0, 0.1, 3.0])
CORR = np.array([[1.0, 0.9, -0.3], [0.9, 1.0, 0.0], [-0.3, 0.0, 1.0]])
PREC = np.linalg.inv(CORR * np.outer(SD, SD))


def _gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MEAN
    return -0.5 * np.einsum("ni,ij,nj->n", d, PREC, d)


def _start(seed: int) -> np.ndarray:
    return MEAN + 0.01 * np.random.default_rng(seed).standard_normal((2, 16, 3))


def _samples_the_gaussian(run) -> None:
    flat = run.chains.reshape(-1, 3)
    ess = run.ess
    np.testing.assert_array_less(np.abs(flat.mean(axis=0) - MEAN), 5 * SD / np.sqrt(ess))
    np.testing.assert_array_less(
        np.abs(flat.var(axis=0) / SD**2 - 1), 5 * np.sqrt(2 / np.minimum(ess, flat.shape[0]))
    )
    assert scipy.stats.kstest(flat[:, 2], "norm", args=(MEAN[2], SD[2])).pvalue > 1e-4


@pytest.mark.parametrize("p", [0.1, 0.3, 0.6])
def test_mixing_tau_is_the_tau_of_a_chain_jumping_to_independent_draws(p):
    rng = np.random.default_rng(int(100 * p))
    steps, walkers = 20_000, 32
    chain = np.empty((steps, walkers))
    chain[0] = rng.standard_normal(walkers)
    for t in range(1, steps):
        jump = rng.random(walkers) < p
        chain[t] = np.where(jump, rng.standard_normal(walkers), chain[t - 1])
    expected = mixing_tau(p, 1.0)
    assert expected == pytest.approx((2 - p) / p)
    measured = float(autocorr_time(chain)[0])
    # the windowed estimator's relative error: √(2 (2c + 1) τ / (L W)) with c = 5, and
    # its bias of about 10.5 τ/L (inference/tau_bias.py)
    error = np.sqrt(2 * 11 * expected / (steps * walkers)) + 10.5 * expected / steps
    assert abs(measured / expected - 1) < 5 * error
    # half the weight, half the jumps: twice the τ, or so
    assert mixing_tau(p, 0.5) == pytest.approx((2 - p / 2) / (p / 2))
    assert mixing_tau(0.0, 0.75) == np.inf


def test_a_move_past_the_limit_is_taken_out_and_the_draws_after_it_sample_the_target(
    monkeypatch,
):
    # every τ passes a limit on a predicted τ of a hundredth of a step: the move is
    # taken out at the first check after the adaptation phase
    monkeypatch.setattr(sampling, "mixing_tau", lambda acceptance, weight: 0.01)
    settings = SamplerSettings(
        n_walkers=16,
        n_ensembles=2,
        autocorr_multiple=30,
        max_steps=20_000,
        independence=0.75,
        independence_limit=4.0,
    )
    run = run_ensembles(_gaussian, _start(0), settings, seed=1, names=["a", "b", "c"])
    assert run.independence_dropped == settings.adapt_steps + settings.check_every
    assert run.independence == 0.0 and run.independence_acceptance > 0.3
    assert run.burn >= run.independence_dropped
    assert run.converged, run.reasons
    assert run.n_steps - run.burn >= 30 * np.max(run.autocorr_time)
    _samples_the_gaussian(run)


def test_the_move_is_not_taken_out_at_the_ceiling(monkeypatch):
    # the first check is at the ceiling: taking the move out would leave no step
    monkeypatch.setattr(sampling, "mixing_tau", lambda acceptance, weight: 0.01)
    settings = SamplerSettings(
        n_walkers=16, n_ensembles=2, max_steps=150, independence=0.75, independence_limit=4.0
    )
    run = run_ensembles(_gaussian, _start(12), settings, seed=13)
    assert run.n_steps == 150 and run.independence_dropped is None
    assert run.independence == 0.75 and np.all(np.isfinite(run.autocorr_time))
    assert not run.converged
    assert not any("undefined" in reason for reason in run.reasons)


@pytest.mark.parametrize("moves", ["grouped", "emcee"])
def test_taking_the_move_out_restores_the_de_moves_mix(moves, monkeypatch):
    mixes = []
    original = sampling._without_independence

    def recorded(sampler):
        original(sampler)
        mixes.append((sampler._moves, np.asarray(sampler._weights)))

    monkeypatch.setattr(sampling, "_without_independence", recorded)
    monkeypatch.setattr(sampling, "mixing_tau", lambda acceptance, weight: 0.01)
    settings = SamplerSettings(
        n_walkers=16,
        n_ensembles=2,
        max_steps=2_000,
        moves=moves,
        independence=0.75,
        independence_limit=4.0,
    )
    run_ensembles(_gaussian, _start(2), settings, seed=3)
    assert mixes
    for moves_now, weights in mixes:
        assert len(moves_now) == 2
        assert not any(type(m).__name__ == "GroupedIndependenceMove" for m in moves_now)
        np.testing.assert_array_equal(weights, [0.8, 0.2])


def test_without_a_limit_the_move_stays_in():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000, independence=0.75)
    run = run_ensembles(_gaussian, _start(4), settings, seed=5)
    assert run.converged and run.independence == 0.75 and run.independence_dropped is None


def test_on_a_gaussian_the_fits_limit_keeps_the_move():
    settings = SamplerSettings(
        n_walkers=16,
        n_ensembles=2,
        max_steps=20_000,
        independence=0.75,
        independence_limit=FIT_INDEPENDENCE_LIMIT,
    )
    run = run_ensembles(_gaussian, _start(6), settings, seed=7)
    assert run.converged and run.independence == 0.75 and run.independence_dropped is None
    _samples_the_gaussian(run)


@pytest.mark.parametrize(
    "rule",
    [
        {"debias": True},  # the fit's rule, the DE moves alone
        {"independence": 0.75},  # the population's: the move in, τ raw
    ],
)
def test_tau_is_judged_raw_without_the_fits_rule_and_the_move(rule, monkeypatch):
    def refused(tau, length):
        raise AssertionError("τ debiased")

    monkeypatch.setattr(sampling, "debiased", refused)
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000, **rule)
    run = run_ensembles(_gaussian, _start(8), settings, seed=9)
    assert run.converged
    assert run.independence == rule.get("independence", 0.0)


def test_the_fits_rule_debiases_tau_while_the_move_is_in(monkeypatch):
    calls = []
    original = sampling.debiased

    def counted(tau, length):
        calls.append(length)
        return original(tau, length)

    monkeypatch.setattr(sampling, "debiased", counted)
    settings = SamplerSettings(
        n_walkers=16, n_ensembles=2, max_steps=20_000, independence=0.75, debias=True
    )
    run = run_ensembles(_gaussian, _start(10), settings, seed=11)
    assert run.converged and run.independence == 0.75 and calls


def _banana(theta: np.ndarray) -> np.ndarray:
    """x ~ N(0, 2²), y = x² within 0.3: a curved ridge no Student-t fits."""
    d = np.atleast_2d(theta)
    return -0.5 * ((d[:, 1] - d[:, 0] ** 2) / 0.3) ** 2 - 0.5 * d[:, 0] ** 2 / 4.0


@pytest.mark.validation
def test_on_a_curved_ridge_the_fits_limit_takes_the_move_out():
    settings = SamplerSettings(
        n_walkers=16,
        n_ensembles=2,
        max_steps=60_000,
        independence=0.75,
        independence_limit=FIT_INDEPENDENCE_LIMIT,
    )
    start = 0.1 * np.random.default_rng(21).standard_normal((2, 16, 2))
    run = run_ensembles(_banana, start, settings, seed=22, names=["x", "y"])
    assert run.independence_dropped is not None and run.independence == 0.0
    assert run.burn >= run.independence_dropped
    assert run.converged, run.reasons
    flat = run.chains.reshape(-1, 2)
    assert scipy.stats.kstest(flat[:, 0], "norm", args=(0.0, 2.0)).pvalue > 1e-4
    assert abs(flat[:, 0].mean()) < 5 * 2.0 / np.sqrt(run.ess[0])
    assert abs(flat[:, 1].mean() - 4.0) < 5 * np.sqrt(32.09) / np.sqrt(run.ess[1])


def test_a_limit_of_one_or_less_is_refused():
    with pytest.raises(BayestriboError, match="independence_limit"):
        SamplerSettings(independence=0.75, independence_limit=1.0)
