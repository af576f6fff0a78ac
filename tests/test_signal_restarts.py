"""A time column that restarts within a record: continued where the signal is, cut where not.

The records are written here from the closed form of a viscously damped oscillator
(x = A e^{-ζωt} cos(ω_d t), nothing from the package's models), on a regular 2 kHz clock,
then given a restart: the stamps fall back to zero at one sample, with or without
samples lost there.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.errors import ClockRestartWarning, RecordingError, ShortAnalysisWarning
from bayestribo.io import read_run
from bayestribo.signal.restarts import JUMP_FACTOR, continue_clock, restarts

RATE = 2000.0
F = 32.6
ZETA = 0.004
AT = 1500


def _record(n: int = 6000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n) / RATE
    w = 2 * np.pi * F
    wd = w * np.sqrt(1 - ZETA**2)
    x = 1e-3 * np.exp(-ZETA * w * t) * np.cos(wd * t)
    v = 1e-3 * np.exp(-ZETA * w * t) * (-ZETA * w * np.cos(wd * t) - wd * np.sin(wd * t))
    return t, x, v


def _restarted(t: np.ndarray, lost: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Stamps falling back to 0 at sample AT, with ``lost`` samples dropped before it."""
    keep = np.r_[0:AT, AT + lost : t.size]
    stamps = t[keep].copy()
    stamps[AT:] -= stamps[AT]
    return stamps, keep


def _write(path, t, x, v) -> None:
    np.savetxt(
        path,
        np.column_stack([t, x, v]),
        delimiter=",",
        header="time_s,displacement_m,velocity_m_per_s",
        comments="",
    )


def test_a_contiguous_restart_is_continued_on_the_sample_step():
    t, x, v = _record()
    stamps, _ = _restarted(t)
    found = restarts(stamps, x, v)
    assert [(r.at, r.contiguous) for r in found] == [(AT, True)]
    assert found[0].jump <= JUMP_FACTOR
    out, x2, v2, said, cut = continue_clock(stamps, x, v)
    assert cut is None and said == found
    np.testing.assert_allclose(out, t, rtol=0, atol=1e-9)
    assert x2 is x and v2 is v  # the samples themselves untouched


@pytest.mark.parametrize("lost", [1, 5])
def test_samples_lost_at_the_restart_are_seen_in_either_channel(lost):
    t, x, v = _record()
    stamps, keep = _restarted(t, lost)
    for channels in ((x[keep], None), (None, v[keep]), (x[keep], v[keep])):
        (found,) = restarts(stamps, *channels)
        assert not found.contiguous and found.jump > JUMP_FACTOR
    out, x2, v2, _, cut = continue_clock(stamps, x[keep], v[keep])
    assert cut == AT and out.size == x2.size == v2.size == AT
    np.testing.assert_array_equal(out, stamps[:AT])


def test_a_record_that_never_restarts_is_returned_as_it_is():
    t, x, v = _record()
    out, x2, v2, said, cut = continue_clock(t, x, v)
    assert np.shares_memory(out, t) and x2 is x and v2 is v and said == () and cut is None


def test_a_fall_at_the_end_of_the_record_is_not_taken_for_a_restart(tmp_path):
    t, x, v = _record()
    stamps = t.copy()
    stamps[-3:] -= 1.0  # three samples: too few to judge, so not continued
    assert restarts(stamps, x, v) == ()
    path = tmp_path / "end.csv"
    _write(path, stamps, x, v)
    with pytest.raises(RecordingError, match="not strictly increasing: sample 5997"):
        read_run(path)


def test_reading_a_restarted_record_continues_it_and_says_so(tmp_path):
    t, x, v = _record()
    stamps, _ = _restarted(t)
    path = tmp_path / "restarted.csv"
    _write(path, stamps, x, v)
    with pytest.warns(ClockRestartWarning, match=r"restarts at sample 1500 \(t = 0 s after"):
        run = read_run(path)
    np.testing.assert_allclose(run.time, t, rtol=0, atol=1e-9)
    # a window is taken on the continued clock
    with pytest.warns(ClockRestartWarning):
        part = read_run(path, window=(0.5, 1.0))
    assert part.time[0] == pytest.approx(0.5) and part.time[-1] == pytest.approx(1.0)


def test_the_fit_of_a_continued_record_is_the_fit_of_the_record_without_restart(tmp_path):
    from bayestribo import fit

    t, x, v = _record()
    stamps, _ = _restarted(t)
    whole, restarted = tmp_path / "whole.csv", tmp_path / "restarted.csv"
    _write(whole, t, x, v)
    _write(restarted, stamps, x, v)
    a = fit(str(whole), seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ClockRestartWarning)
        b = fit(str(restarted), seed=3)
    for name in ("zeta",):
        sa, sb = a.samples(name), b.samples(name)
        assert abs(np.mean(sa) - np.mean(sb)) < 0.05 * np.std(sa)
        assert np.quantile(sb, 0.025) < ZETA < np.quantile(sb, 0.975)


def test_the_command_line_exits_1_when_samples_are_left_out(tmp_path, capsys):
    t, x, v = _record()
    stamps, keep = _restarted(t, lost=5)
    path = tmp_path / "lost.csv"
    _write(path, stamps, x[keep], v[keep])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        status = main(["fit", str(path), "--quiet", "--json"])
    err = capsys.readouterr().err
    assert status == 1
    assert "only samples 0 to 1499" in err and "samples 1500 to 5994 were left out" in err
    assert issubclass(ShortAnalysisWarning, Warning)
