"""All estimators on one run: the table, cross-checks between methods, real recordings."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from _paths import APPSTAT
from test_estimators_signals import F_HZ, sampled

from bayestribo import Estimate, estimate_all
from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.estimators import estimate_signals, friction_fraction
from bayestribo.estimators.all import METHODS
from bayestribo.io.run import Run
from bayestribo.model.scaling import Rig
from bayestribo.synthetic import PAPER_RIG

HARMOSC = APPSTAT

FRICTION_AWARE = ("feeny_liang", "nonsuccessive", "energy_ls_exact", "energy_ls_averaged")


@pytest.mark.parametrize(
    ("zeta", "mu", "y0"),
    [
        (0.001, 0.0, 10.0),  # nearly undamped, many oscillations (record cut at 400π)
        (0.001, 0.1, 10.0),  # friction-dominated, 47 turning points
        (0.1, 0.0, 10.0),  # strongly viscous
        (0.1, 0.1, 10.0),  # both strong, 10 turning points
        (0.03, 0.05, 3.0),  # both, ~14 turning points
    ],
)
def test_methods_agree_with_truth_and_each_other(zeta, mu, y0):
    t, x, v = sampled(zeta, mu, y0, noise_x=1e-4 * y0, noise_v=1e-4 * y0 * 2 * math.pi * F_HZ)
    # The record starts at rest at a turning point, no release transient: skip nothing.
    table = estimate_signals(t, x, v, rig=Rig(F_HZ), skip_oscillations=0)
    z_scale = zeta + 2 * mu / (math.pi * y0)
    m_scale = mu + math.pi * zeta * y0 / 2
    got = [e for e in table if e.method in FRICTION_AWARE]
    assert len(got) == 6  # two peak methods on x and on v, two energy models
    for e in got:
        assert e.ok, e.notes
        # noise 1e-4 Y_0 per sample; the averaged model's own error (5 %, see
        # test_estimators_energy_ls) is the loosest: 5 % of the damping scales for all
        assert abs(e.zeta - zeta) <= 0.05 * z_scale, (e.method, e.data, e.zeta)
        assert abs(e.friction_displacement - mu) <= 0.05 * m_scale, (e.method, e.data)
    # and therefore with each other (within twice that)
    zs = [e.zeta for e in got]
    assert max(zs) - min(zs) <= 0.1 * z_scale


def test_table_json_has_nulls_and_every_method():
    t, x, _ = sampled(0.0236, 0.0294, 10.0)
    table = estimate_signals(t, x, name="sim")
    d = json.loads(table.to_json())
    assert d["run"] == "sim"
    assert [e["method"] for e in d["estimates"]] == list(METHODS)
    for e in d["estimates"]:
        assert set(e) >= {"method", "zeta", "zeta_se", "mu_k", "mu_k_se", "friction_displacement"}
        assert e["mu_k"] is None  # no load or mass: μ_k undefined, x_c given instead
    log = d["estimates"][0]
    assert log["friction_displacement"] is None  # a viscous-only method
    text = table.to_text()
    assert all(m in text for m in METHODS)


def test_failed_method_is_a_row_with_the_reason():
    # 6 turning points: the first is the release (on the edge), so 4 peaks: too few
    # for the non-successive method (needs Y_0, Y_2p, Y_2q)
    t, x, _ = sampled(0.01, 0.1, 1.0)
    table = estimate_signals(t, x, skip_oscillations=0)
    row = table["nonsuccessive"]
    assert not row.ok and "no estimate" in row.notes and "5" in row.notes
    assert row.to_dict()["zeta"] is None


def test_run_object_and_rig_from_metadata():
    from bayestribo.synthetic.recording import simulate

    run = simulate(rig=PAPER_RIG, seed=3)
    table = estimate_all(run, skip_oscillations=1, methods=["feeny_liang", "energy_ls_exact"])
    for e in table:
        # μ_k needs the run's load and mass (ℓ = N/k); resolution noise and a magnet
        # fade in the first oscillation (skipped): 1 % of ζ, 2 % of μ_k
        assert e.mu_k == pytest.approx(0.0294, rel=0.02), (e.method, e.data)
        assert e.zeta == pytest.approx(0.0236, rel=0.01), (e.method, e.data)


def test_bad_arguments():
    t, x, _ = sampled(0.0236, 0.0294, 10.0)
    with pytest.raises(RecordingError, match="unknown method"):
        estimate_signals(t, x, methods=["magic"])
    with pytest.raises(RecordingError, match="displacement x or a velocity v"):
        estimate_signals(t)
    with pytest.raises(BayestriboError, match="run: expected a bayestribo Run or the path"):
        estimate_all(t)
    with pytest.raises(TypeError):
        estimate_all(Run(t, displacement=x), x)  # arrays go to estimate_signals


def test_friction_fraction_limits_and_closed_form():
    assert friction_fraction(0.01, 0.0, 1.0) == 0.0
    assert friction_fraction(0.0, 0.01, 1.0) == 1.0
    zeta, mu, a0, a1 = 0.02, 0.03, 10.0, 1.0
    g = 2 * mu / (math.pi * zeta)
    closed = (g * (a0 - a1) - g * g * math.log((a0 + g) / (a1 + g))) / (0.5 * (a0**2 - a1**2))
    assert friction_fraction(zeta, mu, a0, a1) == pytest.approx(closed, rel=1e-10)
    with pytest.raises(ValueError, match="a0 > a_end"):
        friction_fraction(zeta, mu, 1.0, 2.0)


def test_estimate_is_exported():
    assert Estimate(method="x").ok is False


def _harmosc(name):
    from bayestribo.io import read_run

    path = HARMOSC / f"{name}.txt"
    if not path.is_file():
        pytest.skip(f"real recording {path} not available")
    return read_run(
        path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"}
    )


def test_real_recordings_viscous_versus_friction():
    air = estimate_all(_harmosc("HarmOsc1"))  # 100 Hz, air damping only
    plate = estimate_all(_harmosc("HarmOsc3"))  # 1 kHz, dry friction against a plate
    for table in (air, plate):
        for e in table:
            assert e.ok, (table.run, e.method, e.notes)
            assert e.mu_k is None  # no load, no mass: friction as a displacement only
    # the paper's method (both models) splits the dissipation: HarmOsc1 viscous,
    # HarmOsc3 friction
    for model in ("energy_ls_averaged", "energy_ls_exact"):
        assert air[model].friction_fraction < 0.1
        assert plate[model].friction_fraction > 0.9
    # the peak methods agree on the side of the verdict
    for e in plate:
        if e.friction_fraction is not None:
            assert e.friction_fraction > 0.5, (e.method, e.data)
    for e in air:
        if e.friction_fraction is not None:
            assert e.friction_fraction < 0.5, (e.method, e.data)
    # natural frequency from the recording: the same spring in both (period ~0.68 s)
    w_air = air["energy_ls_exact"].details["omega"]
    w_plate = plate["energy_ls_exact"].details["omega"]
    assert w_air == pytest.approx(w_plate, rel=0.05)
    # independent check: mean-level crossings of HarmOsc1 (56 periods, ±1 crossing of
    # 112 is 1 %); Ω is the undamped frequency, within ζ²/2 ~ 1e-6 of the damped one
    run = _harmosc("HarmOsc1")
    x = run.displacement - np.median(run.displacement)
    crossings = np.flatnonzero(np.diff(np.sign(x)) != 0)
    periods = (crossings.size - 1) / 2
    f_cross = periods / (run.time[crossings[-1]] - run.time[crossings[0]])
    assert w_air / (2 * math.pi) == pytest.approx(f_cross, rel=0.02)


def test_an_estimate_summarises_with_its_standard_errors():
    t, x, v = sampled(0.0236, 0.0294, 10.0)
    [est] = estimate_signals(t, x, v, rig=Rig(F_HZ), methods=["energy_ls_exact"])
    s90, s99 = est.summary(0.9)["zeta"], est.summary(0.99)["zeta"]
    assert s90.kind == "normal" and s90.prob == 0.9 and s90.sd == est.zeta_se
    assert s90.mean == est.zeta and s90.low < est.zeta < s90.high
    assert s99.high - s99.low > s90.high - s90.low
    # ±1.645 sd for 90 %
    assert (s90.high - s90.low) / (2 * est.zeta_se) == pytest.approx(1.6448536, rel=1e-6)


def test_the_estimators_and_the_fit_analyse_the_same_window(bundled_run):
    from bayestribo.estimators.energy_ls import energy_data
    from bayestribo.inference import prepare

    run = bundled_run
    decay = prepare(run).decay
    data = energy_data(run.time, run.displacement, run.velocity, rig=run.rig())
    # The same samples: as many, from the same start to the same end of motion (the
    # least squares takes Ω from the rig, the fit measures it: y differs by 1e-5).
    assert data.y.size == decay.y.size
    assert data.y[0] == pytest.approx(decay.y[0], rel=1e-5)
    table = estimate_all(run, methods=["feeny_liang"])
    for row in table:
        assert row.ok, row.notes
    # The peak methods count the turning points of the window only: those from its
    # start (a turning point, within a sample step) to the end of motion.
    from bayestribo.signal.peaks import find_peaks

    peaks = find_peaks(run.time, run.displacement)
    inside = int(np.count_nonzero(peaks.t >= decay.start_time - 0.75e-4))
    assert 0 < inside < len(peaks)
    assert table["feeny_liang"].data.startswith(f"displacement peaks (n={inside})")
