"""Rest, spikes and clipping on independent simulations of a spring + disc in air.

m x'' + c x' + c2 x'|x'| + k x = 0 (k = 14.9 N/m, m = 0.2 kg, 1.37 Hz) integrated by
scipy's solve_ivp, the position 0.41 m + x rounded to the motion sensor's steps.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.errors import ClippingWarning, MisfitWarning, RecordingError
from bayestribo.io import validate_run
from bayestribo.io.run import Run
from bayestribo.signal.coverage import coverage_note
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.spikes import SpikeWarning


def _disc(duration: float, fs: float, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    k, m, c, c2 = 14.9, 0.2, 0.008, 0.05

    def rhs(_: float, s: np.ndarray) -> list[float]:
        return [s[1], -(c * s[1] + c2 * s[1] * abs(s[1]) + k * s[0]) / m]

    t = np.arange(0.0, duration, 1.0 / fs)
    x = solve_ivp(rhs, (0.0, duration), [0.08, 0.0], t_eval=t, rtol=1e-8, atol=1e-11).y[0]
    return t, np.round((0.41 + x) / step) * step, x


@pytest.fixture(scope="module")
def coarse() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """1 cm steps at 100 Hz for 90 s: the swing falls from 8 steps to half a step."""
    return _disc(90.0, 100.0, 0.01)


@pytest.fixture(scope="module")
def fine() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """0.1 mm steps at 200 Hz for 20 s."""
    return _disc(20.0, 200.0, 1e-4)


def _analyse(t: np.ndarray, x: np.ndarray) -> tuple[object, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        decay = energy_decay(t, x)
    return decay, caught


def test_coarse_steps_analysed_until_the_swing_is_below_one_step(coarse) -> None:
    t, pos, x = coarse
    decay, caught = _analyse(t, pos)
    above = t[np.flatnonzero(np.abs(x) > 0.01)[-1]]  # last swing beyond one step
    assert decay.end_time > above
    # the rest the noise comes from holds no oscillation of half a step
    assert decay.noise.source in ("rest after stop", "signal differences")
    if decay.motion_ended:
        rest = t > decay.end_time + 1.0
        assert np.abs(x[rest]).max() < 0.0055
    assert decay.noise.displacement == pytest.approx(0.01 / np.sqrt(12.0), rel=0.05)
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]


def test_spikes_named_and_not_ending_the_analysis(coarse) -> None:
    t, pos, _ = coarse
    spiked = pos.copy()
    for at in (20.3, 50.7):
        spiked[round(at * 100)] += 0.3
    decay, caught = _analyse(t, spiked)
    clean, _ = _analyse(t, pos)
    said = [str(w.message) for w in caught if issubclass(w.category, SpikeWarning)]
    assert len(said) == 1 and "20.3 s" in said[0] and "50.7 s" in said[0]
    assert decay.end_time == pytest.approx(clean.end_time)
    assert not np.any(np.abs(decay.peaks.value) > 0.2)


def test_quantised_smooth_troughs_are_not_clipping(fine) -> None:
    t, pos, _ = fine
    validate_run(Run(t, pos, metadata={"length_unit": "m"}))
    _, caught = _analyse(t, pos)
    assert not [w for w in caught if issubclass(w.category, ClippingWarning)]


def test_a_real_clip_is_named_and_its_cycles_left_out(fine) -> None:
    t, pos, x = fine
    level = 0.41 - 0.8 * 0.08
    clipped = np.maximum(pos, np.round(level / 1e-4) * 1e-4)
    run = Run(t, clipped, metadata={"length_unit": "m"})
    validate_run(run)  # the clipped cycles are the first ones: the analysis goes on
    decay, caught = _analyse(t, clipped)
    said = [str(w.message) for w in caught if issubclass(w.category, ClippingWarning)]
    assert len(said) == 1
    # cycles cut clearly (by more than 2 mm, 20 steps: a run far longer than a smooth
    # extreme's dwell) must be named; one cut by a step or two is a smooth extreme
    deep = int(np.sum(np.diff((x < -0.8 * 0.08 - 2e-3).astype(int)) == 1))
    cut = int(np.sum(np.diff((x < -0.8 * 0.08).astype(int)) == 1))
    named = int(said[0].split(" cycle(s)")[0].rsplit(" ", 1)[1])
    assert deep >= 1 and deep <= named <= cut
    assert f"minimum {float(clipped.min()):.6g}" in said[0]
    assert decay.start_time > t[np.flatnonzero(x < -0.8 * 0.08 - 2e-3)[-1]]
    with pytest.raises(RecordingError, match="held flat at its minimum"):
        validate_run(Run(t[:400], clipped[:400], metadata={"length_unit": "m"}))


def test_coverage_note_names_both_spans() -> None:
    assert coverage_note(2.0, 60.0, 1.0, 100.0, "why") is None
    note = coverage_note(2.0, 36.0, 1.0, 156.0, "its last turning point is at 36 s")
    assert note is not None and "2 s to 36 s" in note and "1 s to 156 s" in note


def test_bayestribo_decay_exits_1_on_a_short_analysis(tmp_path, monkeypatch, capsys) -> None:
    """As ``bayestribo fit`` does: the warning is said, and the status is 1."""
    import bayestribo.signal.decay as decay_module
    from bayestribo.cli import main
    from bayestribo.errors import ShortAnalysisWarning
    from bayestribo.io import write_run
    from bayestribo.synthetic import simulate

    path = write_run(simulate(seed=3), tmp_path / "r.csv")
    assert main(["decay", str(path)]) == 0
    real = decay_module.energy_decay

    def short(*args, **kwargs):
        warnings.warn("analysed 2 s to 36 s of 1 s to 156 s", ShortAnalysisWarning, stacklevel=2)
        return real(*args, **kwargs)

    monkeypatch.setattr(decay_module, "energy_decay", short)
    assert main(["decay", str(path)]) == 1
    assert "analysed 2 s to 36 s" in capsys.readouterr().err


@pytest.mark.parametrize(
    "run_id",
    ["water8.00pc-N0.12-r1", "water2.30pc-N0.12-r3", "water6.00pc-N0.46-r2", "glycerol-N0.31-r1"],
)
def test_steps_as_fine_as_the_noise_do_not_move_the_end_of_motion(bundled_runs, run_id):
    # The bundled runs are rounded to the vibrometer's resolution, about their noise: at
    # rest the noise toggles the displacement between levels, and a block straddling the
    # stop may still look periodic. The stop is the last excursion beyond the noise (the
    # manifest's true stop within a few samples), not the noise's last change of level
    # (80 ms late on the first three before).
    import csv

    from bayestribo.io import read_run
    from bayestribo.signal.motion import motion_span

    truth = {r["run_id"]: r for r in csv.DictReader(open(bundled_runs.parent / "manifest.csv"))}
    row = truth[run_id]
    stop = float(row["release_time_s"]) + float(row["motion_duration_s"])
    run = read_run(bundled_runs / f"{run_id}.csv")
    period = 1.0 / run.metadata["natural_frequency_Hz"]
    span = motion_span(run.time, run.velocity, period, periodic=run.displacement)
    dt = float(run.time[1] - run.time[0])
    assert abs(span.stop_time - stop) < 5 * dt
    assert span.stop_time == motion_span(run.time, run.velocity, period).stop_time
