"""A run whose walkers stayed in one part of a split posterior is reported not
converged when a point evaluated elsewhere holds far more density
(bayestribo.inference.missed, wired into bayestribo.inference.chains.sample_from)."""

from __future__ import annotations

import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.special import logsumexp

from bayestribo import read_run
from bayestribo.inference import chains
from bayestribo.inference.missed import MARGIN, climbed, missed_reason
from bayestribo.inference.pipeline import build_posterior, prepare
from bayestribo.inference.sampling import SamplerRun, SamplerSettings
from bayestribo.inference.start import Start, maximum_a_posteriori
from bayestribo.inference.surrogate import SurrogateCheck

BUNDLED = Path(__file__).resolve().parents[1] / "data" / "runs" / "glycerol-N0.31-r1.csv"
NAMES = ("a", "b")
#: The second part's density over the first's at their centres [nats].
GAP = 40.0
FAR = np.array([12.0, -12.0])


def _split(theta: np.ndarray) -> np.ndarray:
    """Two unit Gaussians, at 0 and at FAR, the second GAP nats higher."""
    theta = np.atleast_2d(theta)
    near = -0.5 * np.sum(theta**2, axis=1)
    far = GAP - 0.5 * np.sum((theta - FAR) ** 2, axis=1)
    return logsumexp(np.stack([near, far]), axis=0)


def _walkers_in_first_part(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    draws = rng.normal(size=(2, 500, 2))
    return draws, _split(draws.reshape(-1, 2)).reshape(2, 500)


def test_a_point_in_a_higher_part_the_walkers_missed_is_named():
    rng = np.random.default_rng(0)
    _, lp = _walkers_in_first_part(rng)
    reason = missed_reason(_split, NAMES, lp, [FAR + 0.3, np.zeros(2)])
    assert reason is not None
    # by how much (the density at FAR + 0.3 over the best draw's, near the first centre)
    gap = float(_split(FAR + 0.3)[0] - lp.max())
    assert gap > MARGIN
    assert f"{gap:.4g}" in reason and "a = 12.3" in reason and "b = -11.7" in reason


def test_points_in_the_part_the_walkers_explored_say_nothing():
    rng = np.random.default_rng(1)
    _, lp = _walkers_in_first_part(rng)
    # the checked draws of a surrogate that followed the same part: none far above
    points = list(rng.normal(size=(128, 2)))
    assert missed_reason(_split, NAMES, lp, points) is None
    assert missed_reason(_split, NAMES, lp, []) is None
    # a point above the best draw by less than the margin says nothing either
    best = float(lp.max())
    assert missed_reason(lambda x: np.full(len(x), best + 0.5 * MARGIN), NAMES, lp, [FAR]) is None


def test_sample_from_reports_the_exact_run_not_converged(monkeypatch):
    """After failed surrogates, an exact run that stayed in the first part is reported
    not converged with the reason; one that holds the higher part is left as it is."""
    rng = np.random.default_rng(2)

    class Split:
        names = NAMES
        law = SimpleNamespace(closed_form=False)
        likelihood = SimpleNamespace(model="exact")

        def __call__(self, theta):
            return _split(theta)

    posterior = Split()
    failed = SurrogateCheck(
        draws=128, weight_cv=np.inf, log_weight_sd=np.inf, attempt=3, best=FAR.copy()
    )

    def fake_surrogates(*args, seen=None, **kwargs):
        seen.append(FAR.copy())  # a surrogate's checked draw in the higher part
        return None, failed, None, None

    def exact_run(draws):
        def run(*args, **kwargs):
            return SamplerRun(
                chains=draws,
                log_prob=_split(draws.reshape(-1, 2)).reshape(draws.shape[:2]),
                autocorr_time=np.ones(2),
                n_steps=100,
                burn=10,
                thin=1,
                acceptance_fraction=0.3,
                ess=np.full(2, 1000.0),
                rhat=np.ones(2),
                converged=True,
                names=NAMES,
            )

        return run

    climbed_from: list[list[np.ndarray]] = []

    def climbed(post, points):
        climbed_from.append(list(points))
        return list(points)

    monkeypatch.setattr(chains, "climbed", climbed)
    monkeypatch.setattr(chains, "_first_surrogate", lambda *args: object())
    monkeypatch.setattr(chains, "initial_walkers", lambda *args: np.zeros((2, 8, 2)))
    monkeypatch.setattr(chains, "_sample_surrogate", fake_surrogates)
    start = Start(posterior, np.zeros(2), np.eye(2), None)
    settings = SamplerSettings(n_walkers=8, n_ensembles=2)

    first_part, _ = _walkers_in_first_part(rng)
    monkeypatch.setattr(chains, "_exact_run", exact_run(first_part))
    sampled = chains.sample_from(start, settings=settings, seed=0)
    assert not sampled.run.converged
    assert "higher by" in sampled.run.reasons[-1] and "a = 12" in sampled.run.reasons[-1]
    # the checked draws are climbed from before they are compared
    assert len(climbed_from) == 1 and np.array_equal(climbed_from[0][0], FAR)

    both_parts = first_part + np.where(np.arange(500) % 2 == 0, 1.0, 0.0)[None, :, None] * FAR
    monkeypatch.setattr(chains, "_exact_run", exact_run(both_parts))
    sampled = chains.sample_from(start, settings=settings, seed=0)
    assert sampled.run.converged and sampled.run.reasons == []


def test_climbed_adds_the_optimum_from_the_best_point():
    """A point checked far down the posterior's slope is climbed to its optimum."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prepared = prepare(read_run(BUNDLED), seed=0)
    posterior = build_posterior(prepared.data)
    theta, cov, _ = maximum_a_posteriori(posterior, prepared.decay)
    sd = np.sqrt(np.diag(cov))
    zeta = posterior.names.index("zeta")
    low, lower = theta.copy(), theta.copy()
    low[zeta] += 5.0 * sd[zeta]
    lower[zeta] -= 8.0 * sd[zeta]
    points = climbed(posterior, [lower, low, None])
    assert len(points) == 3 and np.array_equal(points[0], lower)
    top, at_optimum, given = posterior(np.vstack([points[-1], theta, low]))
    assert given < at_optimum - 10.0
    assert top > at_optimum - 1.0  # climbed from `low`, the better of the two
    assert climbed(posterior, []) == []


def test_a_climb_that_fails_leaves_the_points(monkeypatch):
    import bayestribo.inference.start as start

    def failing(*args, **kwargs):
        raise FloatingPointError("the least squares met a NaN")

    monkeypatch.setattr(start, "refine", failing)
    points = [FAR.copy(), np.zeros(2)]
    out = climbed(lambda theta: _split(theta), points)
    assert len(out) == 2 and np.array_equal(out[0], FAR)
