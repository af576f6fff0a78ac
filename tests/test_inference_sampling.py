"""The one sampling driver on targets with known answers (seeded).

* a correlated 3-D Gaussian: means, covariance and a marginal's distribution, with
  tolerances from the reported effective sample size;
* an AR(1) chain, whose integrated autocorrelation time (1 + ρ)/(1 − ρ), hence its
  effective sample size, is known;
* R-hat on identical against separated chains;
* a run too short to converge is reported so, with its reason;
* a NaN log-probability is an error naming the parameters;
* the grouped moves (all ensembles in one emcee sampler) propose as emcee's own DE
  and snooker moves do, never from another ensemble's walkers, and sample known
  targets as emcee's moves do.
"""

from __future__ import annotations

import re

import emcee
import numpy as np
import pytest
import scipy.stats
from _paths import RUNS

from bayestribo.errors import BayestriboError
from bayestribo.inference.moves import DESnookerMove, GroupedDEMove, GroupedDESnookerMove
from bayestribo.inference.sampling import (
    NaNLogProbabilityError,
    SamplerSettings,
    autocorr_time,
    effective_sample_size,
    rhat,
    run_ensembles,
)

MEAN = np.array([1.0, -2.0, 0.5])
SD = np.array([1.0, 0.1, 3.0])
CORR = np.array([[1.0, 0.9, -0.3], [0.9, 1.0, 0.0], [-0.3, 0.0, 1.0]])
COV = CORR * np.outer(SD, SD)
PREC = np.linalg.inv(COV)


def _gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MEAN
    return -0.5 * np.einsum("ni,ij,nj->n", d, PREC, d)


@pytest.fixture(scope="module", params=["grouped", "emcee"])
def gaussian_run(request):
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000, moves=request.param)
    rng = np.random.default_rng(0)
    start = MEAN + 0.01 * rng.standard_normal((2, 16, 3))
    return run_ensembles(_gaussian, start, settings, seed=1, names=["a", "b", "c"])


def test_a_correlated_gaussian_is_sampled_to_convergence(gaussian_run):
    run = gaussian_run
    assert run.converged, run.reasons
    flat = run.chains.reshape(-1, 3)
    ess = run.ess
    # Monte Carlo error of a mean is sd/√ESS: 5 of them is a 1-in-10⁶ miss.
    np.testing.assert_array_less(np.abs(flat.mean(axis=0) - MEAN), 5 * SD / np.sqrt(ess))
    # Variance: relative error about √(2/ESS); thinned draws are nearly independent.
    np.testing.assert_array_less(
        np.abs(flat.var(axis=0) / SD**2 - 1), 5 * np.sqrt(2 / np.minimum(ess, flat.shape[0]))
    )
    corr = np.corrcoef(flat.T)
    assert abs(corr[0, 1] - 0.9) < 0.05 and abs(corr[0, 2] + 0.3) < 0.15
    # The marginal of c is N(0.5, 3²): Kolmogorov-Smirnov on the thinned draws.
    ks = scipy.stats.kstest(flat[:, 2], "norm", args=(MEAN[2], SD[2]))
    assert ks.pvalue > 1e-4
    assert np.all(run.rhat < 1.01) and run.burn > 0 and run.thin >= 1
    # The stopping rule: at least 50 autocorrelation times after burn.
    assert run.n_steps - run.burn >= 50 * np.max(run.autocorr_time)


def test_the_run_summary_names_each_parameter(gaussian_run):
    summary = gaussian_run.summary(0.9)
    assert list(summary) == ["a", "b", "c"]
    c = summary["c"]
    assert c.prob == 0.9 and c.kind == "posterior"
    # The 90 % interval of N(0.5, 3²) is 0.5 ± 1.645·3; its ends are known to about
    # 2.1·sd/√ESS each (the sd of a 5 % quantile estimate, in units of the sd).
    half = scipy.stats.norm.ppf(0.95) * SD[2]
    err = 5 * 2.1 * SD[2] / np.sqrt(gaussian_run.ess[2])
    assert abs(c.low - (MEAN[2] - half)) < err and abs(c.high - (MEAN[2] + half)) < err
    with pytest.raises(BayestriboError, match="prob"):
        gaussian_run.summary(1.5)


