"""The importance-resampling correction of a surrogate posterior's draws
(bayestribo/inference/correction.py), on targets whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from bayestribo.inference.correction import (
    MAX_CORRECTED_CV,
    importance_corrected,
    resample_in_order,
)
from bayestribo.inference.sampling import SamplerRun, rhat
from bayestribo.inference.surrogate import MAX_WEIGHT_CV, SurrogateCheck


def _run(chains: np.ndarray, log_prob: np.ndarray) -> SamplerRun:
    """A run of independent draws (τ = 1) with its diagnostics."""
    n_chains, n_draws, d = chains.shape
    return SamplerRun(
        chains=chains,
        log_prob=log_prob,
        autocorr_time=np.ones(d),
        n_steps=n_draws,
        burn=0,
        thin=1,
        acceptance_fraction=1.0,
        ess=np.full(d, float(n_chains * n_draws)),
        rhat=rhat(chains),
        converged=True,
    )


def _normal_run(rng: np.random.Generator, shape=(2, 3000)) -> SamplerRun:
    """Draws of the standard normal, its log density as the run's log_prob."""
    x = rng.standard_normal((*shape, 1))
    return _run(x, scipy.stats.norm.logpdf(x[..., 0]))


def test_resampling_in_order_keeps_each_draw_its_weight_in_copies():
    rng = np.random.default_rng(1)
    w = rng.uniform(0.5, 1.5, 200)
    idx = resample_in_order(w, 0.37)
    assert idx.size == w.size
    assert np.all(np.diff(idx) >= 0)
    expected = w.size * w / w.sum()
    counts = np.bincount(idx, minlength=w.size)
    assert np.all((counts == np.floor(expected)) | (counts == np.ceil(expected)))
    # equal weights keep every draw once
    np.testing.assert_array_equal(resample_in_order(np.ones(50), 0.5), np.arange(50))


def test_the_corrected_draws_are_of_the_exact_posterior():
    """Surrogate N(0, 1), exact N(0.1, 1.05²): weights' cv about 0.12 (above the
    check's limit, below the correction's); the corrected mean and sd are the exact
    ones within four Monte Carlo standard errors, the uncorrected mean is not."""
    rng = np.random.default_rng(2)
    run = _normal_run(rng)
    exact = scipy.stats.norm(0.1, 1.05)
    out = importance_corrected(run, lambda x: (exact.logpdf(x[:, 0]), None), rng, rhat_max=1.01)
    assert out is not None
    assert MAX_WEIGHT_CV < out.weight_cv <= MAX_CORRECTED_CV
    draws = out.run.chains.reshape(-1)
    # Kish's effective number of the weighted draws
    n_eff = draws.size / (1.0 + out.weight_cv**2)
    error = 1.05 / np.sqrt(n_eff)
    assert abs(draws.mean() - 0.1) < 4.0 * error
    assert abs(run.chains.mean() - 0.1) > 4.0 * error
    # the sd of a normal sample's sd is σ/√(2n)
    assert abs(draws.std() - 1.05) < 4.0 * 1.05 / np.sqrt(2.0 * n_eff)
    # the log_prob kept is the exact density of the draws kept, and every draw kept
    # is one of the surrogate's
    np.testing.assert_allclose(out.run.log_prob, exact.logpdf(out.run.chains[..., 0]))
    assert np.isin(draws, run.chains.reshape(-1)).all()
    assert out.run.chains.shape == run.chains.shape
    assert np.all(out.run.ess < run.ess)
    assert out.pointwise is None


