"""One period estimator for the whole package, and the names that moved to signal/."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from bayestribo.errors import RecordingError
from bayestribo.io.run import Run
from bayestribo.signal import channels, frequency, period
from bayestribo.signal.period import dominant_period


def _decay(rate: float = 2000.0, f: float = 32.6, seconds: float = 1.0) -> Run:
    t = np.arange(round(rate * seconds)) / rate
    x = 1e-3 * np.exp(-0.5 * t) * np.cos(2 * np.pi * f * t)
    v = np.gradient(x, t)
    return Run(time=t, displacement=x, velocity=v)


def test_the_period_of_a_decay():
    run = _decay()
    assert dominant_period(run.time, run.displacement) == pytest.approx(1 / 32.6, rel=1e-3)


def test_a_flat_signal_has_no_period():
    t = np.arange(100) / 100.0
    with pytest.raises(RecordingError, match="does not oscillate"):
        dominant_period(t, np.ones_like(t))


def test_the_period_of_a_runs_arrays_is_computed_once(monkeypatch):
    run = _decay()
    calls = []
    spectral = period._spectral_period

    def counted(t, s):
        calls.append(1)
        return spectral(t, s)

    monkeypatch.setattr(period, "_spectral_period", counted)
    first = dominant_period(run.time, run.displacement)
    assert dominant_period(run.time, run.displacement) == first
    assert len(calls) == 1
    # a writeable copy is not remembered: its values may change
    writeable = np.array(run.displacement)
    dominant_period(run.time, writeable)
    dominant_period(run.time, writeable)
    assert len(calls) == 3


def test_the_readers_checks_use_the_one_estimator(monkeypatch):
    """The channel comparison and the unit hint take the period from dominant_period."""
    run = _decay()
    seen = []

    def spy(t, s):
        seen.append(s is run.displacement)
        return dominant_period(t, s)

    monkeypatch.setattr(channels, "dominant_period", spy)
    channels._CONSISTENCY.clear()
    assert channels.channel_consistency(run).gain == pytest.approx(1.0, rel=0.01)
    assert channels._motion(run)[0] == pytest.approx(32.6, rel=1e-3)
    assert seen == [True, True]


@pytest.mark.parametrize(
    ("old", "new", "name"),
    [
        ("bayestribo.io.frequency", frequency, "oscillation_frequency"),
        ("bayestribo.io.frequency", frequency, "frequency_trend"),
        ("bayestribo.io.frequency", frequency, "FrequencyTrend"),
        ("bayestribo.io.validation", channels, "channel_consistency"),
        ("bayestribo.io.validation", channels, "ChannelConsistency"),
        ("bayestribo.io.validation", channels, "UNIT_GAIN_TOLERANCE"),
    ],
)
def test_moved_names_still_import_with_a_deprecation_warning(old, new, name):
    module = importlib.import_module(old)
    with pytest.warns(DeprecationWarning, match=f"moved to {new.__name__}"):
        assert getattr(module, name) is getattr(new, name)


def test_check_channels_is_still_the_readers():
    from bayestribo.io.validation import check_channels

    assert check_channels is channels.check_channels


def test_unknown_names_of_a_moved_module_raise_attribute_error():
    from bayestribo.io import frequency as old

    with pytest.raises(AttributeError):
        old.no_such_name  # noqa: B018


def test_candidates_left_uncomputed_change_no_period(monkeypatch):
    # where the strongest peak's power is beyond any candidate's bound, the candidates
    # are not scored; the period is the one scoring them all gives, to the bit, on
    # decays, decays with a rest, a mains line, a drift, a large offset, and noise
    rng = np.random.default_rng(12)
    signals = []
    for trial in range(120):
        fs = float(rng.choice([1000.0, 2000.0, 10_000.0]))
        n = int(rng.integers(256, 20_000))
        t = np.arange(n) / fs
        rest = int(rng.integers(0, n // 3))
        u = np.arange(n - rest) / fs
        decay = np.exp(-rng.uniform(0.0, 5.0) * u) * np.cos(2 * np.pi * rng.uniform(1, fs / 8) * u)
        s = np.r_[np.full(rest, 1.0), decay]
        s = [
            s,
            s + rng.uniform(0.0, 0.5) * np.sin(2 * np.pi * 50.0 * t),
            s + np.linspace(0.0, rng.uniform(0.0, 20.0), n),
            0.01 * s + rng.uniform(-1e4, 1e4) + 1e-3 * rng.standard_normal(n),
            rng.standard_normal(n),
        ][trial % 5]
        signals.append((t, s))
    shortcut = []
    decided = period._unbeatable

    def noted(s, power):
        shortcut.append(decided(s, power))
        return shortcut[-1]

    monkeypatch.setattr(period, "_unbeatable", noted)
    fast = [period._spectral_period(t, s) for t, s in signals]
    monkeypatch.setattr(period, "_unbeatable", lambda s, p: False)
    every = [period._spectral_period(t, s) for t, s in signals]
    assert fast == every
    assert 20 <= sum(shortcut) < len(signals)
