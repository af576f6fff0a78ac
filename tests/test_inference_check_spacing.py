"""The stopping rule's checks on a long run (inference/sampling.py ``check_spacing``):
every ``check_every`` steps up to twice ``check_every / CHECK_GROWTH``, then every
``CHECK_GROWTH`` of the steps run, so that a long run's checks cost in proportion to
its length; a run that stops before that is the run it was, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference import sampling
from bayestribo.inference.sampling import (
    CHECK_GROWTH,
    SamplerSettings,
    check_spacing,
    run_ensembles,
)


@pytest.mark.parametrize(
    ("steps", "spacing"),
    [(0, 50), (100, 50), (1999, 50), (2000, 100), (2999, 100), (3000, 150), (16_000, 800)],
)
def test_the_checks_come_every_five_percent_of_the_steps_past_2000(steps, spacing):
    assert CHECK_GROWTH == 0.05
    assert check_spacing(steps, 50) == spacing
    assert check_spacing(steps, 50) % 50 == 0


def _two_modes(theta: np.ndarray) -> np.ndarray:
    """Two narrow modes far apart: each ensemble mixes in its own and never crosses, so
    the rule's R-hat fails at every check and the run goes to its ceiling."""
    d = np.atleast_2d(theta)
    a = -0.5 * np.sum((d - 5.0) ** 2, axis=1) / 0.01
    b = -0.5 * np.sum((d + 5.0) ** 2, axis=1) / 0.01
    return np.logaddexp(a, b)


_AUTOCORR_TIMES = sampling._autocorr_times


def _run(target, max_steps: int, monkeypatch, growth: float | None = None):
    """A run of ``target`` and how many times its rule was checked."""
    monkeypatch.setattr(sampling, "CHECK_GROWTH", CHECK_GROWTH if growth is None else growth)
    seen: list[int] = []

    def counted(chains, *args, **kwargs):
        seen.append(chains.shape[1])
        return _AUTOCORR_TIMES(chains, *args, **kwargs)

    monkeypatch.setattr(sampling, "_autocorr_times", counted)
    settings = SamplerSettings(n_walkers=8, n_ensembles=2, max_steps=max_steps)
    start = 0.05 * np.random.default_rng(7).standard_normal((2, 8, 2))
    start += np.array([5.0, -5.0])[:, None, None]
    run = run_ensembles(target, start, settings, seed=8)
    return run, len(seen)


def test_a_long_run_is_checked_every_five_percent_of_its_steps(monkeypatch):
    # every 50 steps: up to 120 checks; every 50 up to 2000 (40), then 5 % of the
    # steps in whole 50s (10 of 100 steps, 7 of 150, 5 of 200, 4 of 250 or fewer): 66
    schedule, steps = 0, 0
    while steps < 6000:
        steps += min(check_spacing(steps, 50), 6000 - steps)
        schedule += 1
    assert schedule == 66
    run, checks = _run(_two_modes, 6000, monkeypatch)
    before, checks_before = _run(_two_modes, 6000, monkeypatch, growth=0.0)
    assert not run.converged and run.n_steps == before.n_steps == 6000
    # the same first few checks skipped in both (the rule cannot hold that early), the
    # rest as scheduled
    assert 110 <= checks_before <= 120
    assert schedule - checks == 120 - checks_before


def test_a_run_that_stops_before_2000_steps_is_the_run_it_was(monkeypatch):
    def gaussian(theta):
        d = np.atleast_2d(theta) - np.array([1.0, -2.0])
        return -0.5 * np.einsum("ni,ni->n", d, d)

    run, _ = _run(gaussian, 20_000, monkeypatch)
    before, _ = _run(gaussian, 20_000, monkeypatch, growth=0.0)
    assert run.n_steps < 2000 and run.converged
    assert run.n_steps == before.n_steps
    np.testing.assert_array_equal(run.chains, before.chains)
