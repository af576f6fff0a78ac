"""The independence Metropolis-Hastings move (seeded).

* the proposal's draws follow its density (a Student-t where no coordinate is flat,
  scipy's; a flat coordinate's uniform with its Cauchy defence), and the compiled
  step's Hastings factors are that density's;
* independence steps alone, with a proposal off the target's centre and scale, sample
  a correlated Gaussian (and the same check fails without the Hastings factor);
* the sampler with the move in its mix samples known targets: a correlated Gaussian,
  a bounded uniform times a correlated Gaussian pair (the fit's shape), a banana;
* each ensemble's proposal is fitted from, and draws for, that ensemble alone; the
  adaptation phase is never kept.

Tolerances are Monte Carlo errors from the effective sample size the run reports
(5 of them: a one-in-a-million miss for a mean).
"""

from __future__ import annotations

import emcee
import numpy as np
import pytest
import scipy.stats

import bayestribo.inference.independence as independence
from bayestribo.errors import BayestriboError
from bayestribo.inference.independence import (
    DEFENSIVE,
    GroupedIndependenceMove,
    StudentProposal,
    mix_weight,
)
from bayestribo.inference.sampling import SamplerSettings, autocorr_time, run_ensembles

MEAN = np.array([1.0, -2.0, 0.5])
SD = np.array([1.0, 0.1, 3.0])
CORR = np.array([[1.0, 0.9, -0.3], [0.9, 1.0, 0.0], [-0.3, 0.0, 1.0]])
COV = CORR * np.outer(SD, SD)
PREC = np.linalg.inv(COV)


def _gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MEAN
    return -0.5 * np.einsum("ni,ij,nj->n", d, PREC, d)


def _flat_cdf(x: np.ndarray, low: float, high: float) -> np.ndarray:
    """CDF of a flat coordinate's proposal: (1 − ε) U(low, high) + ε Cauchy."""
    half = 0.5 * (high - low)
    cauchy = scipy.stats.cauchy.cdf(x, loc=low + half, scale=half)
    return (1 - DEFENSIVE) * np.clip((x - low) / (high - low), 0, 1) + DEFENSIVE * cauchy


def test_the_proposal_is_scipys_multivariate_t_where_no_coordinate_is_flat():
    rng = np.random.default_rng(1)
    draws = rng.multivariate_normal(MEAN, COV, size=4000)
    proposal = StudentProposal.fitted(draws, scale=1.2, df=5.0)
    assert not proposal.flat.any()
    shape = proposal.chol @ proposal.chol.T
    np.testing.assert_allclose(shape, 1.2**2 * np.cov(draws, rowvar=False), rtol=1e-12)
    t = scipy.stats.multivariate_t(loc=proposal.location, shape=shape, df=5.0)
    x = rng.multivariate_normal(MEAN, 4 * COV, size=50)
    np.testing.assert_allclose(proposal.log_density(x), t.logpdf(x), rtol=1e-10)
    # its draws are that t's: each marginal by Kolmogorov-Smirnov
    y = proposal.draw(np.random.RandomState(2), 20_000)
    for j in range(3):
        marginal = scipy.stats.t(5.0, loc=proposal.location[j], scale=np.sqrt(shape[j, j]))
        assert scipy.stats.kstest(y[:, j], marginal.cdf).pvalue > 1e-4