def test_autocorrelation_time_and_ess_of_an_ar1_chain_are_the_known_ones():
    # x_t = ρ x_{t-1} + √(1-ρ²) ε_t: τ = (1+ρ)/(1-ρ) exactly, so ESS = N·W/τ; the
    # estimate's relative error over 32 walkers × 20000 steps is about √(2M/(N·W)),
    # 1-2 %, with M the window (about 5τ).
    rng = np.random.default_rng(3)
    for rho in (0.5, 0.9):
        n, walkers = 20_000, 32
        eps = rng.standard_normal((n, walkers, 1)) * np.sqrt(1 - rho**2)
        x = np.empty_like(eps)
        x[0] = rng.standard_normal((walkers, 1))
        for t in range(1, n):
            x[t] = rho * x[t - 1] + eps[t]
        tau = autocorr_time(x)[0]
        exact = (1 + rho) / (1 - rho)
        assert tau == pytest.approx(exact, rel=0.08)
        assert effective_sample_size(x)[0] == pytest.approx(n * walkers / exact, rel=0.08)
    with pytest.raises(BayestriboError, match=r"chain: expected shape \(steps, walkers"):
        effective_sample_size(np.zeros((100, 4)))


def test_rhat_tells_separated_chains_from_identical_ones():
    rng = np.random.default_rng(4)
    same = rng.standard_normal((2, 2000, 1))
    assert rhat(same)[0] < 1.01
    apart = same + np.array([0.0, 1.0])[:, None, None]
    assert rhat(apart)[0] > 1.1


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # constant chains: 0/0, as ArviZ
def test_rhat_is_arvizs_rank_normalised_split_rhat():
    # The numpy R-hat (a fit imports no ArviZ) against ArviZ's on chains of many
    # shapes and scales, with ties, offsets between chains, constant chains, a NaN
    # draw and too few chains or draws: the same values (the variance sums are taken
    # in order as ArviZ's compiled ones).
    az = pytest.importorskip("arviz")
    rng = np.random.default_rng(11)
    cases = []
    for trial in range(120):
        n_chain, n_draw, n_par = rng.integers(2, 6), rng.integers(4, 300), rng.integers(1, 4)
        x = rng.standard_normal((n_chain, n_draw, n_par)) * 10 ** rng.uniform(-8, 3)
        x += rng.standard_normal() * 10 ** rng.uniform(-3, 3)
        if trial % 3 == 0:
            x = np.round(x, 1)  # ties
        if trial % 5 == 0:
            x[1] += 0.5
        if trial % 17 == 0:
            x[...] = 1.0
        cases.append(x)
    with_nan = rng.standard_normal((3, 50, 2))
    with_nan[0, 7, 1] = np.nan
    cases += [with_nan, rng.standard_normal((1, 50, 2)), rng.standard_normal((2, 3, 2))]
    for x in cases:
        ours = rhat(x)
        theirs = np.array(
            [float(az.rhat(np.ascontiguousarray(x[..., i]))) for i in range(x.shape[-1])]
        )
        np.testing.assert_allclose(ours, theirs, rtol=1e-10, atol=0, equal_nan=True)
    assert np.isnan(rhat(with_nan)[1]) and np.isfinite(rhat(with_nan)[0])


def test_a_run_too_short_to_converge_is_reported_with_its_reason():
    # 200 steps cannot hold a burn plus 50 autocorrelation times (τ is over 4 steps
    # even for a well-mixed 3-D Gaussian).
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=200)
    start = MEAN + 5.0 * np.random.default_rng(5).standard_normal((2, 16, 3))
    run = run_ensembles(_gaussian, start, settings, seed=2)
    assert not run.converged
    assert any("autocorrelation times" in r for r in run.reasons), run.reasons
    assert run.names == ("theta[0]", "theta[1]", "theta[2]")


