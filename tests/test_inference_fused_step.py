"""The compiled sampler step (fused_step.py) against the grouped moves' Python splits.

The compiled step must give the chains of the Python splits to the bit: the same
proposals from the same random numbers, the same log posterior, the same acceptance.
It is checked over whole runs of every posterior variant it serves (exact and
averaged model, with the discrepancy, with a fixed parameter, without friction), for
a log-probability that offers the step only for one move, and where a split cannot be
evaluated compiled (the step stops there and the Python split raises the reference's
error).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _sim import simulate_flat

from bayestribo.inference import build_posterior, sampling
from bayestribo.inference.moves import DE, GroupedDEMove
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Uniform
from bayestribo.inference.sampling import SamplerSettings, run_ensembles
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model


@pytest.fixture(scope="module")
def data():
    run = simulate_flat(
        seed=5,
        zeta=0.0236,
        mu_k=0.0294,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        sample_rate_Hz=5000.0,
        offset_m=1e-4,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    return pi_data(decay, noise_model(decay, run.metadata), seed=0)


class _Python:
    """The posterior without its compiled step: every split runs in Python."""

    def __init__(self, posterior: Posterior, step=None) -> None:
        self.posterior = posterior
        self.names = posterior.names
        if step is not None:
            self.grouped_step = step

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        return self.posterior(theta)


def _start(post: Posterior, n_walkers: int = 16) -> np.ndarray:
    """Walkers in a small box around a point of high density."""
    centre = {
        "zeta": 0.0236,
        "mu_k": 0.0294 * 0.5,
        "mu_s_ratio": 1.2,
        "y0": post.likelihood.data.y0,
        "log10_discrepancy": -3.0,
        "log10_shape": -3.0,
    }
    x = np.array([centre[n] for n in post.names])
    rng = np.random.default_rng(3)
    start = x * (1 + 1e-3 * rng.standard_normal((2, n_walkers, x.size)))
    assert np.all(np.isfinite(post(start.reshape(-1, x.size))))
    return start


def _grouped_chain(log_prob, start: np.ndarray, steps: int, seed: int = 11) -> np.ndarray:
    ens = sampling._Grouped(sampling._nan_checked(log_prob, log_prob.names), start, seed)
    ens.run(steps)
    return ens.sampler.get_chain(), ens.sampler.get_log_prob()


VARIANTS = {
    "exact": {},
    "averaged": {"model": "averaged"},
    "discrepancy": {"discrepancy": True},
    "fixed ratio": {"fixed": {"mu_s_ratio": 1.2}},
    "no friction": {"friction": False},
}


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_compiled_steps_give_the_python_splits_chains_to_the_bit(data, variant):
    post = build_posterior(data, **VARIANTS[variant])
    assert post.grouped_step is not None
    start = _start(post)
    chain, lp = _grouped_chain(post, start, 150)
    ref_chain, ref_lp = _grouped_chain(_Python(post), start, 150)
    np.testing.assert_array_equal(chain, ref_chain)
    np.testing.assert_array_equal(lp, ref_lp)
    # The chains moved: both moves ran and accepted proposals.
    assert np.unique(chain[:, 0, 0]).size > 10


def test_a_step_offered_for_one_move_only_mixes_with_python_steps(data):
    post = build_posterior(data)
    calls = {"compiled": 0, "python": 0}

    def de_only(kind, *args):
        if kind == DE:
            calls["compiled"] += 1
            return post.grouped_step(kind, *args)
        calls["python"] += 1
        return 0

    start = _start(post)
    chain, _ = _grouped_chain(_Python(post, de_only), start, 150)
    ref, _ = _grouped_chain(_Python(post), start, 150)
    np.testing.assert_array_equal(chain, ref)
    assert calls["compiled"] > 50 and calls["python"] > 10


def test_without_a_compiled_density_there_is_no_step(data):
    post = build_posterior(data)
    assert Posterior(post.priors, post.likelihood, compiled=False).grouped_step is None


def test_a_split_the_step_cannot_evaluate_is_left_to_python(data):
    # The averaged model with ζ allowed below 0: the compiled density flags ζ < 0
    # (outside the model's domain), where the reference raises its error.
    # ζ's prior below 0, outside the law's support: build_posterior refuses it, the
    # Posterior itself takes it
    post = build_posterior(data, model="averaged")
    post = dataclasses.replace(post, priors=post.priors.replace(zeta=Uniform(-0.1, 0.3)))
    # Walkers that differ in ζ only (by about 2e-5), so that proposals move ζ alone.
    coords = np.repeat(_start(post)[0, :1], 16, axis=0)
    coords[:, 0] += np.linspace(-2e-5, 2e-5, 16)
    log_prob = post(coords)
    n = coords.shape[0]
    order = np.arange(n)[None, :]
    rng = np.random.default_rng(0)
    uniform = rng.random((2, 1, n // 2, 2))
    # First split: small steps (ζ stays near 0.0236); second: stretches up to 10⁴,
    # which send some proposals to ζ in [-0.1, 0), inside the prior.
    gamma = np.stack([np.full((1, n // 2), 0.5), np.geomspace(10.0, 1e4, n // 2)[None]])
    log_u = np.log(rng.random((2, n // 2)))
    accepted = np.zeros(n, dtype=bool)
    new, new_lp = coords.copy(), log_prob.copy()
    done = post.grouped_step(DE, new, new_lp, order, uniform, gamma, log_u, accepted)
    assert done == 1
    # The first split is the Python split's, the second untouched.
    move = GroupedDEMove(1)
    q, _ = move._split_proposal(coords, order, 0, uniform[0], gamma[0])
    q_lp = post(q)
    take = q_lp - log_prob[: n // 2] > log_u[0]
    expect = coords.copy()
    expect[: n // 2][take] = q[take]
    np.testing.assert_array_equal(new, expect)
    np.testing.assert_array_equal(accepted[: n // 2], take)
    assert take.any() and not accepted[n // 2 :].any()
    np.testing.assert_array_equal(new[n // 2 :], coords[n // 2 :])
    # The second split in Python raises the reference's error.
    q2, _ = move._split_proposal(new, order, 1, uniform[1], gamma[1])
    assert np.any((q2[:, 0] < 0) & (q2[:, 0] > -0.1))
    with pytest.raises(ValueError, match="zeta must satisfy"):
        post(q2)


def test_a_run_that_reaches_an_unevaluable_point_fails_as_without_the_step(data):
    # ζ's prior below 0, outside the law's support: build_posterior refuses it, the
    # Posterior itself takes it
    post = build_posterior(data, model="averaged")
    post = dataclasses.replace(post, priors=post.priors.replace(zeta=Uniform(-0.1, 0.3)))
    start = _start(post)
    start[..., 0] = np.abs(start[..., 0] - 0.0236) + 1e-5  # ζ just above 0
    settings = SamplerSettings(n_walkers=16, max_steps=2000)
    messages = []
    for log_prob in (post, _Python(post)):
        with pytest.raises(ValueError, match="zeta must satisfy") as err:
            run_ensembles(log_prob, start, settings, seed=2)
        messages.append(str(err.value))
    assert messages[0] == messages[1]


def test_a_law_without_closed_form_leaves_every_split_to_python(data):
    """Its Π comes from the law's own integrator: the step does no split, the moves
    run them all, with the compiled density's values."""
    post = build_posterior(data, law="viscous+coulomb+quadratic")
    assert post.uses_compiled and post.grouped_step is not None
    centre = {"zeta": 0.0236, "mu_k": 0.0147, "mu_s_ratio": 1.2, "c2": 1e-4}
    x = np.array([centre.get(n, post.likelihood.data.y0) for n in post.names])
    start = x * (1 + 1e-3 * np.random.default_rng(3).standard_normal((2, 16, x.size)))
    coords = np.ascontiguousarray(start.reshape(-1, x.size))
    log_prob = post(coords)
    assert np.all(np.isfinite(log_prob))
    n = coords.shape[0]
    rng = np.random.default_rng(0)
    args = (
        np.arange(n).reshape(2, -1),
        rng.random((2, 2, n // 4, 2)),
        np.full((2, 2, n // 4), 0.5),
        np.log(rng.random((2, n // 2))),
        np.zeros(n, dtype=bool),
    )
    new, new_lp = coords.copy(), log_prob.copy()
    assert post.grouped_step(DE, new, new_lp, *args) == 0
    np.testing.assert_array_equal(new, coords)
    np.testing.assert_array_equal(new_lp, log_prob)
    chain, lp = _grouped_chain(post, start, 20)
    ref_chain, ref_lp = _grouped_chain(_Python(post), start, 20)
    np.testing.assert_array_equal(chain, ref_chain)
    np.testing.assert_array_equal(lp, ref_lp)
    assert np.unique(chain[:, 0, 0]).size > 3


def _independence_chain(log_prob, start: np.ndarray, steps: int, seed: int = 13):
    """300 DE steps, then ``steps`` with the independence move (fitted to each
    ensemble's walkers) in the mix at 0.75."""
    from bayestribo.inference.independence import GroupedIndependenceMove

    ens = sampling._Grouped(sampling._nan_checked(log_prob, log_prob.names), start, seed)
    ens.run(300)  # from the small box into the posterior
    ens.use_independence(GroupedIndependenceMove.fitted(ens.chains(150)), 0.75)
    ens.run(steps)
    return ens.sampler.get_chain(), ens.sampler.get_log_prob()


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_the_compiled_independence_step_gives_the_python_steps_chains_to_the_bit(data, variant):
    post = build_posterior(data, **VARIANTS[variant])
    assert post.independence_step is not None
    start = _start(post)
    chain, lp = _independence_chain(post, start, 100)
    ref_chain, ref_lp = _independence_chain(_Python(post), start, 100)
    np.testing.assert_array_equal(chain, ref_chain)
    np.testing.assert_array_equal(lp, ref_lp)
    assert np.unique(chain[:, 0, 0]).size > 10


def test_without_a_compiled_density_there_is_no_independence_step(data):
    post = build_posterior(data)
    assert Posterior(post.priors, post.likelihood, compiled=False).independence_step is None