def test_a_flat_coordinate_is_proposed_from_its_range():
    rng = np.random.default_rng(3)
    n = 4000
    a = rng.standard_normal(n)
    draws = np.column_stack([a, rng.uniform(1.0, 3.0, n), 0.5 * a + rng.standard_normal(n)])
    proposal = StudentProposal.fitted(draws)
    np.testing.assert_array_equal(proposal.flat, [False, True, False])
    low, high = proposal.low[1], proposal.high[1]
    assert low < 1.0 < low + 0.05 and high - 0.05 < 3.0 < high
    y = proposal.draw(np.random.RandomState(4), 40_000)
    assert scipy.stats.kstest(y[:, 1], lambda x: _flat_cdf(x, low, high)).pvalue > 1e-4
    # the density is the product of the t over the others and the flat coordinate's
    keep = [0, 2]
    shape = (proposal.chol @ proposal.chol.T)[np.ix_(keep, keep)]
    t = scipy.stats.multivariate_t(loc=proposal.location[keep], shape=shape, df=proposal.df)
    x = np.column_stack(
        [rng.standard_normal(30), rng.uniform(0.0, 4.0, 30), rng.standard_normal(30)]
    )
    half = 0.5 * (high - low)
    flat = DEFENSIVE * scipy.stats.cauchy.pdf(x[:, 1], low + half, half) + (1 - DEFENSIVE) * (
        (x[:, 1] >= low) & (x[:, 1] <= high)
    ) / (high - low)
    np.testing.assert_allclose(
        proposal.log_density(x), t.logpdf(x[:, keep]) + np.log(flat), rtol=1e-10
    )


def test_the_compiled_step_draws_the_proposals_and_their_hastings_factors():
    rng = np.random.default_rng(5)
    chains = np.stack(
        [
            np.column_stack([rng.standard_normal((50, 8)), rng.uniform(1, 3, (50, 8))])
            .reshape(50, 2, 8)
            .transpose(0, 2, 1),
            np.column_stack([3 + rng.standard_normal((50, 8)), rng.standard_normal((50, 8))])
            .reshape(50, 2, 8)
            .transpose(0, 2, 1),
        ]
    )
    move = GroupedIndependenceMove.fitted(chains)
    assert move.proposals[0].flat.tolist() == [False, True]
    assert not move.proposals[1].flat.any()
    coords = rng.standard_normal((16, 2)) + np.array([0.0, 2.0])
    z, w, u = move.proposals[0].numbers(np.random.RandomState(6), 16)
    q, factors = independence._proposals(coords, *move._stacked(), z, w, u)
    for e, proposal in enumerate(move.proposals):
        block = slice(8 * e, 8 * (e + 1))
        expected = independence._draws(
            proposal.location,
            proposal.chol,
            proposal.df,
            proposal.flat,
            proposal.low,
            proposal.high,
            z[block],
            w[block],
            u[block],
        )
        np.testing.assert_array_equal(q[block], expected)
        np.testing.assert_allclose(
            factors[block],
            proposal.log_density(coords[block]) - proposal.log_density(q[block]),
            rtol=1e-10,
            atol=1e-12,
        )


