"""The Monte Carlo noise of a derived channel: drawn once, added to each motion."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
from scipy.integrate import cumulative_trapezoid

from bayestribo.signal import channel_noise
from bayestribo.signal.channel_noise import reused_noise
from bayestribo.signal.increments import (
    detrended,
    increment_draws,
    increment_weights,
    integrate_increments,
)

N = 401
TAU = np.linspace(0.0, 8 * np.pi, N)
EDGES, WEIGHTS = increment_weights(N, float(TAU[1] - TAU[0]), 8)


def motion(decrement: float, lag: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A damped cosine and a velocity that is not quite its derivative (``lag``), so
    that the derived channel of the motion differs from the y' given."""
    envelope = np.exp(-decrement * TAU)
    return envelope * np.cos(TAU), -envelope * np.sin(TAU + lag)


def rederived(y, yp, derived, sigma, seed, replicates, window=9):
    """The increments' changes with the derivation repeated on the noisy recorded
    channel, written out independently of the module (the blocks of 25 replicates
    it draws)."""
    rng = np.random.default_rng(seed)
    h = float(TAU[1] - TAU[0])
    reference = integrate_increments(0.5 * (y * y + yp * yp)[None], EDGES, WEIGHTS)
    rows = []
    for first in range(0, replicates, 25):
        draw = rng.normal(0.0, sigma, (min(25, replicates - first), N))
        if derived == "velocity":
            yn = y + draw
            ypn = scipy.signal.savgol_filter(yn, window, 5, deriv=1, delta=h, mode="interp")
        else:
            yn = y + detrended(cumulative_trapezoid(draw, TAU, initial=0.0, axis=-1), TAU)
            ypn = yp + draw
        rows.append(integrate_increments(0.5 * (yn * yn + ypn * ypn), EDGES, WEIGHTS) - reference)
    return np.vstack(rows)


@pytest.mark.parametrize("derived", ["velocity", "displacement"])
def test_the_noise_added_to_the_motion_is_the_derivation_of_the_noisy_channel(derived):
    y, yp = motion(0.03, lag=0.05)
    sigma = 1e-3
    draws = increment_draws(
        TAU,
        y,
        yp,
        EDGES,
        WEIGHTS,
        sigma,
        sigma,
        derived=derived,
        savgol_window=9,
        n_replicates=60,
        seed=4,
    )
    expected = rederived(y, yp, derived, sigma, seed=4, replicates=60)
    # rounding alone: the changes are about σ·|y|·√samples, their rounding 1e-16 of E
    scale = float(np.max(np.abs(expected)))
    np.testing.assert_allclose(draws, expected, rtol=0, atol=1e-9 * scale)


def _counting(monkeypatch) -> list[int]:
    calls: list[int] = []
    original = channel_noise._draw

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(channel_noise, "_draw", counted)
    return calls


def _draws(y, yp, *, seed=1, sigma=1e-3, derived="velocity", **kwargs):
    return increment_draws(
        TAU,
        y,
        yp,
        EDGES,
        WEIGHTS,
        sigma,
        sigma,
        derived=derived,
        savgol_window=9,
        n_replicates=60,
        seed=seed,
        **kwargs,
    )


def test_kept_noise_gives_the_same_numbers_and_is_drawn_once(monkeypatch):
    calls = _counting(monkeypatch)
    motions = [motion(0.03), motion(0.01, lag=0.02), motion(0.05)]
    fresh = [_draws(*m) for m in motions]
    assert len(calls) == 3
    with reused_noise():
        kept = [_draws(*m) for m in motions]
    assert len(calls) == 4
    for a, b in zip(kept, fresh, strict=True):
        np.testing.assert_array_equal(a, b)
    # nothing is kept once the block has ended
    _draws(*motions[0])
    assert len(calls) == 5


def test_kept_noise_is_keyed_by_every_input_of_the_draws(monkeypatch):
    calls = _counting(monkeypatch)
    y, yp = motion(0.03)
    recipes = [
        {},
        {"seed": 2},
        {"sigma_y": 2e-3},
        {"derived": "displacement"},
        {"derived": "displacement", "sigma_yp": 2e-3},
        {"savgol_window": 11},
    ]

    def draws(recipe):
        recipe = dict(recipe)
        window = recipe.pop("savgol_window", 9)
        return increment_draws(
            TAU,
            y,
            yp,
            EDGES,
            WEIGHTS,
            recipe.get("sigma_y", 1e-3),
            recipe.get("sigma_yp", 1e-3),
            derived=recipe.get("derived", "velocity"),
            savgol_window=window,
            n_replicates=60,
            seed=recipe.get("seed", 1),
        )

    fresh = [draws(r) for r in recipes]
    calls.clear()
    with reused_noise():
        kept = [draws(r) for r in recipes]
        assert len(calls) == len(recipes)
        again = [draws(r) for r in recipes]
        assert len(calls) == len(recipes)
    for a, b, c in zip(fresh, kept, again, strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)


def test_blocks_share_the_outermost_and_too_large_a_recipe_is_not_kept(monkeypatch):
    calls = _counting(monkeypatch)
    y, yp = motion(0.03)
    with reused_noise():
        _draws(y, yp)
        with reused_noise():
            _draws(y, yp)
        _draws(y, yp)
        assert len(calls) == 1
        monkeypatch.setattr(channel_noise, "KEEP_LIMIT", 2 * 60 * N - 1)
        _draws(y, yp, seed=7)
        _draws(y, yp, seed=7)
        assert len(calls) == 3


def test_an_accelerometers_draws_are_not_kept(monkeypatch):
    calls = _counting(monkeypatch)
    y, yp = motion(0.03)

    def velocity_draws(count, rng):
        return rng.normal(0.0, 1e-3, (count, N))

    with reused_noise():
        first = _draws(y, yp, derived="displacement", velocity_draws=velocity_draws)
        second = _draws(y, yp, derived="displacement", velocity_draws=velocity_draws)
    assert len(calls) == 2
    np.testing.assert_array_equal(first, second)
