"""Time as it was recorded: jittered stamps with dropped samples, as a teaching-lab DAQ
writes them, against an independent simulation.

``solve_ivp`` of x'' + 2ζω x' + ω² x = 0 (a torsion pendulum in air at 0.8 Hz),
sampled at 100 Hz with stamps jittered by ±0.5 ms (uniform), two single samples
dropped, and the angle quantised to 0.011 (a DAQ's 12-bit steps over ±22).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo import fit, read_run
from bayestribo._clock import bridge_gaps, timeline
from bayestribo.errors import GapWarning, RecordingError
from bayestribo.io.files import write_run
from bayestribo.io.run import Run
from bayestribo.signal.decay import energy_decay

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

F_HZ, ZETA, THETA0, FS, QUANTUM = 0.8, 0.01, 1.2, 100.0, 0.011
DROPPED = (1234, 3210)


@functools.lru_cache(maxsize=1)
def _record() -> tuple[np.ndarray, np.ndarray]:
    omega = 2 * math.pi * F_HZ
    t = np.arange(0.0, 40.0, 1.0 / FS)
    sol = solve_ivp(
        lambda _t, u: [u[1], -2 * ZETA * omega * u[1] - omega**2 * u[0]],
        (0.0, t[-1]),
        [THETA0, 0.0],
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
    )
    rng = np.random.default_rng(7)
    stamps = t + rng.uniform(-5e-4, 5e-4, t.size)
    angle = np.round(sol.y[0] / QUANTUM) * QUANTUM
    keep = np.setdiff1d(np.arange(t.size), DROPPED)
    return np.round(stamps[keep], 4), angle[keep]


def test_the_gaps_are_found_on_the_jittered_grid():
    stamps, _ = _record()
    line = timeline(stamps)
    assert line.on_grid
    assert line.clock.step == pytest.approx(0.01, rel=1e-5)
    assert [(g.after, g.missing) for g in line.gaps] == [(1233, 1), (3208, 1)]


def test_a_daq_record_with_jitter_and_dropped_samples_is_read_and_fitted(tmp_path):
    stamps, angle = _record()
    path = write_run(
        Run(stamps, angle, metadata={"length_unit": "arbitrary"}), tmp_path / "daq.csv"
    )
    run = read_run(path)  # no refusal for jitter or two dropped samples
    with pytest.warns(GapWarning, match=r"2 gap\(s\).*after sample 1233.*after sample 3208"):
        decay = energy_decay(run.time, run.displacement, None)
    np.testing.assert_allclose(np.diff(decay.t), 0.01, rtol=1e-4)  # on the grid
    with pytest.warns(GapWarning):
        result = fit(run, seed=3, grid_points=32)
    zeta = result.samples("zeta")
    assert abs(np.mean(zeta) - ZETA) < 4 * np.std(zeta)


def test_bridged_samples_are_within_their_bound_of_the_motion():
    t = np.arange(0.0, 5.0, 0.01)
    x = np.cos(2 * math.pi * F_HZ * t) + np.random.default_rng(1).normal(0, 1e-3, t.size)
    keep = np.setdiff1d(np.arange(t.size), [200, 301, 302])
    grid, out, gaps = bridge_gaps(t[keep], {"x": x[keep]}, 1 / F_HZ)
    np.testing.assert_allclose(grid, t, atol=1e-12)
    np.testing.assert_array_equal(out["x"][keep], x[keep])  # recorded samples unchanged
    truth = np.cos(2 * math.pi * F_HZ * t)
    for index in (200, 301, 302):
        assert abs(out["x"][index] - truth[index]) < gaps[0].error_bound + 4e-3
    assert [g.missing for g in gaps] == [1, 2]


def test_a_gap_beyond_a_tenth_of_a_period_or_a_restarted_clock_is_refused():
    t = np.arange(0.0, 5.0, 0.01)
    x = np.cos(2 * math.pi * F_HZ * t) + np.random.default_rng(2).normal(0, 1e-3, t.size)
    long = np.setdiff1d(np.arange(t.size), np.arange(100, 120))  # a sixth of a period
    with pytest.raises(RecordingError, match=r"20 samples are missing after sample 99"):
        bridge_gaps(t[long], {"x": x[long]}, 1 / F_HZ)
    # a clock that went on at another rate after sample 249 (a resampled segment)
    other = np.r_[t[:250], t[249] + 0.0125 * np.arange(1, 251)]
    with pytest.raises(RecordingError, match=r"leave the regular grid at sample \d+"):
        bridge_gaps(np.delete(other, 100), {"x": np.delete(x, 100)}, 1 / F_HZ)
    # the bridge's error bound beyond the noise: a noiseless record is not bridged
    smooth = np.cos(2 * math.pi * 3.0 * t)
    with pytest.raises(RecordingError, match=r"could be off by .* beyond the noise"):
        bridge_gaps(np.delete(t, 100), {"x": np.delete(smooth, 100)}, 1 / 3.0)
