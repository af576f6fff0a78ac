"""The compiled log posterior against the numpy reference (Posterior.reference), and
the compiled standardized residuals against PiLikelihood.standardized_residuals.

Random parameter sets in a box wider than the priors' support (so that some rows are
outside it), for every variant: exact and averaged model, with and without the
discrepancy term, with fixed parameters, without friction, with replaced priors of
each kind, with a record that ends before the motion and a start in motion. The two
must agree to 1e-10 of the largest term of log p (max(1, |log p|, χ²/2): far from the
data χ² and the nuisances' explained part cancel) and give −inf at the same rows.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _sim import simulate_flat

from bayestribo.errors import BayestriboError
from bayestribo.inference import build_posterior
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import LogUniform, Normal, Uniform
from bayestribo.inference.sampling import NaNLogProbabilityError
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model

#: Agreement required: the same formulas in a different order of floating-point
#: operations (sums over ~40 increments of terms up to ~1e3 in log p), relative to
#: the largest term of the sum (see :func:`_scale`).
RTOL = 1e-10


def _scale(post: Posterior, rows: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """The size of the terms whose sum is log p: max(1, |log p|, χ²/2).

    log p = -½(χ² - bᵀA⁻¹b + ...): far from the data χ² and the nuisances' explained
    part bᵀA⁻¹b are both huge and cancel (6.5e6 each for a log p of 8 at a large
    shape scale), so two orders of the same operations differ by a few ulps of χ²,
    not of log p.
    """
    lik = post.likelihood
    args = post._likelihood_args(rows)
    resid = lik.data.increments - lik.model_increments(args[0])
    chi2 = np.sum(resid * resid / lik.variance(args[1]), axis=-1)
    return np.maximum(np.maximum(1.0, np.abs(ref)), 0.5 * chi2)


@pytest.fixture(scope="module")
def data():
    run = simulate_flat(
        seed=21,
        zeta=0.0236,
        mu_k=0.0294,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        sample_rate_Hz=5000.0,
        offset_m=1e-4,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    return pi_data(decay, noise_model(decay, run.metadata), grid_points=40, seed=0)


def _box(post: Posterior, y0: float) -> tuple[np.ndarray, np.ndarray]:
    """A box around the priors' support, 10 % wider on each side (and ±5 σ for y0)."""
    low, high = [], []
    for name in post.names:
        p = post.priors[name]
        if isinstance(p, Normal):
            low.append(p.mu - 5 * p.sigma)
            high.append(p.mu + 5 * p.sigma)
        else:
            width = p.high - p.low
            low.append(p.low - 0.1 * width)
            high.append(p.high + 0.1 * width)
    return np.array(low), np.array(high)


def _rows(post: Posterior, y0: float, n: int, seed: int) -> np.ndarray:
    low, high = _box(post, y0)
    rows = np.random.default_rng(seed).uniform(low, high, (n, low.size))
    # Points on the support's edges: the lower and upper bounds of the uniform priors
    # (ζ = 0 and μ_k = 0 alone, never both: ζ = μ_k = 0 never stops, see below).
    for i, name in enumerate(post.names):
        p = post.priors[name]
        if isinstance(p, Uniform | LogUniform) and name not in ("zeta", "mu_k"):
            rows[:5, i] = p.low
            rows[5:10, i] = p.high
        elif isinstance(p, Uniform):
            rows[10:15, i] = p.high
    if "zeta" in post.names and post.friction:
        rows[15:20, post.names.index("zeta")] = 0.0
    if "mu_k" in post.names and "zeta" in post.names:
        rows[20:25, post.names.index("mu_k")] = 0.0
    return rows