def test_the_pointwise_values_given_follow_the_draws_kept():
    """A density that gives each row's pointwise values too: the corrected run's are
    those of the draws it kept, in their place."""
    rng = np.random.default_rng(5)
    run = _normal_run(rng, (2, 500))
    exact = scipy.stats.norm(0.05, 1.0)

    def density(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return exact.logpdf(x[:, 0]), np.column_stack([x[:, 0], 2.0 * x[:, 0]])

    out = importance_corrected(run, density, rng, 1.01)
    assert out is not None and out.pointwise.shape == (2, 500, 2)
    np.testing.assert_array_equal(out.pointwise[..., 0], out.run.chains[..., 0])
    np.testing.assert_array_equal(out.pointwise[..., 1], 2.0 * out.run.chains[..., 0])


def test_the_exact_density_is_the_posteriors_from_one_pi(bundled_run):
    """exact_density gives the posterior's own log density (compiled) and pointwise
    log-likelihood, a law without a closed form, from one evaluation of Π."""
    from bayestribo.inference import pipeline
    from bayestribo.inference.correction import exact_density
    from bayestribo.inference.start import maximum_a_posteriori

    prepared = pipeline.prepare(bundled_run, seed=1)
    posterior = pipeline.build_posterior(prepared.data, law="viscous+quadratic")
    assert not posterior.law.closed_form
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    rows = np.random.default_rng(6).multivariate_normal(theta, cov, size=12)
    rows[:, posterior.names.index("c2")] = np.abs(rows[:, posterior.names.index("c2")])
    rows[0, posterior.names.index("y0")] = np.inf  # outside the support
    lp, pointwise = exact_density(posterior)(rows)
    assert lp[0] == -np.inf and np.all(np.isnan(pointwise[0]))
    np.testing.assert_allclose(lp[1:], posterior(rows[1:]), rtol=1e-10, atol=1e-8)
    np.testing.assert_allclose(pointwise[1:], posterior.pointwise(rows[1:]), rtol=1e-12)


@pytest.mark.parametrize(
    "exact",
    [scipy.stats.norm(0.0, 2.0), scipy.stats.norm(1.5, 1.0)],
    ids=["wider than the surrogate", "shifted far"],
)
def test_a_surrogate_that_misses_the_exact_mass_is_not_corrected(exact):
    """An exact posterior twice as wide (the weights unbounded in the tails: a Pareto
    k̂ above 1/2) or shifted by 1.5 sd (cv above 1) is left to the exact sampler."""
    rng = np.random.default_rng(3)
    run = _normal_run(rng)
    assert importance_corrected(run, lambda x: (exact.logpdf(x[:, 0]), None), rng, 1.01) is None


def test_a_draw_outside_the_exact_support_refuses_the_correction():
    rng = np.random.default_rng(4)
    run = _normal_run(rng)

    def exact(x: np.ndarray) -> tuple[np.ndarray, None]:
        return np.where(x[:, 0] > 3.0, -np.inf, scipy.stats.norm.logpdf(x[:, 0])), None

    assert importance_corrected(run, exact, rng, 1.01) is None


def test_a_corrected_check_passes_and_says_so():
    check = SurrogateCheck(1800, 0.09, 0.1, 2, corrected=True)
    assert check.passed and check.to_dict()["corrected"] is True
    assert not SurrogateCheck(128, 0.09, 0.1, 2).passed


class _Scripted:
    """Stand-ins for the surrogate loop's stages (``bayestribo.inference.chains``):
    each surrogate's check gives the next weights' cv of ``cvs``, each correction the
    next answer of ``corrections`` (True: kept)."""

    def __init__(self, monkeypatch, cvs: list[float], corrections: list[bool]) -> None:
        import types

        from bayestribo.inference import chains

        self.cvs, self.corrections = list(cvs), list(corrections)
        self.checks: list[int] = []
        self.corrected: list[int] = []
        rng = np.random.default_rng(5)
        self.run = _normal_run(rng, shape=(2, 40))
        target = types.SimpleNamespace(uses_compiled=True)
        monkeypatch.setattr(chains, "surrogate_posterior", lambda *a: target)
        monkeypatch.setattr(chains, "regressed_posterior", lambda *a: target)
        monkeypatch.setattr(chains, "run_or_failure", lambda *a, **k: self.run)
        monkeypatch.setattr(chains, "exact_density", lambda posterior: None)
        monkeypatch.setattr(chains, "check", self.check)
        monkeypatch.setattr(chains, "importance_corrected", self.correct)

    def check(self, exact, surrogate, draws, rng, attempt=1) -> SurrogateCheck:
        self.checks.append(attempt)
        return SurrogateCheck(128, self.cvs.pop(0), 0.1, attempt, draws[0])

    def correct(self, run, exact, rng, rhat_max):
        import types

        self.corrected.append(self.checks[-1])
        if not self.corrections.pop(0):
            return None
        return types.SimpleNamespace(
            run=run, draws=80, weight_cv=0.2, log_weight_sd=0.1, pointwise=None
        )

    def sample(self, weighted: int = 0):
        from bayestribo.inference.chains import _sample_surrogate
        from bayestribo.inference.sampling import SamplerSettings

        walkers = np.zeros((2, 32, 1))
        return _sample_surrogate(
            None, np.zeros(1), np.eye(1), walkers, SamplerSettings(), 1, False, weighted=weighted
        )


def test_a_refused_correction_within_reach_is_followed_by_further_surrogates(monkeypatch):
    """The second surrogate comes within the correction's reach and its correction is
    refused, the next ones miss by more: further surrogates are built, up to
    ``CORRECTING_ATTEMPTS``, rather than the exact posterior sampled, and the last
    one's correction is kept."""
    from bayestribo.inference.correction import CORRECTING_ATTEMPTS, NEAR_CORRECTED_CV
    from bayestribo.inference.surrogate import ATTEMPTS

    assert CORRECTING_ATTEMPTS > ATTEMPTS
    near = 0.5 * MAX_CORRECTED_CV
    far = 2.0 * NEAR_CORRECTED_CV
    cvs = [far, near] + [far] * (CORRECTING_ATTEMPTS - 3) + [near]
    scripted = _Scripted(monkeypatch, cvs, [False, True])
    run, checked, _, _ = scripted.sample()
    assert scripted.checks == list(range(1, CORRECTING_ATTEMPTS + 1))
    assert scripted.corrected == [2, CORRECTING_ATTEMPTS]
    assert run is scripted.run and checked.corrected and checked.attempt == CORRECTING_ATTEMPTS


def test_checks_a_little_beyond_the_reach_are_followed_by_further_surrogates(monkeypatch):
    """Surrogates built again whose checks miss the correction's reach by a little (cv
    between ``MAX_CORRECTED_CV`` and ``NEAR_CORRECTED_CV``) up to ``ATTEMPTS``: the
    next one, within reach, is corrected rather than the exact posterior sampled."""
    from bayestribo.inference.correction import NEAR_CORRECTED_CV
    from bayestribo.inference.surrogate import ATTEMPTS

    beyond = 0.5 * (MAX_CORRECTED_CV + NEAR_CORRECTED_CV)
    cvs = [2.0 * NEAR_CORRECTED_CV] + [beyond] * (ATTEMPTS - 1) + [0.5 * MAX_CORRECTED_CV]
    scripted = _Scripted(monkeypatch, cvs, [True])
    run, checked, _, _ = scripted.sample()
    assert scripted.checks == list(range(1, ATTEMPTS + 2))
    assert scripted.corrected == [ATTEMPTS + 1]
    assert run is scripted.run and checked.corrected


def test_surrogates_never_near_the_reach_stop_at_the_usual_attempts(monkeypatch):
    """Checks all beyond ``NEAR_CORRECTED_CV``: the exact posterior after
    ``ATTEMPTS`` surrogates, as before, and no correction tried."""
    from bayestribo.inference.correction import NEAR_CORRECTED_CV
    from bayestribo.inference.surrogate import ATTEMPTS

    far = 2.0 * NEAR_CORRECTED_CV
    scripted = _Scripted(monkeypatch, [far] * 10, [])
    run, _, target, _ = scripted.sample()
    assert run is None and target is None
    assert scripted.checks == list(range(1, ATTEMPTS + 1)) and scripted.corrected == []


def test_weights_at_few_draws_weight_them_to_the_exact_posterior():
    """Surrogate N(0, 1), exact N(0.1, 1.05²): 400 evenly spaced draws, weighted, give
    the exact mean and sd within four Monte Carlo standard errors; a surrogate far from
    the exact posterior gives no weights."""
    from bayestribo.inference.correction import evenly_spaced, weights_at
    from bayestribo.inference.halves_statistic import weighted_moments

    rng = np.random.default_rng(5)
    run = _normal_run(rng)

    def exact(rows: np.ndarray) -> np.ndarray:
        return scipy.stats.norm.logpdf(rows[:, 0], 0.1, 1.05)

    picks = evenly_spaced(run, 400)
    assert picks.size == 400 and picks[0] == 0 and picks[-1] == 5999
    w = weights_at(run, exact, picks)
    x = run.chains.reshape(-1, 1)[picks]
    expected = np.exp(exact(x) - run.log_prob.reshape(-1)[picks])
    np.testing.assert_allclose(w, expected / expected.max(), rtol=1e-12)
    mean, var, _ = weighted_moments(x, w)
    kish = w.sum() ** 2 / np.sum(w * w)
    assert abs(mean[0] - 0.1) < 4 * 1.05 / np.sqrt(kish)
    assert abs(np.sqrt(var[0]) - 1.05) < 4 * 1.05 / np.sqrt(2 * kish)

    def far(rows: np.ndarray) -> np.ndarray:
        return scipy.stats.norm.logpdf(rows[:, 0], 1.5, 0.5)

    assert weights_at(run, far, picks) is None


def _weights_scripted(monkeypatch, holds: list[bool]) -> list[tuple[int, float]]:
    """``weights_at`` in the surrogate loop answering each call with the next of
    ``holds`` (True: weights given); returns the calls' (draws, max_cv)."""
    from bayestribo.inference import chains

    calls: list[tuple[int, float]] = []

    def weights_at(run, posterior, picks, max_cv):
        calls.append((len(picks), max_cv))
        return np.ones(len(picks)) if holds.pop(0) else None

    monkeypatch.setattr(chains, "weights_at", weights_at)
    return calls


def test_a_weighted_caller_keeps_the_first_surrogate_whose_weights_hold(monkeypatch):
    """A caller that weights its draws (the halves): the first surrogate, its check
    failed within ``MAX_WEIGHTED_CV``, is returned as it is where the weights of the
    draws it uses hold by that limit; no further surrogate, no correction."""
    from bayestribo.inference.correction import MAX_WEIGHTED_CV

    between = 0.5 * (MAX_CORRECTED_CV + MAX_WEIGHTED_CV)
    scripted = _Scripted(monkeypatch, [between] * 5, [])
    calls = _weights_scripted(monkeypatch, [True])
    run, checked, target, pointwise = scripted.sample(weighted=50)
    assert scripted.checks == [1] and scripted.corrected == []
    assert calls == [(50, MAX_WEIGHTED_CV)]
    assert run is scripted.run and not checked.passed and target is not None
    assert pointwise is None


def test_a_weighted_caller_whose_weights_do_not_hold_gets_the_next_surrogate(monkeypatch):
    """The first surrogate's weights refused, the second's check within the
    correction's reach and its weights refused too: that one is corrected, as for
    any caller; a check beyond ``MAX_WEIGHTED_CV`` asks for no weights."""
    from bayestribo.inference.correction import MAX_WEIGHTED_CV

    between = 0.5 * (MAX_CORRECTED_CV + MAX_WEIGHTED_CV)
    far = 2.0 * MAX_WEIGHTED_CV
    scripted = _Scripted(monkeypatch, [far, between, 0.5 * MAX_CORRECTED_CV], [True])
    calls = _weights_scripted(monkeypatch, [False, False])
    run, checked, _, _ = scripted.sample(weighted=50)
    assert scripted.checks == [1, 2, 3] and scripted.corrected == [3]
    assert calls == [(50, MAX_WEIGHTED_CV)] * 2
    assert run is scripted.run and checked.corrected


def test_a_caller_that_does_not_weight_never_keeps_a_failed_check(monkeypatch):
    """Without ``weighted``, a first check within ``MAX_WEIGHTED_CV`` is followed by
    another surrogate, as before."""
    from bayestribo.inference.correction import MAX_WEIGHTED_CV

    between = 0.5 * (MAX_CORRECTED_CV + MAX_WEIGHTED_CV)
    scripted = _Scripted(monkeypatch, [between, 0.5 * MAX_CORRECTED_CV], [True])
    calls = _weights_scripted(monkeypatch, [])
    _, checked, _, _ = scripted.sample()
    assert scripted.checks == [1, 2] and scripted.corrected == [2] and calls == []
    assert checked.corrected


def test_weights_at_the_weighted_limit_are_given_only_when_asked_for():
    """Surrogate N(0, 1), exact N(0.45, 1): the weights' cv about 0.47, beyond the
    correction's limit and within the weighted callers'; their Pareto k̂ below 1/2."""
    from bayestribo.inference.correction import MAX_WEIGHTED_CV, evenly_spaced, weights_at

    rng = np.random.default_rng(6)
    run = _normal_run(rng)

    def exact(rows: np.ndarray) -> np.ndarray:
        return scipy.stats.norm.logpdf(rows[:, 0], 0.45, 1.0)

    picks = evenly_spaced(run, 400)
    assert weights_at(run, exact, picks) is None
    w = weights_at(run, exact, picks, MAX_WEIGHTED_CV)
    assert w is not None
    assert MAX_CORRECTED_CV < np.std(w) / np.mean(w) <= MAX_WEIGHTED_CV

    def wider(rows: np.ndarray) -> np.ndarray:
        return scipy.stats.norm.logpdf(rows[:, 0], 0.0, 2.0)

    # unbounded weights (Pareto k̂ above 1/2) are refused at any cv limit
    assert weights_at(run, wider, picks, MAX_WEIGHTED_CV) is None
