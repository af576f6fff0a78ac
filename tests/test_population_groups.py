"""Population of repeats from per-run posterior samples, against exact answers.

The reference case is the normal-normal model: run i measures y_i ~ N(θ_i, s_i²) and
θ_i ~ N(μ, σ²). Each run is "fitted" alone with a normal prior, so its posterior is
normal and is sampled exactly; the joint posterior of (μ, σ) follows from
y_i ~ N(μ, σ² + s_i²) by numerical integration on a grid. The sample-reuse route
(per-run samples, per-run priors divided out) must agree with it.

Tolerances. The population sampler runs its 2 ensembles × 16 walkers until 50
autocorrelation times after burn (τ ≈ 12-15 steps, about 800 steps here): an effective
sample size of about 1700, so a quantile's Monte Carlo standard error is about 0.04
posterior sd. The importance-sampling estimate adds its own: with an informative
per-run prior divided out, the weights 1/prior grow where a run's likelihood reaches
beyond its posterior samples, so σ's upper quantiles converge slowly in the number of
samples S. Under the default σ prior (∝ 1/σ, a narrower posterior of σ than the
half-Cauchy's) S = 1000 left σ's 90 % quantile 0.3 sd off on the reference case and
S = 4000 within 0.16 sd on four data sets, so that case keeps S = 4000 samples per
run. Quantiles must agree to 0.2 posterior sd, which the tests also show is tight
enough to reject the answer obtained without dividing out the per-run priors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from bayestribo.errors import BayestriboError, ConvergenceWarning
from bayestribo.inference.sampling import NaNLogProbabilityError
from bayestribo.population import (
    HalfCauchy,
    HalfNormal,
    LogUniform,
    MarginalLikelihood,
    RunSamples,
    ScaleFree,
    population,
    run_samples,
    sigma_priors,
    slope_probabilities,
    trend,
)
from bayestribo.population.sampler import sample_hyperparameters

QS = np.array([0.1, 0.5, 0.9])
TOL_SD = 0.2  # in posterior standard deviations; see the module docstring


def _normal_logpdf(x, mean, sd):
    return -0.5 * ((x - mean) / sd) ** 2 - math.log(sd * math.sqrt(2 * math.pi))


def _normal_runs(y, s, prior_mean, prior_sd, rng, n_samples=1000, meta=None):
    """Exact per-run posterior samples of the normal-normal model, one parameter."""
    runs = []
    for i, (yi, si) in enumerate(zip(y, s, strict=True)):
        v = 1 / (1 / si**2 + 1 / prior_sd**2)
        m = v * (yi / si**2 + prior_mean / prior_sd**2)
        x = rng.normal(m, math.sqrt(v), n_samples)
        md = {"run_id": f"r{i}", **(meta[i] if meta else {})}
        runs.append(RunSamples(f"r{i}", {"zeta": x}, _normal_logpdf(x, prior_mean, prior_sd), md))
    return runs


def _grid_quantiles(grid, weights, qs):
    c = np.cumsum(weights) / weights.sum()
    return np.interp(qs, c, grid)


def _grid_posterior(y, s, prior):
    """Exact marginal posteriors of μ (flat prior) and σ, on grids.

    For each σ the flat μ integrates out in closed form (a normal of mean ȳ_w, the
    precision-weighted mean, and variance 1/Σw); μ's marginal is the mixture of those
    normals over σ's posterior, tabulated on a grid wide enough for σ's tail. σ is on
    a log grid weighted by its spacing (the default prior ∝ 1/σ reaches far down).
    """
    sigs = np.geomspace(1e-7, 0.1, 4000)
    var = sigs[:, None] ** 2 + np.asarray(s)[None, :] ** 2
    w = 1.0 / var
    mean_w = (w * y).sum(axis=1) / w.sum(axis=1)
    ll = (
        prior.logpdf(sigs)
        + np.log(np.gradient(sigs))
        - 0.5 * np.log(var).sum(axis=1)
        - 0.5 * np.log(w.sum(axis=1))
        - 0.5 * (w * (y[None, :] - mean_w[:, None]) ** 2).sum(axis=1)
    )
    ps = np.exp(ll - ll.max())
    sd_w = 1.0 / np.sqrt(w.sum(axis=1))
    mus = np.linspace(y.min() - 0.3, y.max() + 0.3, 12001)
    # the mixture's density on the μ grid, a block of σ at a time (a whole 4000 × 12001
    # table of normal densities is some 400 MB)
    pm = np.zeros_like(mus)
    for k in range(0, sigs.size, 250):
        z = (mus[None, :] - mean_w[k : k + 250, None]) / sd_w[k : k + 250, None]
        pm += (ps[k : k + 250] / sd_w[k : k + 250]) @ np.exp(-0.5 * z * z)
    return mus, pm / math.sqrt(2 * math.pi), sigs, ps


def _default(runs, name="zeta"):
    """The default σ prior (scale 0.01) as a group of ``runs`` resolves it."""
    return ScaleFree(0.01).for_runs([np.std(r.values[name]) for r in runs])


def _sd(grid, w):
    w = w / w.sum()
    return math.sqrt((w * grid**2).sum() - (w * grid).sum() ** 2)


@pytest.fixture(scope="module")
def normal_case():
    rng = np.random.default_rng(11)
    s = np.array([0.002, 0.0015, 0.003, 0.0025])
    theta = rng.normal(0.02, 0.003, len(s))
    y = rng.normal(theta, s)
    # An informative per-run prior (mean 0.03, sd 0.004): dividing it out matters.
    runs = _normal_runs(y, s, 0.03, 0.004, rng, n_samples=4000)
    return y, s, runs


def test_sample_reuse_agrees_with_the_exact_joint_posterior(normal_case):
    y, s, runs = normal_case
    prior = _default(runs)  # the default
    pop = population(runs, ("zeta",), seed=5, max_samples=None)
    g = pop.pooled
    assert g.diagnostics["converged"]
    mus, pm, sigs, ps = _grid_posterior(y, s, prior)
    for samples, grid, w in ((g.mean["zeta"], mus, pm), (g.sigma["zeta"], sigs, ps)):
        exact = _grid_quantiles(grid, w, QS)
        got = np.quantile(samples, QS)
        np.testing.assert_array_less(np.abs(got - exact), TOL_SD * _sd(grid, w))


@pytest.mark.validation  # the power of the tolerance above, a second population
def test_not_dividing_out_the_prior_is_rejected_by_the_same_tolerance(normal_case):
    # The same samples with a flat "prior" (nothing divided out) double-count the
    # informative per-run prior: the test's tolerance must see the difference.
    y, s, runs = normal_case
    wrong = [RunSamples(r.name, r.values, np.zeros(r.n_samples), r.metadata) for r in runs]
    g = population(wrong, ("zeta",), seed=5).pooled  # 1000 of each run's samples: enough here
    mus, pm, _, _ = _grid_posterior(y, s, _default(runs))
    exact = _grid_quantiles(mus, pm, QS)
    assert np.abs(np.median(g.mean["zeta"]) - exact[1]) > 3 * TOL_SD * _sd(mus, pm)


@pytest.mark.validation  # a 20 000-step reference emcee run of the joint model
def test_correlated_parameters_agree_with_a_joint_fit():
    """Two parameters with correlated per-run posteriors (like ζ and μ_k).

    Reference: the joint model with each run's θ_i integrated out analytically,
    y_i ~ N₂(m, C_i + diag(σ²)), sampled by its own emcee run.
    """
    import emcee

    rng = np.random.default_rng(3)
    n = 5
    m_true, sig_true = np.array([0.024, 0.029]), np.array([0.0012, 0.0036])
    sd = np.array([0.0015, 0.003])
    cov = np.array([[sd[0] ** 2, -0.8 * sd[0] * sd[1]], [-0.8 * sd[0] * sd[1], sd[1] ** 2]])
    ys = rng.normal(m_true, sig_true, (n, 2))
    ys = np.array([rng.multivariate_normal(t, cov) for t in ys])
    p_mean, p_sd = np.array([0.03, 0.03]), np.array([0.02, 0.02])
    p_cov = np.diag(p_sd**2)
    runs = []
    for i in range(n):
        post_cov = np.linalg.inv(np.linalg.inv(cov) + np.linalg.inv(p_cov))
        post_mean = post_cov @ (np.linalg.solve(cov, ys[i]) + np.linalg.solve(p_cov, p_mean))
        x = rng.multivariate_normal(post_mean, post_cov, 1000)
        lp = _normal_logpdf(x[:, 0], p_mean[0], p_sd[0]) + _normal_logpdf(
            x[:, 1], p_mean[1], p_sd[1]
        )
        runs.append(RunSamples(f"r{i}", {"zeta": x[:, 0], "mu_k": x[:, 1]}, lp))
    g = population(runs, ("zeta", "mu_k"), seed=2).pooled
    assert g.diagnostics["converged"]

    priors = [_default(runs, "zeta"), _default(runs, "mu_k")]  # the default

    def log_post(p):  # vectorised over walkers: p has shape (W, 4)
        m, ls = p[:, :2], np.clip(p[:, 2:], -50, 50)
        sig2 = np.exp(2 * ls)
        a = cov[0, 0] + sig2[:, 0]
        d = cov[1, 1] + sig2[:, 1]
        det = a * d - cov[0, 1] ** 2
        out = priors[0].logpdf(np.exp(ls[:, 0])) + priors[1].logpdf(np.exp(ls[:, 1]))
        out = out + ls.sum(axis=1) - 0.5 * n * np.log(det)
        for y in ys:
            u, v = y[0] - m[:, 0], y[1] - m[:, 1]
            out = out - 0.5 * (d * u * u - 2 * cov[0, 1] * u * v + a * v * v) / det
        return out

    start = np.concatenate([ys.mean(0), np.log(sd)]) + 1e-4 * rng.normal(size=(32, 4))
    ref = emcee.EnsembleSampler(32, 4, log_post, vectorize=True)
    ref.random_state = np.random.RandomState(1).get_state()
    ref.run_mcmc(
        start, 20000
    )  # a near-exact reference: its own error stays far below the tolerance
    chain = ref.get_chain(discard=2000, thin=10, flat=True)
    pairs = {
        "mean zeta": (g.mean["zeta"], chain[:, 0]),
        "mean mu_k": (g.mean["mu_k"], chain[:, 1]),
        "sigma zeta": (g.sigma["zeta"], np.exp(chain[:, 2])),
        "sigma mu_k": (g.sigma["mu_k"], np.exp(chain[:, 3])),
    }
    for name, (got, want) in pairs.items():
        diff = np.abs(np.quantile(got, QS) - np.quantile(want, QS))
        tol = math.sqrt(2) * TOL_SD * np.ones(QS.size)  # both sides Monte Carlo estimates
        if name == "sigma mu_k":
            # A known bias of the sample reuse, not Monte Carlo error: against a
            # 40000-step reference the 0.9 quantile of this σ comes out low by
            # 0.24 ± 0.05 posterior sd over 8 population seeds (the 0.1 and 0.5
            # quantiles agree within 0.09 sd). The bound keeps it from growing.
            tol[-1] = 0.4
        assert np.all(diff < tol * want.std()), name


def test_three_repeats_say_little_about_sigma_many_repeats_pin_it_down():
    rng = np.random.default_rng(8)
    mu, sigma = 0.0236, 0.0012
    s_run = 0.0003  # per-run posterior sd, small against σ as in the paper's runs

    def fit(n):
        y = rng.normal(rng.normal(mu, sigma, n), s_run)
        runs = _normal_runs(y, np.full(n, s_run), 0.03, 0.02, rng, n_samples=400)
        return population(runs, ("zeta",), seed=1).pooled

    few, many = fit(3), fit(30)
    lo3, hi3 = np.quantile(few.sigma["zeta"], [0.025, 0.975])
    lo30, hi30 = np.quantile(many.sigma["zeta"], [0.025, 0.975])
    # The classical 95 % interval of a standard deviation from n values spans a factor
    # √(χ²_{0.975}/χ²_{0.025}) with n − 1 degrees of freedom: about 12 for n = 3, 1.8
    # for n = 30. The posterior must say as much: wider than 10 for three repeats;
    # narrower than 2.5 and covering the truth for thirty.
    assert hi3 / lo3 > 10
    assert lo30 < sigma < hi30 and hi30 / lo30 < 2.5
    assert np.quantile(many.mean["zeta"], 0.025) < mu < np.quantile(many.mean["zeta"], 0.975)


def _trend_exact(x, y, s, prior, sig_grid):
    """Exact posterior of the slope: flat (a, b) integrated analytically per σ."""
    design = np.column_stack([np.ones_like(x), x])
    log_w, means, sds = [], [], []
    for sg, step in zip(sig_grid, np.gradient(sig_grid), strict=True):
        w = 1 / (sg**2 + s**2)
        a = design.T @ (w[:, None] * design)
        beta = np.linalg.solve(a, design.T @ (w * y))
        resid = y - design @ beta
        cov = np.linalg.inv(a)
        log_w.append(
            prior.logpdf(sg)
            + math.log(step)
            + 0.5 * np.log(w).sum()
            - 0.5 * (w * resid**2).sum()
            - 0.5 * np.linalg.slogdet(a)[1]
        )
        means.append(beta[1])
        sds.append(math.sqrt(cov[1, 1]))
    log_w = np.array(log_w)
    wts = np.exp(log_w - log_w.max())
    return wts / wts.sum(), np.array(means), np.array(sds)


def test_trend_slope_agrees_with_the_exact_posterior():
    from scipy.stats import norm

    rng = np.random.default_rng(21)
    loads = np.repeat([0.07, 0.12, 0.31, 0.46, 0.59], 2)
    s = np.full(len(loads), 0.001)
    y = rng.normal(0.022 + 0.004 * loads + rng.normal(0, 0.001, len(loads)), s)
    meta = [{"load_N": float(v)} for v in loads]
    runs = _normal_runs(y, s, 0.03, 0.02, rng, n_samples=1000, meta=meta)
    tr = trend(runs, "load_N", ("zeta",), seed=4)
    assert tr.diagnostics["converged"]
    # sampled with the independence move in the mix, its adaptation phase not kept
    from bayestribo.inference.sampling import SamplerSettings
    from bayestribo.population.sampler import POPULATION_INDEPENDENCE

    assert tr.diagnostics["independence_weight"] == POPULATION_INDEPENDENCE
    assert tr.diagnostics["burn"] >= SamplerSettings.adapt_steps
    w, means, sds = _trend_exact(loads, y, s, _default(runs), np.geomspace(1e-6, 0.1, 3000))
    grid = np.linspace(means.min() - 8 * sds.max(), means.max() + 8 * sds.max(), 4000)
    cdf = (w[:, None] * norm.cdf((grid[None] - means[:, None]) / sds[:, None])).sum(0)
    exact_q = np.interp(QS, cdf, grid)
    exact_sd = math.sqrt((w * (sds**2 + means**2)).sum() - (w * means).sum() ** 2)
    got = tr.slope["zeta"]
    np.testing.assert_array_less(np.abs(np.quantile(got, QS) - exact_q), TOL_SD * exact_sd)
    p_pos = float((w * norm.sf(-means / sds)).sum())
    # P(b > 0): Monte Carlo error of a probability p with ESS ~ 1500 is < 0.013.
    assert abs(tr.slope_summary("zeta")["prob_positive"] - p_pos) < 0.04
    # The intercept is reported at load 0.
    assert abs(np.median(tr.intercept["zeta"]) - 0.022) < 4 * tr.intercept["zeta"].std()


def test_trend_finds_a_simulated_slope_and_none_without_one():
    rng = np.random.default_rng(5)
    loads = np.repeat([0.07, 0.12, 0.31, 0.46, 0.59], 3)
    s = np.full(len(loads), 0.0005)
    meta = [{"load_N": float(v)} for v in loads]
    out = {}
    for slope in (0.0, 0.01):
        y = rng.normal(0.0236 + slope * loads + rng.normal(0, 0.0012, len(loads)), s)
        runs = _normal_runs(y, s, 0.03, 0.02, rng, n_samples=300, meta=meta)
        out[slope] = trend(runs, "load_N", ("zeta",), seed=1, rope={"zeta": 0.001}).slope_summary(
            "zeta"
        )
    assert out[0.01]["prob_positive"] > 0.99 and out[0.01]["interval"][0] > 0
    assert out[0.01]["prob_outside_rope"] > 0.95
    assert out[0.0]["interval"][0] < 0 < out[0.0]["interval"][1]
    assert out[0.0]["prob_sign"] < 0.975


def test_groups_differences_and_pooled():
    rng = np.random.default_rng(9)
    s = np.full(3, 0.0005)
    runs = []
    for load, mean in ((0.12, 0.02), (0.46, 0.04)):
        y = rng.normal(rng.normal(mean, 0.001, 3), s)
        for r in _normal_runs(y, s, 0.03, 0.02, rng, n_samples=300):
            runs.append(RunSamples(f"{load}-{r.name}", r.values, r.log_prior, {"load_N": load}))
    pop = population(runs, ("zeta",), by="load_N", seed=3)
    for group in (*pop.groups.values(), pop.pooled):
        diag = group.diagnostics
        assert diag["converged"], diag["reasons"]
        # Converged by the one stopping rule: 50 autocorrelation times after burn, and
        # R-hat and ESS by sampled hyperparameter, as the single-run fit reports them.
        assert diag["n_steps"] - diag["burn"] >= 50 * diag["autocorr_time_max"]
        assert set(diag["rhat"]) == {"beta[0,zeta]", "log_sigma[zeta]"} == set(diag["ess"])
        assert max(diag["rhat"].values()) == diag["rhat_max"] < 1.01
        assert min(diag["ess"].values()) == diag["ess_min"] > 1000
    assert list(pop.groups) == [0.12, 0.46]
    assert pop.groups[0.12].runs == ("0.12-r0", "0.12-r1", "0.12-r2")
    assert pop.pooled is not None and len(pop.pooled.runs) == 6
    d = pop.difference("zeta", 0.46, 0.12)
    assert d["prob_positive"] > 0.99 and d["interval"][0] > 0
    assert abs(d["mean"] - 0.02) < 4 * d["sd"]
    assert len(pop.differences("zeta")) == 1
    summary = pop.to_dict()
    first = [r for r in runs if r.metadata["load_N"] == 0.12]
    assert summary["groups"][0]["parameters"]["zeta"]["sigma_prior"] == _default(first).describe()
    assert summary["pooled"]["n_runs"] == 6
    # Reproducible, and independent of the order of the runs.
    again = population(runs[::-1], ("zeta",), by="load_N", pooled=False, seed=3)
    np.testing.assert_array_equal(again.groups[0.46].sigma["zeta"], pop.groups[0.46].sigma["zeta"])
    with pytest.raises(BayestriboError, match="not among the groups"):
        pop.difference("zeta", 0.12, 0.99)


@dataclass
class _Fit:
    """Stand-in for bayestribo.inference.FitResult: samples, prior_logpdf, metadata."""

    draws: dict[str, np.ndarray]
    metadata: dict[str, Any] = field(default_factory=dict)
    run_name: str = "run"

    def samples(self, name):
        return self.draws[name]

    def prior_logpdf(self, name, values):
        return np.where(values > 0, -math.log(0.2), -np.inf)  # uniform on (0, 0.2)


def test_run_samples_from_a_fit_result_divides_the_joint_prior():
    rng = np.random.default_rng(0)
    fit = _Fit(
        {"zeta": rng.uniform(0.01, 0.03, 50), "mu_k": rng.uniform(0.02, 0.04, 50)},
        {"run_id": "a", "load_N": 0.31},
        "a",
    )
    rs = run_samples(fit, ("zeta", "mu_k"), max_samples=20, seed=1)
    assert rs.n_samples == 20 and rs.name == "a" and rs.metadata["load_N"] == 0.31
    np.testing.assert_allclose(rs.log_prior, 2 * -math.log(0.2))
    assert set(rs.values["zeta"]) <= set(fit.draws["zeta"])


def test_bad_input_is_a_package_error_naming_the_field():
    x = np.linspace(0.01, 0.02, 10)
    with pytest.raises(BayestriboError, match="prior density is zero"):
        RunSamples("a", {"zeta": x}, np.full(10, -np.inf))
    with pytest.raises(BayestriboError, match="shape"):
        RunSamples("a", {"zeta": x}, np.zeros(9))
    good = RunSamples("a", {"zeta": x}, np.zeros(10), {"load_N": 0.1})
    with pytest.raises(BayestriboError, match="duplicate run names"):
        population([good, good], ("zeta",))
    with pytest.raises(BayestriboError, match="no 'lubricant' to group by"):
        population([good], ("zeta",), by="lubricant")
    with pytest.raises(BayestriboError, match="no default scale"):
        sigma_priors(("friction_displacement",))
    with pytest.raises(BayestriboError, match="scale"):
        HalfNormal(-1.0)
    with pytest.raises(BayestriboError, match="two or more distinct values"):
        trend([good], "load_N", ("zeta",))
    with pytest.raises(BayestriboError, match="no posterior samples"):
        population([good], ("zeta", "mu_k"))
    with pytest.raises(BayestriboError, match="rope"):
        slope_probabilities(np.zeros(3), rope=-1.0)


def test_hyperprior_densities_are_normalised():
    from scipy.integrate import quad

    for prior in (HalfCauchy(0.01), HalfNormal(0.003)):
        total, _ = quad(lambda v, p=prior: math.exp(float(p.logpdf(v))), 0, np.inf)
        assert total == pytest.approx(1.0, rel=1e-8)
        assert prior.logpdf(-1.0) == -np.inf
    log_uniform = LogUniform(1e-6, 0.1)
    # On log σ the density is flat: integrate there, over the bounds and a margin.
    total, _ = quad(
        lambda u: math.exp(float(log_uniform.logpdf(math.exp(u))) + u),
        math.log(1e-7),
        math.log(1.0),
        points=[math.log(1e-6), math.log(0.1)],
        limit=200,
    )
    assert total == pytest.approx(1.0, rel=1e-8)
    assert log_uniform.logpdf(0.2) == log_uniform.logpdf(5e-7) == -np.inf
    with pytest.raises(BayestriboError, match="high"):
        LogUniform(0.1, 0.01)


def test_likelihood_matches_direct_evaluation():
    rng = np.random.default_rng(2)
    runs = [
        RunSamples(f"r{i}", {"a": rng.normal(0.02, 0.002, 50 + i)}, rng.normal(size=50 + i))
        for i in range(3)
    ]
    like = MarginalLikelihood(runs, ("a",))
    m, sg = 0.021, 0.0015
    direct = 0.0
    for r in runs:
        terms = np.exp(_normal_logpdf(r.values["a"], m, sg) - r.log_prior)
        direct += math.log(terms.mean())
    got = like(np.array([[[m]]]), np.array([[math.log(sg)]]))
    assert got[0] == pytest.approx(direct, rel=1e-12)


def test_a_nan_log_posterior_is_an_error_naming_the_hyperparameters():
    # The rule of the single-run fit: NaN is a broken input, never a silent -inf.
    rng = np.random.default_rng(3)
    runs = _normal_runs(rng.normal(0.02, 0.001, 3), np.full(3, 0.001), 0.03, 0.02, rng, 100)

    class Broken(MarginalLikelihood):
        def __call__(self, beta, log_sigma):
            return np.full(len(beta), np.nan)

    with pytest.raises(
        NaNLogProbabilityError, match=r"NaN at beta\[0,zeta\]=.*, log_sigma\[zeta\]="
    ):
        sample_hyperparameters(Broken(runs, ("zeta",)), [HalfCauchy(0.01)], seed=0)


def test_short_runs_warn():
    rng = np.random.default_rng(1)
    runs = _normal_runs(rng.normal(0.02, 0.001, 3), np.full(3, 0.001), 0.03, 0.02, rng, 100)
    with pytest.warns(ConvergenceWarning, match="not converged: only .* steps after burn-in"):
        population(runs, ("zeta",), max_steps=200)


def test_the_mean_of_a_non_negative_parameter_stays_non_negative():
    # Damping in air (ζ₀ = 0.0033) measured by three runs each uncertain by 0.004: each
    # run's posterior is cut at 0 by its prior, and so is the population mean; with a
    # flat prior on the whole line about a fifth of the mean's draws would be negative.
    rng = np.random.default_rng(3)
    runs = []
    for i in range(3):
        x = rng.normal(0.002, 0.004, 4000)
        x = x[x >= 0.0][:1000]
        runs.append(RunSamples(f"air{i}", {"zeta": x}, np.full(x.size, -math.log(0.3)), {}))
    g = population(runs, ("zeta",), seed=2).pooled
    assert g.mean["zeta"].min() >= 0.0
    # The bound cuts, it does not move the mass: the median stays near the runs' level.
    assert 0.0005 < np.median(g.mean["zeta"]) < 0.006
    # A parameter without the bound (a slope, a friction displacement) is unbounded.
    free = [RunSamples(r.name, {"x_c": r.values["zeta"] - 0.002}, r.log_prior, {}) for r in runs]
    unbounded = population(free, ("x_c",), sigma_prior={"x_c": 0.01}, seed=2).pooled
    assert unbounded.mean["x_c"].min() < 0.0


def test_groups_on_an_executor_give_the_same_population_and_its_warnings():
    from concurrent.futures import ProcessPoolExecutor

    rng = np.random.default_rng(7)
    runs = []
    for i, load in enumerate((0.12, 0.12, 0.12, 0.46, 0.46, 0.46)):
        x = rng.normal(0.02 + 0.01 * load, 0.001, 400)
        runs.append(
            RunSamples(f"r{i}", {"zeta": x}, np.full(x.size, -math.log(0.3)), {"load_N": load})
        )
    kw = {"by": "load_N", "seed": 4, "max_steps": 600}
    with pytest.warns(ConvergenceWarning):  # 600 steps: not converged, and said so
        serial = population(runs, ("zeta",), **kw)
    with ProcessPoolExecutor(max_workers=2) as pool, pytest.warns(ConvergenceWarning):
        parallel = population(runs, ("zeta",), executor=pool, **kw)
    for value, group in serial.groups.items():
        np.testing.assert_array_equal(parallel.groups[value].mean["zeta"], group.mean["zeta"])
    np.testing.assert_array_equal(parallel.pooled.sigma["zeta"], serial.pooled.sigma["zeta"])


def test_compiled_likelihood_agrees_with_the_numpy_reference():
    # Two parameters, a load trend (two design columns), runs of different lengths
    # (padded samples), walkers near and far from the runs (weights over many decades).
    rng = np.random.default_rng(5)
    runs = []
    for i, n in enumerate((300, 317, 40, 300)):
        values = {"zeta": rng.normal(0.02, 0.001, n), "mu_k": rng.normal(0.03, 0.004, n)}
        runs.append(RunSamples(f"r{i}", values, rng.normal(0.0, 2.0, n), {}))
    design = np.column_stack([np.ones(4), np.array([0.12, 0.3, 0.46, 0.6]) - 0.37])
    like = MarginalLikelihood(runs, ("zeta", "mu_k"), design)
    w = 64
    beta = rng.normal([[0.02, 0.03], [0.0, 0.0]], [[0.003, 0.01], [0.01, 0.02]], size=(w, 2, 2))
    log_sigma = np.log(rng.uniform(1e-5, 0.05, size=(w, 2)))
    got, want = like(beta, log_sigma), like.reference(beta, log_sigma)
    assert np.all(np.isfinite(want)) and np.ptp(want) > 1e3  # far walkers included
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10)


def test_compiled_likelihood_names_a_wrong_shape():
    rng = np.random.default_rng(6)
    runs = [RunSamples("r0", {"zeta": rng.normal(0.02, 0.001, 10)}, np.zeros(10), {})]
    like = MarginalLikelihood(runs, ("zeta",))
    with pytest.raises(BayestriboError, match=r"beta: expected shape \(W, 1, 1\)"):
        like(np.zeros((3, 2, 1)), np.zeros((3, 1)))
    with pytest.raises(BayestriboError, match=r"log_sigma: expected shape \(3, 1\)"):
        like(np.zeros((3, 1, 1)), np.zeros((2, 1)))


def _scaled(x, factor):
    """A job for the shared queue (module level, so a process pool can run it)."""
    if x < 0:
        import warnings

        warnings.warn(f"negative {x}", UserWarning, stacklevel=1)
    return x * factor


def test_the_shared_queue_returns_results_and_warnings_in_call_order():
    from concurrent.futures import ProcessPoolExecutor

    from bayestribo.population.jobs import run_calls

    calls = [(_scaled, (x, 2)) for x in (3, -1, 5, -2)] + [(max, (1, 7))]
    costs = [1.0, 5.0, 0.5, 9.0, 2.0]  # submitted as 4, 2, 5, 1, 3: results still in order
    with ProcessPoolExecutor(max_workers=2) as pool, pytest.warns(UserWarning) as caught:
        got = run_calls(calls, pool, costs)
    assert got == [6, -2, 10, -4, 7]
    assert [str(w.message) for w in caught if "negative" in str(w.message)] == [
        "negative -1",
        "negative -2",
    ]
    with pytest.raises(ValueError, match="costs: expected 5 values"):
        run_calls(calls, pool, costs[:2])


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_population_jobs_assemble_to_the_population():
    from bayestribo.population.groups import fit_group, population_jobs

    rng = np.random.default_rng(8)
    runs = []
    for i, load in enumerate((0.12, 0.12, 0.46, 0.46)):
        x = rng.normal(0.02 + 0.01 * load, 0.001, 200)
        runs.append(
            RunSamples(f"r{i}", {"zeta": x}, np.full(x.size, -math.log(0.3)), {"load_N": load})
        )
    # the queue's answer is the direct one, draw for draw: short samplers do (not converged)
    kw = {"by": "load_N", "seed": 1, "max_steps": 600}
    jobs, assemble = population_jobs(runs, ("zeta",), **kw)
    assert [job[0] for job in jobs] == ["load_N=0.12", "load_N=0.46", "all"]
    queued = assemble([fit_group(*job) for job in jobs])
    direct = population(runs, ("zeta",), **kw)
    for value, group in direct.groups.items():
        np.testing.assert_array_equal(queued.groups[value].mean["zeta"], group.mean["zeta"])
    np.testing.assert_array_equal(queued.pooled.sigma["zeta"], direct.pooled.sigma["zeta"])
    with pytest.raises(BayestriboError, match="fitted: expected 3 groups, got 2"):
        assemble([fit_group(*job) for job in jobs[:2]])


def test_the_default_sigma_prior_of_a_group_of_one_run_is_the_half_cauchy():
    # One run says nothing of σ: under p(σ) ∝ 1/σ its posterior would be the bounds'.
    prior = ScaleFree(0.01)
    assert prior.for_runs([1e-4]) == HalfCauchy(0.01)
    two = prior.for_runs([1e-4, 3e-4])
    assert isinstance(two, LogUniform)
    assert two.low == pytest.approx(0.1 * 2e-4) and two.high == pytest.approx(0.1)
    assert prior.for_runs([0.0, 0.0]).low == pytest.approx(1e-6)  # no spread: the scale's
