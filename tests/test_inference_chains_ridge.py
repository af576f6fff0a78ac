"""A quadratic surrogate's run stopped on a ridge the record does not identify is the
law's answer, not converged: no further surrogate and no exact run walk the same ridge
(bayestribo.inference.chains)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bayestribo.inference import chains
from bayestribo.inference.sampling import SamplerRun, SamplerSettings
from bayestribo.inference.surrogate import ATTEMPTS, MAX_WEIGHT_CV, SurrogateCheck
from bayestribo.model.laws import get_law

NAMES = ("mu_k", "mu_s_ratio", "zeta_alpha", "alpha", "y0")


def _run(ridge: bool, rng: np.random.Generator) -> SamplerRun:
    chains_ = rng.normal(size=(2, 50, len(NAMES)))
    reasons = ["stopped at 900 steps: a ridge"] if ridge else ["only 20 steps after burn-in"]
    return SamplerRun(
        chains=chains_,
        log_prob=np.zeros(chains_.shape[:2]),
        autocorr_time=np.full(len(NAMES), 300.0),
        n_steps=900,
        burn=600,
        thin=300,
        acceptance_fraction=0.03,
        ess=np.full(len(NAMES), 10.0),
        rhat=np.full(len(NAMES), 1.2),
        converged=False,
        reasons=reasons,
        names=NAMES,
        ridge=ridge,
    )


@pytest.mark.parametrize("ridge", [True, False])
def test_a_surrogate_stopped_on_a_ridge_ends_the_attempts(monkeypatch, ridge):
    rng = np.random.default_rng(3)
    posterior = SimpleNamespace(
        names=NAMES,
        law=get_law("coulomb+power"),
        likelihood=SimpleNamespace(data=SimpleNamespace(increments=np.zeros(5))),
    )
    target = SimpleNamespace(uses_compiled=True)
    runs: list[object] = []

    def fake_run(log_prob, initial, settings, *, seed, progress=False, unidentified=None):
        # the rule that stops a run on a ridge is given to the surrogate's runs
        assert unidentified is not None and unidentified(np.zeros((4, len(NAMES))))
        runs.append(log_prob)
        return _run(ridge, rng)

    failed = SurrogateCheck(
        draws=100, weight_cv=50 * MAX_WEIGHT_CV, log_weight_sd=2.0, attempt=1, best=np.zeros(5)
    )
    monkeypatch.setattr(chains, "run_ensembles", fake_run)
    monkeypatch.setattr(chains, "check", lambda *args, **kwargs: failed)
    monkeypatch.setattr(chains, "regressed_posterior", lambda *args: target)
    run, checked, used, pointwise = chains._sample_surrogate(
        posterior,
        np.zeros(len(NAMES)),
        np.eye(len(NAMES)),
        np.zeros((2, 16, len(NAMES))),
        SamplerSettings(n_walkers=16, n_ensembles=2),
        seed=0,
        progress=False,
        first=target,
    )
    if ridge:
        assert len(runs) == 1 and run is not None and used is target and pointwise is None
        assert checked is failed and not run.converged and run.ridge
        assert run.reasons[0].startswith("stopped at")
        assert "surrogate's" in run.reasons[-1] and "not sampled" in run.reasons[-1]
    else:
        # without a ridge the next surrogates are tried, then the exact sampler
        assert len(runs) == ATTEMPTS and run is None and used is None