def _assert_agree(post: Posterior, rows: np.ndarray) -> None:
    assert post.uses_compiled
    fast = post(rows)
    ref = post.reference(rows)
    np.testing.assert_array_equal(np.isneginf(fast), np.isneginf(ref))
    assert np.all(np.isfinite(ref) | np.isneginf(ref))
    finite = np.isfinite(ref)
    # Enough rows on both sides of the support's edge for the test to mean something.
    assert 0.2 * rows.shape[0] < finite.sum() < rows.shape[0]
    err = np.abs(fast[finite] - ref[finite]) / _scale(post, rows[finite], ref[finite])
    assert np.max(err) <= RTOL, np.max(err)
    # The standardized conditional residuals (the optimiser's), to 1e-10 of each
    # row's largest residual.
    inside = rows[finite]
    fast_r = post.standardized_residuals(inside)
    ref_r = post.likelihood.standardized_residuals(*post._likelihood_args(inside))
    scale = np.maximum(1.0, np.max(np.abs(ref_r), axis=1, keepdims=True))
    assert np.max(np.abs(fast_r - ref_r) / scale) <= RTOL
    # With the nuisances' rows (conditional mean over prior sd) the sum of squares is
    # the log-likelihood's χ² part, rᵀWr - bᵀA⁻¹b, which the least squares minimise.
    fast_n = post.standardized_residuals(inside, nuisances=True)
    ref_n = post.likelihood.standardized_residuals(*post._likelihood_args(inside), nuisances=True)
    assert fast_n.shape == ref_n.shape and fast_n.shape[1] > fast_r.shape[1]
    np.testing.assert_array_equal(fast_n[:, : fast_r.shape[1]], fast_r)
    scale_n = np.maximum(1.0, np.max(np.abs(ref_n), axis=1, keepdims=True))
    assert np.max(np.abs(fast_n - ref_n) / scale_n) <= RTOL
    lik = post.likelihood
    params, disc, shape = post._likelihood_args(inside)
    resid = lik.data.increments - lik.model_increments(params)
    var = lik.variance(disc)
    _, explained, _ = lik._solve(resid, var, shape)
    white = lik._whiten(resid / np.sqrt(var))  # the increments as they are if independent
    chi2 = np.sum(white * white, axis=-1) - explained
    total = np.sum(resid * resid / var, axis=-1)
    np.testing.assert_allclose(np.sum(ref_n**2, axis=1), chi2, rtol=0, atol=1e-9 * total.max())


VARIANTS = {
    "default": {},
    "discrepancy": {"discrepancy": True},
    "viscous only": {"friction": False},
    "viscous only, discrepancy": {"friction": False, "discrepancy": True},
    "zeta fixed": {"fixed": {"zeta": 0.0}},
    "friction fixed": {"fixed": {"mu_k": 0.03, "mu_s_ratio": 1.5}},
    "discrepancy fixed": {"fixed": {"log10_discrepancy": -2.0}},
    "shape only, fixed": {"fixed": {"log10_shape": -2.5}},
    "white and fixed shape": {"discrepancy": True, "fixed": {"log10_shape": -3.0}},
    "other priors": {
        "discrepancy": True,
        "priors": {
            "zeta": Uniform(0.005, 0.1),
            "mu_s_ratio": LogUniform(1.0, 2.5),
            "log10_discrepancy": Normal(-3.0, 1.0),
        },
    },
}


@pytest.mark.parametrize("model", ["exact", "averaged"])
@pytest.mark.parametrize("variant", list(VARIANTS))
def test_compiled_log_posterior_agrees_with_the_reference(data, model, variant):
    post = build_posterior(data, model=model, **VARIANTS[variant])
    _assert_agree(post, _rows(post, data.y0, 600, seed=len(variant)))


@pytest.mark.parametrize("model", ["exact", "averaged"])
@pytest.mark.parametrize(
    "change",
    [
        {"motion_ended": False},  # Π truncated at the end of the record
        {"yp0": 0.4},  # the analysed window starts in motion
        {"yp0": -0.3, "motion_ended": False},
    ],
)
def test_compiled_log_posterior_agrees_for_other_records(data, model, change):
    other = dataclasses.replace(data, **change)
    assert other.motion_ended == change.get("motion_ended", data.motion_ended)
    post = build_posterior(other, model=model, discrepancy=True)
    _assert_agree(post, _rows(post, data.y0, 400, seed=7))