@pytest.mark.parametrize("min_ess", [500.0, 1500.0])
def test_a_run_with_an_ess_target_stops_once_it_holds_that_ess(min_ess):
    # 2 × 16 walkers: an ESS of 500 is 15.6 τ (the floor of 20 τ rules), 1500 is
    # 46.9 τ (the ESS rules).
    settings = SamplerSettings(
        n_walkers=16, n_ensembles=2, max_steps=20_000, autocorr_multiple=20.0, min_ess=min_ess
    )
    assert settings.required_multiple() == max(20.0, min_ess / 32)
    start = MEAN + 0.01 * np.random.default_rng(4).standard_normal((2, 16, 3))
    run = run_ensembles(_gaussian, start, settings, seed=5)
    assert run.converged, run.reasons
    tau = np.max(run.autocorr_time)
    after = run.n_steps - run.burn
    assert after >= settings.required_multiple() * tau
    assert np.min(run.ess) == pytest.approx(after * 32 / tau)
    assert np.min(run.ess) >= max(min_ess, 20 * 32)


def test_ensembles_stuck_in_separate_modes_are_not_converged():
    # Two far-apart narrow modes; each ensemble starts in its own and never crosses:
    # each chain looks fine alone, only R-hat between the ensembles sees the problem.
    def two_modes(theta):
        d = np.atleast_2d(theta)
        a = -0.5 * np.sum((d - 5.0) ** 2, axis=1) / 0.01
        b = -0.5 * np.sum((d + 5.0) ** 2, axis=1) / 0.01
        return np.logaddexp(a, b)

    settings = SamplerSettings(n_walkers=8, n_ensembles=2, max_steps=600)
    rng = np.random.default_rng(7)
    start = 0.05 * rng.standard_normal((2, 8, 2)) + np.array([5.0, -5.0])[:, None, None]
    run = run_ensembles(two_modes, start, settings, seed=8, names=["x", "y"])
    assert not run.converged
    assert any(re.fullmatch(r"R-hat \d+\.\d+ >= 1\.01 for [xy]", r) for r in run.reasons), (
        run.reasons
    )
    assert np.all(run.rhat > 1.1)


@pytest.mark.parametrize("walkers", [3, 4, 7])
def test_fewer_walkers_than_twice_the_parameters_is_an_error_naming_the_option(walkers):
    # an ensemble of fewer walkers does not span the posterior: emcee refused it with a
    # RuntimeError deep in a fit, or the fit went on to fail on too few draws
    settings = SamplerSettings(n_walkers=walkers, n_ensembles=2, max_steps=200)
    start = 0.01 * np.random.default_rng(3).standard_normal((2, walkers, 4))
    with pytest.raises(
        BayestriboError, match=r"n_walkers \(--walkers\): .* 4 sampled .* 8 walkers"
    ):
        run_ensembles(lambda x: -0.5 * np.sum(x * x, axis=1), start, settings, seed=1)


def test_a_fit_with_too_few_walkers_is_refused_naming_the_option(capsys):
    from bayestribo.cli.main import main

    code = main(["fit", str(RUNS / "glycerol-N0.31-r1.csv"), "--walkers", "4"])
    assert code == 2
    assert "--walkers" in capsys.readouterr().err


def test_a_nan_log_probability_is_an_error_naming_the_parameters():
    def broken(theta):
        out = _gaussian(theta)
        out[np.atleast_2d(theta)[:, 0] > 1.5] = np.nan
        return out

    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=400)
    start = MEAN + 0.01 * np.random.default_rng(6).standard_normal((2, 16, 3))
    with pytest.raises(NaNLogProbabilityError, match=r"NaN at a=.*, b=.*, c=") as info:
        run_ensembles(broken, start, settings, seed=3, names=["a", "b", "c"])
    # A package error, and a FloatingPointError like the posterior's own NaN error.
    assert isinstance(info.value, BayestriboError)
    assert isinstance(info.value, FloatingPointError)
    row = [float(v) for v in re.search(r"a=(\S+), b=(\S+), c=(\S+)$", str(info.value)).groups()]
    assert row[0] > 1.5 and np.isnan(broken(np.array([row]))[0])


