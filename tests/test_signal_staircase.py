"""A coarse displacement's turning points from its staircase, and the law-free ΔE(A) read
off them, on records independent of the package's models (the closed-form viscous +
Coulomb decay of ``tests/_coarse_decay.py``, and solve_ivp of a quadratic drag)."""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from _coarse_decay import coarse_record
from scipy.integrate import solve_ivp

from bayestribo.errors import EnergyGainWarning
from bayestribo.inference.dissipation import dissipation_amplitudes, turning_point_dissipation
from bayestribo.inference.law_free import law_free_turning_points, warn_energy_gain
from bayestribo.io.run import Run
from bayestribo.model.laws import PhysicalScale
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.staircase import coarse_turning_points, staircase_turning_points

META = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31, "gain_uncertainty": 0.0}


def _true_turning(t: np.ndarray, x: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The unrounded record's extreme within a tenth of a period of each time."""
    out = []
    for tn in times:
        near = np.abs(t - tn) < 0.1 / 32.6
        seg = x[near]
        out.append(seg[np.argmax(np.abs(seg))])
    return np.asarray(out)


def _true_loss(turning: np.ndarray, swings: np.ndarray) -> np.ndarray:
    """ΔE/k per cycle at the swings, x_n² − x_n+1² interpolated log-log."""
    a = np.abs(turning)
    swing, loss = 0.5 * (a[:-1] + a[1:]), a[:-1] ** 2 - a[1:] ** 2
    order = np.argsort(swing)
    return np.exp(np.interp(np.log(swings), np.log(swing[order]), np.log(loss[order])))


@functools.cache
def _quadratic_motion() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quadratic drag (x'' + β|x'|x' + ω²x = 0) from 2 mm at rest, 10 kHz, 0.1 s of
    rest first."""
    w, beta = 2 * math.pi * 32.6, 80.0
    sol = solve_ivp(
        lambda _, s: [s[1], -(w**2) * s[0] - beta * abs(s[1]) * s[1]],
        (0.0, 0.6),
        [2e-3, 0.0],
        dense_output=True,
        rtol=1e-10,
        atol=1e-13,
    )
    t = np.arange(0.0, 0.7, 1e-4)
    x, v = np.full(t.size, 2e-3), np.zeros(t.size)
    moving = t >= 0.1
    x[moving], v[moving] = sol.sol(t[moving] - 0.1)
    return t, x, v


def _quadratic_record(steps: float, placement: float) -> tuple[np.ndarray, ...]:
    """The quadratic drag's motion, both channels rounded to 1/``steps`` of their swing."""
    t, x, v = _quadratic_motion()
    qx, qv = np.ptp(x) / steps, np.ptp(v) / steps
    u = placement
    return t, x, (np.round(x / qx + u) - u) * qx, (np.round(v / qv + u) - u) * qv, qx


def test_a_coulomb_staircase_gives_back_its_turning_points_and_equilibrium():
    # Coulomb friction about c = 0.3: half cycles are arcs of cosines about c ± x_c, the
    # swing falling by 2 x_c each (from 2.6 to 1.9, steps of 1, levels off the zero)
    c, xc, omega = 0.3, 0.05, 2 * math.pi
    t = np.arange(0.0, 4.0, 1e-3)
    times = np.arange(8) * 0.5
    amp = 2.6 - 2 * xc * np.arange(8)
    signs = (-1.0) ** np.arange(8)
    x = np.full(t.size, np.nan)
    for k in range(8):
        arc = (t >= times[k]) & (t < times[k] + 0.5)
        phase = np.cos(omega * (t[arc] - times[k]))
        x[arc] = c + signs[k] * (xc + (amp[k] - xc) * phase)
    rounded = np.round(x - 0.2) + 0.2
    got = staircase_turning_points(t, rounded, times, signs, 1.0, omega)
    assert got is not None
    values, offset, drift = got
    assert offset == pytest.approx(c, abs=0.01)
    assert drift == 0.0
    # within a fiftieth of a step, where the levels are up to half a step off; the first
    # (its arc before it not recorded) and the last (after it) are left out
    inner = slice(1, 7)
    np.testing.assert_allclose(values[inner], (signs * amp)[inner], atol=0.02)
    level_error = np.abs(np.round(signs * amp + c - 0.2) + 0.2 - c - signs * amp)
    assert level_error[inner].max() > 0.25


@pytest.mark.parametrize("placement", [-0.4, -0.1, 0.2, 0.45])
def test_coarse_turning_points_are_within_a_tenth_of_a_step(placement):
    t, x, v, (qx, _), _ = coarse_record(4.0, placement)
    exact = coarse_record(1e9, 0.0)[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = energy_decay(t, x, v, rig=Run(time=t, displacement=x, velocity=v).rig(32.6))
    stair = coarse_turning_points(decay, t, x)
    assert stair is not None
    truth = _true_turning(t, exact, decay.peaks.t)
    ok = np.isfinite(stair)
    assert ok.sum() >= 4
    staircase_error = np.abs(stair[ok] - truth[ok]) / qx
    level_error = np.abs(decay.peaks.value - truth) / qx
    assert staircase_error.max() < 0.1
    # the levels themselves are up to half a step off (what the staircase corrects)
    assert level_error.max() > 2 * staircase_error.max()


def test_a_dithered_displacement_keeps_its_parabolas():
    # 1000 steps across the swing: the noise dithers them, no staircase is read
    t, x, v, _, _ = coarse_record(1000.0, 0.1)
    rng = np.random.default_rng(3)
    x = x + 2e-6 * rng.standard_normal(t.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        decay = energy_decay(t, x, v, rig=Run(time=t, displacement=x, velocity=v).rig(32.6))
    assert coarse_turning_points(decay, t, x) is None


class _Prepared:
    def __init__(self, t, x, v):
        self.run = Run(time=t, displacement=x, velocity=v, metadata=META)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.decay = energy_decay(t, x, v, rig=self.run.rig())
        self.name = "simulated"


def _coverage(records) -> tuple[float, float, int, int]:
    """Swings covered by the law-free 95 % band read off the staircase and off the levels,
    and the swings whose mean is below zero, each way."""
    hits = {True: 0, False: 0}
    negative = {True: 0, False: 0}
    total = 0
    for t, exact, x, v in records:
        prepared = _Prepared(t, x, v)
        stair, used = law_free_turning_points(prepared, warn_levels=False)
        assert used
        ell = prepared.decay.scaling.length_scale
        swings = dissipation_amplitudes(stair * ell)
        truth = _true_loss(_true_turning(t, exact, prepared.decay.peaks.t), swings)
        for staircase, values in ((True, stair * ell), (False, prepared.decay.peaks.value)):
            band = turning_point_dissipation(values, swings, PhysicalScale(1.0, 1.0, "m"))
            lo, hi = (np.asarray(b) for b in band["interval"])
            hits[staircase] += int(np.sum((lo <= truth) & (truth <= hi)))
            negative[staircase] += int(np.sum(np.asarray(band["mean"]) < 0))
        total += swings.size
    return hits[True] / total, hits[False] / total, negative[True], negative[False]


def test_the_law_free_band_of_a_coarse_friction_decay_covers_and_stays_positive():
    # viscous + Coulomb at 4 steps across the swing, levels at 5 placements (seeded)
    rng = np.random.default_rng(39)
    exact = coarse_record(1e9, 0.0)[1]
    records = []
    for u in rng.uniform(-0.5, 0.5, 5):
        t, x, v, _, _ = coarse_record(4.0, float(u))
        records.append((t, exact, x, v))
    stair, _, stair_negative, _ = _coverage(records)
    # 60 swings: below 0.85 has probability < 1e-3 at the nominal 95 %
    assert stair >= 0.85
    assert stair_negative == 0


def test_the_law_free_band_of_a_coarse_drag_decay_covers_and_stays_positive():
    rng = np.random.default_rng(42)
    records = []
    for u in rng.uniform(-0.5, 0.5, 4):
        t, exact, x, v, _ = _quadratic_record(5.0, float(u))
        records.append((t, exact, x, v))
    stair, _, stair_negative, levels_negative = _coverage(records)
    assert stair >= 0.85
    assert stair_negative == 0
    # the levels' band, as read before: means below zero (an energy gain) at some swings
    assert levels_negative > 0


def test_a_band_wholly_below_zero_is_an_energy_gain_warning():
    measured = {
        "amplitude": [1e-4, 2e-4, 4e-4],
        "amplitude_unit": "m",
        "interval": [[-3e-9, -1e-9, 1e-9], [-1e-9, 1e-9, 3e-9]],
    }
    with pytest.warns(EnergyGainWarning, match="1 swing"):
        assert warn_energy_gain("run", measured) == [1e-4]
    measured["interval"][1][0] = 1e-10
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert warn_energy_gain("run", measured) == []


def test_a_fit_of_a_coarse_record_reports_the_staircase_law_free_answer():
    from bayestribo import fit
    from bayestribo.inference.law_free import STAIRCASE

    t, x, v, _, _ = coarse_record(4.0, 0.3)
    exact = coarse_record(1e9, 0.0)[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(Run(time=t, displacement=x, velocity=v, metadata=META), seed=2)
    measured = result.turning_point_dissipation
    assert STAIRCASE in measured["definition"]
    lo, hi = (np.asarray(b) for b in measured["interval"])
    assert np.all(np.asarray(measured["mean"]) > 0)
    # the truth in joules at the reported swings (k = mω² of the record's 32.6 Hz)
    k = META["mass_kg"] * (2 * math.pi * 32.6) ** 2
    swings = np.asarray(measured["amplitude"])
    d = np.diff(exact)
    turns = np.flatnonzero((d[:-1] > 0) & (d[1:] <= 0) | (d[:-1] < 0) & (d[1:] >= 0)) + 1
    truth = k * _true_loss(np.concatenate([[exact[0]], exact[turns]]), swings)
    assert np.mean((lo <= truth) & (truth <= hi)) >= 0.75