#: Laws without a closed form: Π from the law's integrator, the rest compiled.
LAWS = ("viscous+quadratic", "viscous+coulomb+quadratic", "coulomb+hysteretic", "coulomb+power")


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("variant", ["default", "discrepancy", "fixed"])
def test_a_law_without_closed_form_agrees_with_the_reference(data, law, variant):
    """Rows where the drag is too strong for the motion to turn are −inf on both."""
    kwargs: dict = {"law": law}
    if variant == "discrepancy":
        kwargs["discrepancy"] = True
    elif variant == "fixed":
        kwargs["fixed"] = {"mu_s_ratio": 1.5} if "coulomb" in law else {"zeta": 0.01}
    post = build_posterior(data, **kwargs)
    _assert_agree(post, _law_rows(post, data.y0, seed=len(law) + len(variant)))


def _law_rows(post: Posterior, y0: float, seed: int) -> np.ndarray:
    """:func:`_rows`, but a friction law's μ_k = 0 rows at a small positive μ_k: with
    no friction the law's motion never stops, and its integrator sums the 200 000 half
    cycles it allows (seconds a row) on both paths alike."""
    rows = _rows(post, y0, 150, seed=seed)
    if "mu_k" in post.names:
        i = post.names.index("mu_k")
        rows[rows[:, i] == 0.0, i] = 1e-3 * post.priors["mu_k"].high
    return rows


@pytest.mark.parametrize(
    "change", [{"motion_ended": False}, {"yp0": 0.4}, {"yp0": -0.3, "motion_ended": False}]
)
def test_a_law_without_closed_form_agrees_for_other_records(data, change):
    other = dataclasses.replace(data, **change)
    post = build_posterior(other, law="viscous+coulomb+quadratic", discrepancy=True)
    _assert_agree(post, _law_rows(post, data.y0, seed=11))


def _correlated(data):
    """The increments correlated as an integrated record's are: alternating about a
    slowly varying level (a correlation -0.6^|i-j| plus a smooth part)."""
    m = data.increments.size
    lag = np.abs(np.subtract.outer(np.arange(m), np.arange(m)))
    smooth = np.exp(-0.5 * (lag / 8.0) ** 2)
    return dataclasses.replace(data, correlation=0.7 * (-0.6) ** lag + 0.3 * smooth)


@pytest.mark.parametrize("model", ["exact", "averaged"])
@pytest.mark.parametrize("variant", ["default", "discrepancy", "friction fixed"])
def test_compiled_log_posterior_agrees_for_correlated_increments(data, model, variant):
    other = _correlated(data)
    post = build_posterior(other, model=model, **VARIANTS[variant])
    assert post.likelihood.whitening is not None
    _assert_agree(post, _rows(post, data.y0, 400, seed=13))


def test_a_law_without_closed_form_agrees_for_correlated_increments(data):
    post = build_posterior(_correlated(data), law="viscous+coulomb+quadratic", discrepancy=True)
    _assert_agree(post, _law_rows(post, data.y0, seed=17))


def test_correlated_increments_change_the_density_by_their_correlation(data):
    # The same increments with the correlation: log p differs, and with R = I the
    # whitened path gives the independent density to rounding.
    post = build_posterior(data)
    rows = _rows(post, data.y0, 200, seed=5)
    base = post(rows)
    finite = np.isfinite(base)
    identity = dataclasses.replace(data, correlation=np.eye(data.increments.size))
    same = build_posterior(identity)(rows)
    np.testing.assert_allclose(same[finite], base[finite], rtol=1e-9)
    other = build_posterior(_correlated(data))(rows)
    assert np.all(np.abs(other[finite] - base[finite]) > 1e-6 * np.abs(base[finite]))


