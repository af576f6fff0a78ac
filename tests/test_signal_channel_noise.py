"""The recorded channel's Monte Carlo noise: drawn once per recipe inside a block."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from bayestribo.signal import channel_noise, increments
from bayestribo.signal.channel_noise import recorded_noise, reused_noise
from bayestribo.signal.increments import increment_draws, increment_weights
from bayestribo.signal.spectrum import noise_spectrum

N = 401
TAU = np.linspace(0.0, 8 * np.pi, N)
EDGES, WEIGHTS = increment_weights(N, float(TAU[1] - TAU[0]), 8)


def motion(decrement: float) -> tuple[np.ndarray, np.ndarray]:
    envelope = np.exp(-decrement * TAU)
    return envelope * np.cos(TAU), -envelope * np.sin(TAU)


def draws(y, yp, *, seed=1, sigma_y=1e-3, sigma_yp=1e-3, derived="velocity", **kwargs):
    return increment_draws(
        TAU,
        y,
        yp,
        EDGES,
        WEIGHTS,
        sigma_y,
        sigma_yp,
        derived=derived,
        savgol_window=9,
        n_replicates=60,
        seed=seed,
        **kwargs,
    )


@pytest.fixture
def calls(monkeypatch) -> list[int]:
    """Counts the draws made (not the blocks given again)."""
    made: list[int] = []
    original = channel_noise._draw

    def counted(*args, **kwargs):
        made.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(channel_noise, "_draw", counted)
    return made


def test_the_stream_is_the_one_seeded_rows_drawn_block_by_block():
    blocks = list(recorded_noise(N, 0.5, n_replicates=60, seed=3, block=25))
    assert [b.shape for b in blocks] == [(25, N), (25, N), (10, N)]
    rng = np.random.default_rng(3)
    expected = [rng.normal(0.0, 0.5, (k, N)) for k in (25, 25, 10)]
    for got, want in zip(blocks, expected, strict=True):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("derived", ["velocity", "displacement"])
def test_kept_noise_gives_every_motion_the_same_numbers_and_is_drawn_once(calls, derived):
    motions = [motion(0.03), motion(0.01), motion(0.05)]
    fresh = [draws(*m, derived=derived) for m in motions]
    assert len(calls) == 3
    with reused_noise():
        kept = [draws(*m, derived=derived) for m in motions]
    assert len(calls) == 4
    for a, b in zip(kept, fresh, strict=True):
        np.testing.assert_array_equal(a, b)
    # nothing is kept once the block has ended
    draws(*motions[0], derived=derived)
    assert len(calls) == 5


def test_kept_noise_is_keyed_by_every_input_of_the_draws(calls):
    y, yp = motion(0.03)
    rest = np.random.default_rng(0).normal(0.0, 1e-4, 4096)
    spectrum = noise_spectrum([rest], 100.0)
    recipes = [
        {},
        {"seed": 2},
        {"sigma_y": 2e-3},
        {"derived": "displacement"},
        {"derived": "displacement", "sigma_yp": 2e-3},
        {"spectrum": spectrum},
        {"spectrum": spectrum, "spectrum_scale": 3.0},
    ]
    # white noise of one level from one seed is the same numbers whichever channel is
    # recorded: the displacement's draws are the velocity's at that level
    distinct = len(recipes) - 2
    fresh = [draws(y, yp, **r) for r in recipes]
    calls.clear()
    with reused_noise():
        kept = [draws(y, yp, **r) for r in recipes]
        assert len(calls) == distinct
        again = [draws(y, yp, **r) for r in recipes]
        assert len(calls) == distinct
    for a, b, c in zip(fresh, kept, again, strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)


def test_blocks_share_the_outermost_and_too_large_a_recipe_is_not_kept(calls, monkeypatch):
    y, yp = motion(0.03)
    with reused_noise():
        draws(y, yp)
        with reused_noise():
            draws(y, yp)
        draws(y, yp)
        assert len(calls) == 1
        monkeypatch.setattr(channel_noise, "KEEP_LIMIT", 60 * N - 1)
        draws(y, yp, seed=7)
        draws(y, yp, seed=7)
        assert len(calls) == 3


def test_an_accelerometers_draws_and_a_generator_seed_are_not_kept(calls):
    y, yp = motion(0.03)

    def velocity_draws(count, rng):
        return rng.normal(0.0, 1e-3, (count, N))

    with reused_noise():
        first = draws(y, yp, derived="displacement", velocity_draws=velocity_draws)
        second = draws(y, yp, derived="displacement", velocity_draws=velocity_draws)
        assert len(calls) == 2
        # a generator is a stream that moves on: its draws are never given again
        rng = np.random.default_rng(5)
        a = next(recorded_noise(N, 1.0, n_replicates=4, seed=rng, block=4))
        b = next(recorded_noise(N, 1.0, n_replicates=4, seed=rng, block=4))
    assert len(calls) == 4
    np.testing.assert_array_equal(first, second)
    assert not np.array_equal(a, b)


def test_the_recipes_used_longest_ago_are_let_go_first(calls, monkeypatch):
    y, yp = motion(0.03)
    # room for two recipes of 60 replicates, each its noise and the noise's derivative
    monkeypatch.setattr(channel_noise, "KEEP_LIMIT", 2 * 2 * 60 * N)
    fresh = {seed: draws(y, yp, seed=seed) for seed in (1, 2, 3)}
    calls.clear()
    with reused_noise():
        for seed, drawn in [(1, 1), (2, 2), (1, 2), (3, 3), (1, 3), (2, 4)]:
            # seed 3 lets go of seed 2, used longer ago than seed 1
            np.testing.assert_array_equal(draws(y, yp, seed=seed), fresh[seed])
            assert len(calls) == drawn
        kept = channel_noise._KEPT.get()
        assert sum(entry[2] for entry in kept.values()) <= 2 * 2 * 60 * N


def test_the_derived_velocitys_noise_is_the_filter_of_the_noisy_motion():
    # the derivative is linear: the motion's plus the noise's (kept with the noise) is
    # the derivative of the noisy motion, to rounding, edges included
    y, yp = motion(0.03)
    got = draws(y, yp, sigma_y=2e-3)
    filtered = increments._VelocityFilter(TAU, 9)
    reference = increments._integrate_by_blas(0.5 * (y * y + yp * yp), EDGES, WEIGHTS)
    noise = np.concatenate(list(recorded_noise(N, 2e-3, n_replicates=60, seed=1, block=25)))
    noisy = y + noise
    savgol = scipy.signal.savgol_filter(
        noisy, 9, 5, deriv=1, delta=float(TAU[1] - TAU[0]), mode="interp", axis=-1
    )
    energy = 0.5 * (noisy * noisy + savgol * savgol)
    want = increments._integrate_by_blas(energy, EDGES, WEIGHTS) - reference
    np.testing.assert_allclose(filtered(noisy), savgol, rtol=0, atol=1e-12)
    scale = np.max(np.abs(want))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * scale)
    assert np.std(got) > 1e-3 * scale  # the draws are not all zero


def test_the_noises_derivative_is_kept_beside_it_and_given_again(calls, monkeypatch):
    filtered: list[int] = []
    original = increments._VelocityFilter.__call__

    def counted(self, rows):
        filtered.append(np.shape(rows)[0] if np.ndim(rows) == 2 else 1)
        return original(self, rows)

    monkeypatch.setattr(increments._VelocityFilter, "__call__", counted)
    motions = [motion(0.03), motion(0.01)]
    with reused_noise():
        kept = [draws(*m) for m in motions]
        # the first motion filters itself and every replicate, the second itself alone
        assert filtered == [1, 25, 25, 10, 1]
        assert len(calls) == 1
    fresh = [draws(*m) for m in motions]
    for a, b in zip(kept, fresh, strict=True):
        np.testing.assert_array_equal(a, b)
