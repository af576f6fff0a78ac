"""A law's posterior sampled in its sampling transform's coordinates is the same
posterior (bayestribo.model.laws.transforms, bayestribo.model.laws.loss_share,
bayestribo.inference.reparameterised)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bayestribo.inference.reparameterised import Reparameterised, lowest_amplitude
from bayestribo.inference.sampling import SamplerSettings, run_ensembles
from bayestribo.model.laws import get_law
from bayestribo.model.laws.loss_share import LossShare
from bayestribo.model.laws.transforms import SamplingTransform, transform_for

NAMES = ("mu_k", "mu_s_ratio", "zeta_alpha", "alpha", "y0")


def _prior_box(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.column_stack(
        [
            rng.uniform(0.0, 0.25, n),
            rng.uniform(1.0, 3.0, n),
            rng.uniform(0.0, 0.3, n),
            rng.uniform(0.0, 3.0, n),
            rng.uniform(-1.0, 1.0, n),
        ]
    )


@pytest.mark.parametrize("ended", [True, False])
def test_the_loss_share_transform_inverts_and_its_jacobian_is_the_determinant(ended):
    rng = np.random.default_rng(1)
    transform = LossShare(reference=0.7, lowest=0.1, ended=ended)
    assert isinstance(transform, SamplingTransform)
    theta = _prior_box(rng, 40)[:, :4]
    u = transform.from_law(theta)
    np.testing.assert_allclose(transform.to_law(u), theta, rtol=1e-12, atol=1e-15)
    for row in u[:8]:
        jac = np.empty((4, 4))
        for j in range(4):
            step = np.zeros(4)
            step[j] = 1e-6 * max(1.0, abs(row[j]))
            up = transform.to_law((row + step)[None])[0]
            down = transform.to_law((row - step)[None])[0]
            jac[:, j] = (up - down) / (2.0 * step[j])
        expected = math.log(abs(np.linalg.det(jac)))
        assert transform.log_jacobian(row[None])[0] == pytest.approx(expected, abs=1e-6)


def test_alpha_on_its_bound_maps_to_finite_coordinates():
    transform = LossShare(reference=1.0, lowest=0.2)
    u = transform.from_law(np.array([[0.05, 2.0, 0.1, 0.0]]))
    assert np.all(np.isfinite(u)) and np.isfinite(transform.log_jacobian(u)[0])
    # a log α so low that 1 - ρ^α underflows is outside the prior, not a NaN
    far = transform.to_law(np.array([[0.5, 0.1, 1e-3, -800.0]]))
    assert not np.any(np.isnan(far)) and not np.all(np.isfinite(far))


def test_a_law_holding_the_terms_declares_the_transform_where_they_are_sampled():
    assert isinstance(get_law("coulomb+power").sampling_transform(NAMES, 1.0, 0.2), LossShare)
    # the static friction sampled where the record holds its end of motion, else the
    # ratio (a record in motion to its end holds no stick)
    assert get_law("coulomb+power").sampling_transform(NAMES, 1.0, 0.2).names[1] == (
        "static_friction"
    )
    in_motion = get_law("coulomb+power").sampling_transform(NAMES, 1.0, 0.2, ended=False)
    assert in_motion.names[1] == "static_ratio"
    assert isinstance(
        get_law("viscous+coulomb+power").sampling_transform(("zeta", *NAMES), 1.0, 0.2),
        LossShare,
    )
    # a parameter it replaces held fixed: the law's own coordinates
    sampled = [n for n in NAMES if n != "zeta_alpha"]
    assert get_law("coulomb+power").sampling_transform(sampled, 1.0, 0.2) is None
    assert get_law("power").sampling_transform(("zeta_alpha", "alpha", "y0"), 1.0, 0.2) is None
    assert get_law("viscous+coulomb").sampling_transform(("zeta", "mu_k"), 1.0, 0.2) is None
    assert transform_for(["coulomb", "quadratic"], NAMES, 1.0, 0.2) is None


class _LShaped:
    """A stand-in posterior on the default priors' box of ``coulomb+power``: the loss
    per cycle at A_r = 1 measured to 0.02, the drag's departure from a friction
    (ζ_α(1 − 0.3^α), another ρ than the transform's) to 0.003 of 0: an L in (ζ_α, α);
    the static friction μ_k (μ_s/μ_k) to 0.02 of 0.2."""

    names = NAMES

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        mu_k, ratio, zeta, alpha, y0 = theta.T
        inside = (
            (mu_k >= 0) & (mu_k <= 0.25) & (ratio >= 1) & (ratio <= 3) & (zeta >= 0)
            & (zeta <= 0.3) & (alpha >= 0) & (alpha <= 3) & (np.abs(y0) <= 1)
        )  # fmt: skip
        loss = 8.0 * mu_k + 4.0 * math.pi * zeta
        departure = zeta * -np.expm1(alpha * math.log(0.3))
        lp = (
            -0.5 * ((loss - 0.8) / 0.02) ** 2
            - 0.5 * (departure / 0.003) ** 2
            - 0.5 * ((y0 - 0.2) / 0.1) ** 2
            - 0.5 * ((mu_k * ratio - 0.2) / 0.02) ** 2
        )
        return np.where(inside, lp, -np.inf)


def _reference(target: _LShaped, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Draws and their normalised weights under ``target``: ζ_α, α and μ_s/μ_k from
    the prior, y0 from its Gaussian and μ_k from the loss's (both exact factors of the
    density on the box, within it), weighted by the rest: the departure's factor and
    the box and the static friction's."""
    n = 1_500_000
    draws = _prior_box(rng, n)
    draws[:, 4] = rng.normal(0.2, 0.1, n)
    draws[:, 0] = (rng.normal(0.8, 0.02, n) - 4.0 * math.pi * draws[:, 2]) / 8.0
    departure = draws[:, 2] * -np.expm1(draws[:, 3] * math.log(0.3))
    static = draws[:, 0] * draws[:, 1]
    factor = -0.5 * (departure / 0.003) ** 2 - 0.5 * ((static - 0.2) / 0.02) ** 2
    w = np.where(np.isfinite(target(draws)), np.exp(factor), 0.0)
    return draws, w / w.sum()


def _sampled(target, transform, start, rng, jacobian: bool = True) -> np.ndarray:
    density = Reparameterised(target, transform)
    if not jacobian:
        density = Reparameterised(target, _NoJacobian(transform))
    walkers = density.initial(start.reshape(2, 32, -1), rng)
    settings = SamplerSettings(n_walkers=32, n_ensembles=2, max_steps=20_000)
    run = density.law_run(run_ensembles(density, walkers, settings, seed=5))
    assert run.converged, run.reasons
    # the run's log density is the posterior's, in the posterior's own coordinates
    flat = run.chains.reshape(-1, run.chains.shape[-1])
    np.testing.assert_allclose(run.log_prob.ravel(), target(flat), rtol=1e-10, atol=1e-10)
    assert run.names == NAMES
    return flat


class _NoJacobian:
    """The transform with its Jacobian left out (a control the check must catch)."""

    def __init__(self, transform):
        self._t = transform
        self.law_names, self.names = transform.law_names, transform.names
        self.to_law, self.from_law = transform.to_law, transform.from_law

    def log_jacobian(self, u):
        return np.zeros(np.atleast_2d(u).shape[0])


def _shifts(draws: np.ndarray, ref: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """|mean of draws − weighted mean of ref| / posterior sd, per column, and the same
    for the indicator of α < 0.3 (the corner of the L)."""
    cols = np.column_stack([draws, draws[:, 3] < 0.3])
    ref_cols = np.column_stack([ref, ref[:, 3] < 0.3])
    mean = weights @ ref_cols
    sd = np.sqrt(weights @ (ref_cols - mean) ** 2)
    return np.abs(cols.mean(axis=0) - mean) / sd


@pytest.mark.parametrize("ended", [True, False])
def test_sampling_in_the_transform_gives_the_posterior_and_without_its_jacobian_does_not(ended):
    rng = np.random.default_rng(11)
    target = _LShaped()
    transform = LossShare(reference=1.0, lowest=0.2, ended=ended)
    ref, weights = _reference(target, rng)
    assert 1.0 / np.sum(weights**2) > 3000  # the reference's own effective size
    # walkers start at reference draws (from the posterior, as a fit's start near it)
    start = ref[rng.choice(ref.shape[0], size=64, p=weights)]
    draws = _sampled(target, transform, start, rng)
    # thinned at τ, ~1000+ effective draws: 0.15 sd is ~5 standard errors (seed 11: 0.05)
    assert np.max(_shifts(draws, ref, weights)) < 0.15
    # the same run without the Jacobian samples another density, which the check sees
    wrong = _sampled(target, transform, start, rng, jacobian=False)
    assert np.max(_shifts(wrong, ref, weights)) > 0.3  # seed 11: 0.42 (α, ζ_α, μ_k)


def test_the_lowest_amplitude_is_read_from_the_increments():
    tau = np.linspace(0.0, 100.0, 101)
    amplitude = np.exp(-0.02 * tau[:-1])
    posterior = SimpleNamespace(
        likelihood=SimpleNamespace(
            data=SimpleNamespace(tau_grid=tau, increments=0.5 * amplitude**2)
        )
    )
    assert lowest_amplitude(posterior) == pytest.approx(amplitude[-1], rel=1e-12)


class _Posterior:
    """A stand-in posterior of a law on the box of ``_LShaped`` (its density)."""

    def __init__(self, law: str, names: tuple[str, ...]):
        self.law, self.names = get_law(law), names
        tau = np.linspace(0.0, 10.0, 11)
        data = SimpleNamespace(tau_grid=tau, increments=np.exp(-0.1 * tau[:-1]))
        self.likelihood = SimpleNamespace(reference_amplitude=1.0, data=data)

    def __call__(self, theta):
        return _LShaped()(theta) if self.names == NAMES else np.zeros(len(np.atleast_2d(theta)))


@pytest.mark.parametrize("law", ["coulomb+power", "viscous+coulomb"])
def test_the_exact_sampler_runs_in_the_laws_coordinates_and_reports_its_own(monkeypatch, law):
    from bayestribo.inference import chains
    from bayestribo.inference.sampling import SamplerRun

    names = NAMES if law == "coulomb+power" else ("zeta", "mu_k", "mu_s_ratio", "y0")
    posterior = _Posterior(law, names)
    rng = np.random.default_rng(4)
    seen = {}

    def fake_run(log_prob, initial, settings, *, seed, progress=False, unidentified=None):
        seen["log_prob"], seen["initial"] = log_prob, initial
        draws = initial[:, :8]
        return SamplerRun(
            chains=draws,
            log_prob=np.asarray(log_prob(draws.reshape(-1, draws.shape[-1]))).reshape(2, 8),
            autocorr_time=np.arange(1.0, draws.shape[-1] + 1),
            n_steps=100,
            burn=10,
            thin=1,
            acceptance_fraction=0.3,
            ess=np.full(draws.shape[-1], 1000.0),
            rhat=np.ones(draws.shape[-1]),
            converged=True,
            names=tuple(log_prob.names),
        )

    monkeypatch.setattr(chains, "run_ensembles", fake_run)
    ref, weights = _reference(_LShaped(), rng)
    walkers = ref[rng.choice(ref.shape[0], size=32, p=weights)].reshape(2, 16, -1)
    if law != "coulomb+power":
        walkers = walkers[..., [2, 0, 1, 4]]
    settings = SamplerSettings(n_walkers=16, n_ensembles=2)
    run = chains._exact_run(posterior, walkers, settings, 0, False, rng)
    assert run.names == names
    if law == "coulomb+power":
        assert isinstance(seen["log_prob"], Reparameterised)
        assert list(seen["log_prob"].names) == [
            "loss_per_cycle",
            "static_friction",
            "drag_shape",
            "log_alpha",
            "y0",
        ]
        # the draws are the walkers it started from, in the law's own parameters again
        np.testing.assert_allclose(run.chains, walkers[:, :8], rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(run.log_prob.ravel(), posterior(run.chains.reshape(-1, 5)))
        # τ of each replaced parameter the longest of the transform's coordinates
        assert np.all(run.autocorr_time[:4] == 4.0) and run.autocorr_time[4] == 5.0
    else:
        assert seen["log_prob"] is posterior
        np.testing.assert_array_equal(run.chains, walkers[:, :8])


def test_a_run_not_converged_says_which_coordinates_its_reasons_name():
    rng = np.random.default_rng(3)
    target = _LShaped()
    density = Reparameterised(target, LossShare(reference=1.0, lowest=0.2))
    start = _prior_box(rng, 64)
    start[:, 0] = (0.8 - 4.0 * math.pi * start[:, 2]) / 8.0
    start[:, 4] = 0.2
    walkers = density.initial(start.reshape(2, 32, -1), rng)
    # far too few steps to converge: the reasons name the sampled coordinates
    settings = SamplerSettings(n_walkers=32, n_ensembles=2, max_steps=60)
    sampled = run_ensembles(density, walkers, settings, seed=5)
    assert not sampled.converged
    run = density.law_run(sampled)
    assert run.reasons[: len(sampled.reasons)] == sampled.reasons
    said = run.reasons[-1]
    assert all(name in said for name in density.transform.names + LossShare.law_names)
    assert run.names == NAMES