def test_nan_and_nonstopping_points_are_treated_as_the_reference_treats_them(data):
    post = build_posterior(data)
    good = np.array([0.0236, 0.0294 * 0.5, 1.2, data.y0])
    # NaN in a uniform prior's coordinate: outside the support, −inf, no likelihood.
    row = good.copy()
    row[1] = np.nan
    assert post(row[None])[0] == -np.inf == post.reference(row[None])[0]
    # NaN in y0 (a normal prior): a NaN density, as the numpy priors give.
    row = good.copy()
    row[3] = np.nan
    assert np.isnan(post(row[None])[0]) and np.isnan(post.reference(row[None])[0])
    # ζ = μ_k = 0 is in the support but never stops (Π infinite): no decay is made, so
    # no likelihood, −inf on both paths (it used to be an inf − inf NaN, raised as a
    # bug, which crashed the optimiser's check of its bounds), the good row unchanged.
    row = good.copy()
    row[:2] = 0.0
    both = np.vstack([good, row])
    for f in (post, post.reference):
        with np.errstate(invalid="ignore"):
            lp = f(both)
        assert np.isfinite(lp[0]) and lp[1] == -np.inf
        assert lp[0] == pytest.approx(post.reference(good[None])[0], rel=1e-10)
    # a NaN of the likelihood itself still names the parameters
    broken = dataclasses.replace(data, increments=np.full_like(data.increments, np.nan))
    with pytest.raises(NaNLogProbabilityError, match=r"zeta=0\.0236"):
        build_posterior(broken).reference(good[None])


def test_the_averaged_model_outside_its_domain_raises_the_reference_error(data):
    # ζ's prior below 0, outside the law's support: build_posterior refuses it, the
    # Posterior itself takes it
    post = build_posterior(data, model="averaged")
    post = dataclasses.replace(post, priors=post.priors.replace(zeta=Uniform(-0.1, 0.3)))
    row = np.array([[-0.05, 0.01, 1.2, data.y0]])
    with pytest.raises(ValueError, match="zeta must satisfy"):
        post.reference(row)
    with pytest.raises(ValueError, match="zeta must satisfy"):
        post(row)


def test_what_is_not_compiled_uses_the_reference(data):
    class Wider(Uniform):
        pass

    rows = _rows(build_posterior(data), data.y0, 50, seed=3)
    custom_prior = build_posterior(data, priors={"mu_s_ratio": Wider(1.0, 3.0)})

    class Shifted(PiLikelihood):
        def log_likelihood(self, *args, **kwargs):
            return super().log_likelihood(*args, **kwargs) + 1.0

    plain = build_posterior(data)
    lik = plain.likelihood
    subclass = Posterior(plain.priors, Shifted(data, "exact", lik.offset_sd, lik.drift_sd), {})
    off = Posterior(plain.priors, plain.likelihood, {}, compiled=False)
    for post in (custom_prior, subclass, off):
        assert not post.uses_compiled
        np.testing.assert_array_equal(post(rows), post.reference(rows))
    # The subclass's own likelihood is the one evaluated (+1 where finite).
    ref = plain.reference(rows)
    ok = np.isfinite(ref)
    np.testing.assert_allclose(subclass(rows)[ok] - 1.0, ref[ok], rtol=1e-12)


def test_the_compiled_log_prior_is_the_priors_own(data):
    # inside and outside the support, on its edges, with the discrepancy's priors and
    # a NaN row: the same support, the same value to rounding
    for post in (build_posterior(data), build_posterior(data, discrepancy=True)):
        assert post.uses_compiled
        rows = _rows(post, data.y0, 400, seed=8)
        rows[-1, 0] = np.nan
        ours, ref = post.log_prior(rows), post.priors.logpdf(rows)
        np.testing.assert_array_equal(np.isfinite(ours), np.isfinite(ref))
        inside = np.isfinite(ref)
        assert 0 < inside.sum() < rows.shape[0]
        np.testing.assert_allclose(ours[inside], ref[inside], rtol=1e-14)


def test_rows_of_the_wrong_length_are_refused(data):
    post = build_posterior(data)
    with pytest.raises(BayestriboError, match=r"theta: expected rows of 4 values"):
        post(np.zeros((3, 5)))