def test_bad_settings_and_start_shapes_are_refused():
    with pytest.raises(BayestriboError, match="max_steps: expected at least check_every"):
        SamplerSettings(check_every=200, max_steps=100)
    with pytest.raises(BayestriboError, match="settle_steps: expected at least check_every"):
        SamplerSettings(check_every=200, settle_steps=100)
    with pytest.raises(BayestriboError, match="moves: expected one of"):
        SamplerSettings(moves="stretch")
    with pytest.raises(BayestriboError, match="n_ensembles"):
        SamplerSettings(n_ensembles=1)
    with pytest.raises(BayestriboError, match="min_ess: expected > 0 or None, got 0"):
        SamplerSettings(min_ess=0)
    with pytest.raises(BayestriboError, match="autocorr_multiple: expected > 0"):
        SamplerSettings(autocorr_multiple=-1.0)
    with pytest.raises(BayestriboError, match=r"initial: expected shape \(2, 16, d\)"):
        run_ensembles(_gaussian, np.zeros((16, 3)), SamplerSettings(n_walkers=16), seed=0)


def test_autocorrelation_time_is_emcees_estimator():
    # The batched FFT against emcee's own loop over walkers and parameters, on
    # chains with long and short memory (Sokal's window beyond the first quarter of the
    # lags, and within it: white noise and the same with drift), and on a chain that
    # does not move.
    rng = np.random.default_rng(9)
    for shape in [(1000, 16, 4), (777, 8, 3), (6, 4, 2)]:
        for drift in (0.1, 0.0):
            x = drift * np.cumsum(rng.standard_normal(shape), axis=0)
            x += rng.standard_normal(shape)
            ref = emcee.autocorr.integrated_time(x, tol=0, quiet=True)
            np.testing.assert_allclose(autocorr_time(x), ref, rtol=1e-12)
    x = np.ones((50, 4, 2))
    x[:, :, 1] = rng.standard_normal((50, 4))
    tau = autocorr_time(x)
    assert np.isnan(tau[0]) and np.isfinite(tau[1])


def test_the_ensembles_autocorrelation_times_in_one_transform_are_each_ensembles():
    # run_ensembles transforms all ensembles' chains at once; each ensemble's τ must
    # be what autocorr_time gives for its chain alone (one with a longer memory).
    from bayestribo.inference.sampling import _autocorr_times

    rng = np.random.default_rng(10)
    x = rng.standard_normal((3, 500, 8, 4))
    x[1] += 0.3 * np.cumsum(rng.standard_normal((500, 8, 4)), axis=0)
    batched = _autocorr_times(x)
    for e in range(3):
        np.testing.assert_array_equal(batched[e], autocorr_time(x[e]))
    assert np.all(batched[1] > 2 * batched[0])


def _outcomes(proposals, factors=None):
    """Keys of discrete proposal outcomes (rounded coordinates, and factors)."""
    q = np.round(proposals.reshape(-1, proposals.shape[-1]), 9)
    if factors is not None:
        q = np.column_stack([q, np.round(factors.ravel(), 9)])
    return [tuple(row) for row in q]


def _same_distribution(ours, theirs):
    """Both outcome lists hit the same outcomes with frequencies that a χ² test of
    homogeneity cannot tell apart (p > 1e-4: a false alarm once in 10⁴ runs)."""
    keys = sorted(set(ours) | set(theirs))
    assert set(ours) == set(theirs)
    table = np.array([[ours.count(k) for k in keys], [theirs.count(k) for k in keys]])
    assert scipy.stats.chi2_contingency(table).pvalue > 1e-4


def test_grouped_de_proposals_are_emcees():
    # γ fixed (σ = 0): a proposal is s + γ (c_b − c_a) for one of the 12 ordered
    # pairs of 4 complementary walkers; the frequencies of the outcomes must match
    # emcee's DEMove.
    rng = np.random.default_rng(10)
    s = rng.standard_normal((1, 4, 2))
    c = rng.standard_normal((1, 4, 2))
    random = np.random.RandomState(1)
    ours = GroupedDEMove(1, sigma=0.0)
    theirs = emcee.moves.DEMove(sigma=0.0)
    theirs.setup(s[0])
    mine, ref = [], []
    for _ in range(3000):
        mine += _outcomes(ours.get_proposal(s, [c], random)[0])
        ref += _outcomes(theirs.get_proposal(s[0], [c[0]], random)[0])
    assert len(set(mine)) == 4 * 12
    _same_distribution(mine, ref)


