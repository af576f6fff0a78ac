"""A transient the burn-in did not cover (bayestribo.inference.modes.mode_check): the
burn-in is extended past it when the draws left meet the sampler's rule, else the run
is not converged and the reason names it."""

from __future__ import annotations

import numpy as np

from bayestribo.inference.modes import mode_check
from bayestribo.inference.sampling import SamplerRun, SamplerSettings
from bayestribo.inference.types import Sampled

WALKERS, ENSEMBLES, KEPT, AWAY = 16, 2, 400, 20


def _sampled(kept: int = KEPT, converged: bool = True, tau: float = 1.0) -> Sampled:
    # walkers that start 30 sd away and reach the bulk after AWAY of the kept steps
    rng = np.random.default_rng(6)
    x = rng.standard_normal((ENSEMBLES, kept, WALKERS, 2))
    x[:, :AWAY] += 30.0
    lp = -0.5 * np.sum(x**2, axis=3)
    run = SamplerRun(
        chains=x.reshape(ENSEMBLES, -1, 2),
        log_prob=lp.reshape(ENSEMBLES, -1),
        autocorr_time=np.full(2, tau),
        n_steps=kept + 2,
        burn=2,
        thin=1,
        acceptance_fraction=0.3,
        ess=np.full(2, float(kept * WALKERS * ENSEMBLES)),
        rhat=np.ones(2),
        converged=converged,
        reasons=[] if converged else ["R-hat 1.1 >= 1.01 for a"],
        names=("a", "b"),
    )
    settings = SamplerSettings(n_walkers=WALKERS, n_ensembles=ENSEMBLES)
    return Sampled(None, np.zeros(2), run, settings)


def test_the_burn_in_is_extended_past_a_transient():
    sampled, report = mode_check(_sampled())
    run = sampled.run
    assert run.converged and not report.matters and report.n_modes == 1
    assert report.dropped_steps == AWAY
    assert run.burn == 2 + AWAY
    assert run.chains.shape == (ENSEMBLES, (KEPT - AWAY) * WALKERS, 2)
    assert np.all(run.chains[:, :, 0] < 10.0)  # no draw of the transient is left
    assert run.ess[0] == (KEPT - AWAY) * WALKERS * ENSEMBLES


def test_too_few_steps_after_the_transient_leave_the_run_not_converged():
    # τ = 8: the 380 steps after the transient are fewer than 50 τ
    sampled, report = mode_check(_sampled(tau=8.0))
    assert not sampled.run.converged and report.matters and report.dropped_steps == 0
    assert "burn-in too short" in sampled.run.reasons[-1]
    assert sampled.run.chains.shape[1] == KEPT * WALKERS


def test_a_run_not_converged_otherwise_keeps_its_draws_and_names_the_transient():
    sampled, report = mode_check(_sampled(converged=False))
    assert not sampled.run.converged and report.dropped_steps == 0
    assert sampled.run.reasons[0].startswith("R-hat")
    assert "burn-in too short" in sampled.run.reasons[-1]


class _Stored:
    """Ensembles whose draws are given (the sampler's ``flat`` over them)."""

    def __init__(self, x: np.ndarray) -> None:
        self.x = x  # (ensembles, steps, walkers, d)

    def flat(self, discard: int, thin: int) -> tuple[np.ndarray, np.ndarray]:
        x = self.x[:, discard::thin]
        n_ens, steps, walkers, d = x.shape
        return x.reshape(n_ens, steps * walkers, d), -0.5 * np.sum(x**2, axis=3).reshape(n_ens, -1)


def test_the_sampler_extends_its_burn_in_past_a_transient():
    from bayestribo.inference.sampling import _past_transient

    rng = np.random.default_rng(9)
    steps, burn = 600, 10
    x = rng.standard_normal((ENSEMBLES, steps, WALKERS, 2))
    x[:, : burn + AWAY] += 30.0  # the walkers' way in, past the burn-in
    settings = SamplerSettings(n_walkers=WALKERS, n_ensembles=ENSEMBLES)
    past = _past_transient(_Stored(x), steps, burn, 1, np.ones(2), settings, ("a", "b"))
    assert past is not None
    assert past[:3] == (steps, burn + AWAY, 1)
    assert np.all(past[3] < settings.rhat_max)
    # no transient: the burn-in stays the sampler's
    x[:, : burn + AWAY] -= 30.0
    assert _past_transient(_Stored(x), steps, burn, 1, np.ones(2), settings, ("a", "b")) is None


def test_the_end_of_a_transient_is_found_in_steps_of_the_sampler():
    from bayestribo.inference.sampling import _transient_end

    rng = np.random.default_rng(10)
    x = rng.standard_normal((ENSEMBLES, 600, WALKERS, 2))
    x[:, : 10 + 2 * AWAY] += 30.0  # 2 AWAY steps past a burn-in of 10, thinned by 2
    settings = SamplerSettings(n_walkers=WALKERS, n_ensembles=ENSEMBLES)
    assert _transient_end(_Stored(x), 10, np.full(2, 2.0), settings, ("a", "b")) == 10 + 2 * AWAY
    x[:, : 10 + 2 * AWAY] -= 30.0
    assert _transient_end(_Stored(x), 10, np.full(2, 2.0), settings, ("a", "b")) == 0