def _independence_only(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Independence steps alone on the correlated Gaussian, with each ensemble's
    proposal off centre by 0.7 sd and 1.5 times too wide: (draws after 100 steps,
    τ per parameter)."""
    off = StudentProposal(
        MEAN + 0.7 * SD,
        1.5 * np.linalg.cholesky(COV),
        5.0,
        np.zeros(3, dtype=bool),
        np.zeros(3),
        np.ones(3),
    )
    sampler = emcee.EnsembleSampler(
        32, 3, _gaussian, moves=[GroupedIndependenceMove([off, off])], vectorize=True
    )
    sampler.random_state = np.random.RandomState(seed).get_state()
    start = np.random.default_rng(seed).multivariate_normal(MEAN, COV, size=32)
    sampler.run_mcmc(start, 2100, progress=False)
    chain = sampler.get_chain(discard=100)
    return chain.reshape(-1, 3), autocorr_time(chain)


def _mean_and_variance_are_the_targets(flat: np.ndarray, tau: np.ndarray) -> bool:
    ess = flat.shape[0] / tau
    mean_ok = np.all(np.abs(flat.mean(axis=0) - MEAN) < 5 * SD / np.sqrt(ess))
    var_ok = np.all(np.abs(flat.var(axis=0) / SD**2 - 1) < 5 * np.sqrt(2 / ess))
    return bool(mean_ok and var_ok)


def test_independence_steps_alone_sample_the_target_from_a_proposal_off_centre(monkeypatch):
    flat, tau = _independence_only(7)
    assert np.all(tau < 10)  # a proposal 0.7 sd off: a few steps to forget
    assert _mean_and_variance_are_the_targets(flat, tau)
    # the check has power: without the Hastings factor q(x)/q(y) the chain samples
    # another density (π q), and the same check fails
    compiled = independence._proposals

    def no_factor(*args):
        q, factors = compiled(*args)
        return q, np.zeros_like(factors)

    monkeypatch.setattr(independence, "_proposals", no_factor)
    flat, tau = _independence_only(7)
    assert not _mean_and_variance_are_the_targets(flat, tau)


@pytest.mark.parametrize("moves", ["grouped", "emcee"])
def test_a_correlated_gaussian_is_sampled_with_the_move_in_the_mix(moves):
    settings = SamplerSettings(
        n_walkers=16, n_ensembles=2, max_steps=20_000, moves=moves, independence=0.75
    )
    start = MEAN + 0.01 * np.random.default_rng(0).standard_normal((2, 16, 3))
    run = run_ensembles(_gaussian, start, settings, seed=1, names=["a", "b", "c"])
    assert run.converged, run.reasons
    assert run.independence == 0.75 and run.independence_acceptance > 0.3
    # the adaptation phase is never kept
    assert run.burn >= settings.adapt_steps
    flat = run.chains.reshape(-1, 3)
    ess = run.ess
    np.testing.assert_array_less(np.abs(flat.mean(axis=0) - MEAN), 5 * SD / np.sqrt(ess))
    np.testing.assert_array_less(
        np.abs(flat.var(axis=0) / SD**2 - 1), 5 * np.sqrt(2 / np.minimum(ess, flat.shape[0]))
    )
    corr = np.corrcoef(flat.T)
    assert abs(corr[0, 1] - 0.9) < 0.05 and abs(corr[0, 2] + 0.3) < 0.15
    assert scipy.stats.kstest(flat[:, 2], "norm", args=(MEAN[2], SD[2])).pvalue > 1e-4
    assert np.all(run.rhat < 1.01)
    assert run.n_steps - run.burn >= 50 * np.max(run.autocorr_time)


def test_a_bounded_uniform_times_a_correlated_gaussian_pair_is_sampled():
    # The single-run posterior's shape: ζ and μ_k correlated at -0.9 with sds 1e-5 and
    # 4e-5, μ_s/μ_k uniform on [1, 3] (proposed as flat), y0 with sd 1e-3.
    sds = np.array([1e-5, 4e-5, 1e-3])
    prec = np.linalg.inv(np.array([[1.0, -0.9], [-0.9, 1.0]]) * np.outer(sds[:2], sds[:2]))

    def target(theta):
        t = np.atleast_2d(theta)
        lp = -0.5 * np.einsum("ni,ij,nj->n", t[:, :2], prec, t[:, :2])
        lp = lp - 0.5 * ((t[:, 3] - 8.0) / sds[2]) ** 2
        return np.where((t[:, 2] < 1.0) | (t[:, 2] > 3.0), -np.inf, lp)

    rng = np.random.default_rng(19)
    start = np.stack(
        [
            np.column_stack(
                [
                    sds[0] * rng.standard_normal(16),
                    sds[1] * rng.standard_normal(16),
                    rng.uniform(1.0, 3.0, 16),
                    8.0 + sds[2] * rng.standard_normal(16),
                ]
            )
            for _ in range(2)
        ]
    )
    settings = SamplerSettings(
        n_walkers=16, n_ensembles=2, autocorr_multiple=100, max_steps=50_000, independence=0.75
    )
    run = run_ensembles(target, start, settings, seed=20, names=["zeta", "mu_k", "r", "y0"])
    assert run.converged, run.reasons
    assert run.independence == 0.75 and run.burn >= settings.adapt_steps
    flat = run.chains.reshape(-1, 4)
    ratio = flat[:, [0, 1, 3]].std(axis=0) / sds
    se = 1.0 / np.sqrt(2.0 * run.ess[[0, 1, 3]])
    assert np.all(np.abs(ratio - 1.0) < 5 * se), ratio
    assert np.all(np.abs(flat[:, [0, 1]].mean(axis=0)) < 5 * sds[:2] / np.sqrt(run.ess[:2]))
    # the uniform, edges included: Kolmogorov-Smirnov on the thinned draws
    assert scipy.stats.kstest(flat[:, 2], "uniform", args=(1.0, 2.0)).pvalue > 1e-4
    assert abs(np.corrcoef(flat[:, :2].T)[0, 1] + 0.9) < 0.03


def _banana(theta: np.ndarray) -> np.ndarray:
    """x ~ N(0, 2²), y = x² within 0.3: a curved ridge no Student-t fits."""
    d = np.atleast_2d(theta)
    return -0.5 * ((d[:, 1] - d[:, 0] ** 2) / 0.3) ** 2 - 0.5 * d[:, 0] ** 2 / 4.0


@pytest.mark.validation
def test_a_banana_is_sampled_with_the_move_in_the_mix():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=60_000, independence=0.75)
    start = np.array([0.0, 0.0]) + 0.1 * np.random.default_rng(21).standard_normal((2, 16, 2))
    run = run_ensembles(_banana, start, settings, seed=22, names=["x", "y"])
    assert run.converged, run.reasons
    assert run.burn >= settings.adapt_steps
    flat = run.chains.reshape(-1, 2)
    # x ~ N(0, 2²) and E[y] = E[x²] + 0 = 4, sd(y) = √(2·16 + 0.09)
    assert scipy.stats.kstest(flat[:, 0], "norm", args=(0.0, 2.0)).pvalue > 1e-4
    assert abs(flat[:, 0].mean()) < 5 * 2.0 / np.sqrt(run.ess[0])
    assert abs(flat[:, 1].mean() - 4.0) < 5 * np.sqrt(32.09) / np.sqrt(run.ess[1])


def test_each_ensembles_proposal_is_its_own_walkers():
    rng = np.random.default_rng(8)
    chains = rng.standard_normal((2, 40, 8, 3))
    chains[1] += 100.0
    move = GroupedIndependenceMove.fitted(chains)
    for e in range(2):
        own = StudentProposal.fitted(chains[e].reshape(-1, 3))
        np.testing.assert_array_equal(move.proposals[e].location, own.location)
        np.testing.assert_array_equal(move.proposals[e].chol, own.chol)
    # another ensemble's walkers change nothing of ensemble 0's proposal ...
    other = chains.copy()
    other[1] = 1e6 + rng.standard_normal((40, 8, 3))
    np.testing.assert_array_equal(
        GroupedIndependenceMove.fitted(other).proposals[0].location, move.proposals[0].location
    )

    # ... and ensemble 0's walkers are proposed from ensemble 0's proposal alone
    class Model:
        random = np.random.RandomState(9)

        @staticmethod
        def log_prob_fn(theta):
            return np.zeros(theta.shape[0])

    state = emcee.State(np.vstack([chains[0, -1], chains[1, -1]]), log_prob=np.zeros(16))
    for _ in range(20):
        state, accepted = move.propose(Model, state)
        assert np.all(np.abs(state.coords[:8]) < 50) and np.all(state.coords[8:] > 50)
        assert accepted.any()


def test_a_move_that_would_rarely_be_accepted_is_left_out_of_the_mix():
    assert mix_weight(0.6, 0.75) == 0.75
    assert mix_weight(independence.FULL_ACCEPTANCE, 0.75) == 0.75
    assert mix_weight(independence.NO_ACCEPTANCE, 0.75) == 0.0
    assert mix_weight(0.01, 0.75) == 0.0
    middle = 0.5 * (independence.FULL_ACCEPTANCE + independence.NO_ACCEPTANCE)
    assert mix_weight(middle, 0.8) == pytest.approx(0.4)


def test_the_settings_refuse_a_weight_outside_0_1_and_a_phase_past_the_ceiling():
    with pytest.raises(BayestriboError, match="independence"):
        SamplerSettings(independence=1.0)
    with pytest.raises(BayestriboError, match="independence"):
        SamplerSettings(independence=-0.1)
    with pytest.raises(BayestriboError, match="adapt_steps"):
        SamplerSettings(independence=0.5, adapt_steps=500, max_steps=400)
    with pytest.raises(BayestriboError, match="n > d"):
        StudentProposal.fitted(np.zeros((3, 3)))