def test_grouped_snooker_proposals_are_the_snooker_moves():
    # Two walkers in each of the three other splits: 8 choices of (z, z1, z2) in 6
    # orders; proposals and their Metropolis factors against the one-ensemble
    # DESnookerMove (ter Braak & Vrugt's; emcee 3.1.6's own is not a valid move).
    rng = np.random.default_rng(11)
    s = rng.standard_normal((1, 2, 3))
    c = [rng.standard_normal((1, 2, 3)) for _ in range(3)]
    random = np.random.RandomState(2)
    ours = GroupedDESnookerMove(1)
    theirs = DESnookerMove()
    mine, ref = [], []
    for _ in range(3000):
        q, f = ours.get_proposal(s, c, random)
        mine += _outcomes(q, f)
        q, f = theirs.get_proposal(s[0], [cj[0] for cj in c], random)
        ref += _outcomes(q, f)
    _same_distribution(mine, ref)


class _Ordered:
    """A stand-in random state for DESnookerMove.get_proposal: the first walker of each
    split, and (z, z1, z2) in a given order."""

    def __init__(self, order):
        self.order = order

    def randint(self, n):
        return 0

    def shuffle(self, w):
        w[:] = w[list(self.order)]


def test_the_snooker_move_is_undone_by_swapping_z1_and_z2():
    # ter Braak & Vrugt's snooker move is x → x + γ e (e·(z1 − z2)) along the line
    # through z (e the unit vector of x − z): with z1 and z2 swapped it moves back, and
    # its log factor (d − 1) log(|q − z|/|x − z|) changes sign: detailed balance.
    # emcee 3.1.6's (u = (x − z)/√|x − z|, half the factor) fails both: its step is a
    # stretch about z by 1 + γ e·(z1 − z2), a number with the parameters' units.
    rng = np.random.default_rng(18)
    x = rng.standard_normal((1, 4)) * [1e-5, 4e-5, 0.5, 1e-3]
    c = [rng.standard_normal((1, 4)) * [1e-5, 4e-5, 0.5, 1e-3] for _ in range(3)]
    move = DESnookerMove()
    q, f = move.get_proposal(x, c, _Ordered((0, 1, 2)))
    back, f_back = move.get_proposal(q, c, _Ordered((0, 2, 1)))
    assert not np.allclose(q, x)
    np.testing.assert_allclose(back, x, rtol=1e-12, atol=1e-15)
    assert f[0] == pytest.approx(-f_back[0], rel=1e-9)
    q, f = emcee.moves.DESnookerMove().get_proposal(x, c, _Ordered((0, 1, 2)))
    back, _ = emcee.moves.DESnookerMove().get_proposal(q, c, _Ordered((0, 2, 1)))
    if emcee.__version__ == "3.1.6":  # fixed upstream after it (dfm/emcee#531)
        assert not np.allclose(back, x, rtol=1e-6, atol=0.0)


@pytest.mark.parametrize("moves", ["grouped", pytest.param("emcee", marks=pytest.mark.validation)])
def test_scales_far_apart_are_sampled_with_their_spread(moves):
    # The single-run posterior's shape: ζ and μ_k correlated at -0.9 with sds 1e-5 and
    # 4e-5, μ_s/μ_k uniform on [1, 3], y0 with sd 1e-3. emcee 3.1.6's snooker move in
    # the DE mix gave the three narrow ones sds 4-5.5 % too small here (0.944-0.964,
    # ESS 8000 each); the corrected move gives them within the Monte Carlo error
    # (relative sd of an sd about 1/√(2·ESS) = 0.8 % each, their mean 0.5 %).
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
        n_walkers=16, n_ensembles=2, autocorr_multiple=250, max_steps=100_000, moves=moves
    )
    run = run_ensembles(target, start, settings, seed=20, names=["zeta", "mu_k", "r", "y0"])
    assert run.converged, run.reasons
    flat = run.chains.reshape(-1, 4)
    ratio = flat[:, [0, 1, 3]].std(axis=0) / sds
    se = 1.0 / np.sqrt(2.0 * run.ess[[0, 1, 3]])
    assert np.all(np.abs(ratio - 1.0) < 3.5 * se), ratio
    assert abs(ratio.mean() - 1.0) < 3.5 * np.sqrt(np.mean(se**2) / 3), ratio


@pytest.mark.parametrize("move", [GroupedDEMove(2), GroupedDESnookerMove(2)])
def test_grouped_moves_never_use_another_ensembles_walkers(move):
    # Ensemble 1's walkers are NaN: ensemble 0's proposals stay finite, ensemble 1's
    # are all NaN.
    rng = np.random.default_rng(12)
    size = 4 if isinstance(move, GroupedDEMove) else 2
    s = rng.standard_normal((2, size, 3))
    comps = move.nsplits - 1
    c = [rng.standard_normal((2, size, 3)) for _ in range(comps)]
    s[1] = np.nan
    for cj in c:
        cj[1] = np.nan
    random = np.random.RandomState(3)
    for _ in range(200):
        q, f = move.get_proposal(s, c, random)
        assert np.all(np.isfinite(q[0])) and np.all(np.isfinite(f[0]))
        assert np.all(np.isnan(q[1]))


@pytest.mark.parametrize("move", [GroupedDEMove(3), GroupedDESnookerMove(3)])
def test_a_steps_numbers_drawn_together_are_those_drawn_one_by_one(move):
    # propose draws the uniform numbers that follow one another in one call; they must
    # be the numbers of the draws one by one: the split, then per split the proposal
    # numbers (_draw) and the Metropolis uniforms.
    g, per, ndim = 3, 8, 3
    size = per // move.nsplits
    together = np.random.RandomState(5)
    order, uniform, gamma, log_u = move._numbers(together, g, per, ndim)
    random = np.random.RandomState(5)
    ref_order = np.argsort(random.rand(g, per), axis=1) + per * np.arange(g)[:, None]
    np.testing.assert_array_equal(order, ref_order)
    for split in range(move.nsplits):
        ref_uniform, ref_gamma = move._draw(random, g, size, ndim)
        np.testing.assert_array_equal(uniform[split], ref_uniform)
        np.testing.assert_array_equal(gamma[split], ref_gamma)
        np.testing.assert_array_equal(log_u[split], np.log(random.rand(g * size)))
    # and the generators are left in the same state
    assert together.rand() == random.rand()
    for array in (order, uniform, gamma, log_u):
        assert array.flags.c_contiguous


@pytest.mark.parametrize("moves", ["grouped", "emcee"])
def test_a_bounded_skewed_target_is_sampled(moves):
    # x ~ Gamma(2, 1) (log density −inf below 0) and y ~ N(x, 0.5²): the marginal of
    # x is a known skewed distribution with a hard edge, where the snooker move
    # matters. Kolmogorov-Smirnov on the thinned draws of both ways of running.
    def target(theta):
        t = np.atleast_2d(theta)
        x, y = t[:, 0], t[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            lp = np.where(x > 0, np.log(np.where(x > 0, x, 1.0)) - x, -np.inf)
        return lp - 0.5 * ((y - x) / 0.5) ** 2

    settings = SamplerSettings(n_walkers=8, n_ensembles=2, max_steps=20_000, moves=moves)
    start = np.abs(2.0 + 0.1 * np.random.default_rng(13).standard_normal((2, 8, 2)))
    run = run_ensembles(target, start, settings, seed=14, names=["x", "y"])
    assert run.converged, run.reasons
    flat = run.chains.reshape(-1, 2)
    assert scipy.stats.kstest(flat[:, 0], "gamma", args=(2.0,)).pvalue > 1e-4
    assert abs(flat[:, 0].mean() - 2.0) < 5 * np.sqrt(2.0 / run.ess[0])


def test_grouped_moves_refuse_a_log_probability_that_is_not_one_value_per_walker():
    from bayestribo.inference.moves import grouped_moves

    def column(theta):  # shape (n, 1): not one value per walker
        return _gaussian(theta)[:, None]

    sampler = emcee.EnsembleSampler(16, 3, column, moves=grouped_moves(2), vectorize=True)
    start = MEAN + 0.1 * np.random.default_rng(15).standard_normal((16, 3))
    with pytest.raises(BayestriboError, match="one value per walker"):
        sampler.run_mcmc(start, 5, skip_initial_state_check=True)


def test_the_grouped_sampler_gives_the_chains_of_emcees_own_sampler():
    # run_ensembles's sampler skips emcee's copy of the generator state in every step;
    # resumed chunk by chunk, its chains must be emcee's to the bit.
    from bayestribo.inference import sampling

    start = MEAN + 0.1 * np.random.default_rng(16).standard_normal((2, 8, 3))
    runs = []
    for cls in (sampling._ResumingSampler, emcee.EnsembleSampler):
        grouped = sampling._Grouped.__new__(sampling._Grouped)
        grouped.sampler_class = cls
        grouped.__init__(_gaussian, start, seed=17)
        for _ in range(3):
            grouped.run(100)
        runs.append(grouped.sampler.get_chain())
    assert isinstance(sampling._Grouped(_gaussian, start, 1).sampler, sampling._ResumingSampler)
    np.testing.assert_array_equal(runs[0], runs[1])
    assert runs[0].shape == (300, 16, 3) and np.unique(runs[0][:, 0, 0]).size > 10


def test_the_move_choice_draws_what_numpys_choice_draws():
    # one uniform draw per choice, numpy's rule: the same picks and the same stream
    from bayestribo.inference.sampling import _MoveChoice

    items = ["a", "b", "c"]
    for p in ([0.8, 0.2, 0.0], [0.1, 0.6, 0.3], [0.0, 0.0, 1.0]):
        ours, numpys = _MoveChoice(3), np.random.RandomState(3)
        picks = [ours.choice(items, p=np.array(p)) for _ in range(2000)]
        assert picks == [numpys.choice(items, p=np.array(p)) for _ in range(2000)]
        assert ours.random_sample() == numpys.random_sample()
    # other calls and bad probabilities are numpy's own
    ours, numpys = _MoveChoice(4), np.random.RandomState(4)
    assert list(ours.choice(items, size=5, p=[0.5, 0.5, 0.0])) == list(
        numpys.choice(items, size=5, p=[0.5, 0.5, 0.0])
    )
    with pytest.raises(ValueError, match="probabilities"):
        ours.choice(items, p=np.array([0.5, 0.6, 0.0]))
    with pytest.raises(ValueError):
        ours.choice(items, p=np.array([0.5, 0.5]))


def _banana(theta: np.ndarray) -> np.ndarray:
    """A thin curved ridge (y = x² within 0.01): its autocorrelation time under the
    DE moves is hundreds of steps."""
    d = np.atleast_2d(theta)
    return -0.5 * ((d[:, 1] - d[:, 0] ** 2) / 0.01) ** 2 - 0.5 * d[:, 0] ** 2 / 4.0


@pytest.mark.parametrize("ridge", [True, False])
def test_a_ridge_the_record_does_not_identify_stops_the_run_before_its_ceiling(ridge):
    """Where ``unidentified`` names a reason and the rule needs more steps than the
    ceiling even at the τ measured so far, the run stops there, saying so; where it
    names none, the same run goes on to its ceiling."""
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=3000)
    start = np.array([0.0, 0.0]) + 0.01 * np.random.default_rng(9).standard_normal((2, 16, 2))
    calls = []

    def unidentified(draws: np.ndarray) -> list[str]:
        calls.append(draws.shape)
        return ["a ridge"] if ridge else []

    run = run_ensembles(_banana, start, settings, seed=4, unidentified=unidentified)
    assert not run.converged and calls and all(shape[1] == 2 for shape in calls)
    stopped = [r for r in run.reasons if r.startswith("stopped at")]
    if ridge:
        assert run.n_steps < settings.max_steps
        assert (
            stopped == [r for r in stopped if re.search(r"beyond the ceiling of 3000$", r)]
            and len(stopped) == 1
        )
    else:
        assert run.n_steps == settings.max_steps and not stopped
