"""A sensor's analog high-pass (an AC-coupled channel, a geophone): undone, and named.

Independent simulations: the closed-form viscous + Coulomb decay half cycle by half
cycle, sampled at ten times the record's rate, put through the analog high-pass by
:func:`scipy.signal.lsim` and decimated, the sensor's white noise added after it.
"""

from __future__ import annotations

import functools
import json
import math
import re
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import lsim

from bayestribo import fit, read_run
from bayestribo.cli.main import main
from bayestribo.errors import HighPassWarning, MisfitWarning, RunFormatError
from bayestribo.inference.checks import _high_corner, _high_pass_sign, _warn_misfit
from bayestribo.inference.preparation import prepare
from bayestribo.io import as_run
from bayestribo.io.files import write_run
from bayestribo.io.high_pass import UNDONE, undone
from bayestribo.io.run import Run
from bayestribo.signal.high_pass import (
    check_high_pass,
    detect_high_pass,
    high_pass_gain,
    undo_high_pass,
)

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

F, ZETA, MU_K, LOAD, MASS = 3.0, 0.008, 0.02, 1.0, 0.3
RATE, X0, NOISE = 500.0, 0.02, 2e-4  # Hz, m, m/s
META = {"load_N": LOAD, "mass_kg": MASS, "natural_frequency_Hz": F}


def _decay(rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time [s], displacement [m] and velocity [m/s] of the decay, noise-free: 1 s of
    rest, the release from X0, the stop where a turning point is within 1.5 x_c, 3 s
    of rest."""
    w = 2 * math.pi * F
    wd = w * math.sqrt(1 - ZETA**2)
    x_c = MU_K * LOAD / (MASS * w * w)
    t = np.arange(0.0, 12.0, 1.0 / rate)
    x, v = np.full(t.size, X0), np.zeros(t.size)
    start, xk = 1.0, X0
    while abs(xk) > 1.5 * x_c:
        s = math.copysign(1.0, xk)
        m = t >= start
        tau = t[m] - start
        a = xk - s * x_c
        e = np.exp(-ZETA * w * tau)
        x[m] = s * x_c + a * e * (np.cos(wd * tau) + ZETA * w / wd * np.sin(wd * tau))
        v[m] = -a * w * w / wd * e * np.sin(wd * tau)
        start += math.pi / wd
        xk = s * x_c - a * math.exp(-ZETA * w * math.pi / wd)
    m = t >= start
    x[m], v[m] = xk, 0.0
    return t, x, v


@functools.lru_cache(maxsize=8)
def _recorded(cutoff: float, order: int = 1, noise: float = NOISE, seed: int = 3):
    """Time, the high-passed velocity with noise, and the true velocity, at RATE."""
    t, _, v = _decay(10 * RATE)
    wc = 2 * math.pi * cutoff
    system = ([1.0, 0.0], [1.0, wc]) if order == 1 else ([1, 0, 0], [1, 2 * 0.7 * wc, wc * wc])
    _, y, _ = lsim(system, v, t)
    t, y, v = t[::10], y[::10], v[::10]
    return t, y + np.random.default_rng(seed).normal(0.0, noise, t.size), v


def test_a_declaration_is_checked_and_normalised():
    assert check_high_pass(0.5) == {"cutoff_Hz": 0.5, "order": 1}
    assert check_high_pass({"cutoff_Hz": 4.5, "order": 2}) == {
        "cutoff_Hz": 4.5,
        "order": 2,
        "damping": pytest.approx(1 / math.sqrt(2)),
    }
    for bad in (
        {"cutoff_Hz": -1},
        {"cutoff_Hz": 1, "order": 3},
        {"cutoff_Hz": 1, "damping": 0.7},
        {"corner": 1},
        "0.5",
    ):
        with pytest.raises(ValueError):
            check_high_pass(bad)
    # the gain at f of one pole at f/6
    assert high_pass_gain({"cutoff_Hz": 0.5}, 3.0) == pytest.approx(6 / math.sqrt(37))


@pytest.mark.parametrize(
    ("spec", "field"),
    [
        (10**400, "cutoff_Hz"),  # an int no float holds (a sidecar's JSON may hold one)
        ({"cutoff_Hz": 10**5000}, "cutoff_Hz"),  # beyond int-to-text conversion as well
        ({"cutoff_Hz": 1, "order": 2, "damping": -(10**400)}, "damping"),
        ({"cutoff_Hz": True}, "cutoff_Hz"),
        ({"cutoff_Hz": float("inf")}, "cutoff_Hz"),
    ],
)
def test_a_number_no_float_holds_is_refused_naming_its_field(spec, field):
    with pytest.raises(ValueError, match=rf"'{field}' must be") as caught:
        check_high_pass(spec)
    assert len(str(caught.value)) < 200  # the number shortened, not printed whole


@pytest.mark.parametrize("order", [1, 2])
def test_the_inverse_gives_the_motion_before_the_filter(order):
    t, y, v = _recorded(0.5 if order == 1 else 0.9, order, noise=0.0)
    spec = (
        {"cutoff_Hz": 0.5, "order": 1}
        if order == 1
        else {"cutoff_Hz": 0.9, "order": 2, "damping": 0.7}
    )
    index = np.arange(t.size)
    rests = (index < 480, index > t.size - 1400)
    u = undo_high_pass(t, y, spec, zero_at_rest=True, rests=rests)
    # the record is far from the motion; the inverse within 1e-3 of its swing
    assert np.max(np.abs(y - v)) > 0.05 * np.max(np.abs(v))
    assert np.max(np.abs(u - v)) < 1e-3 * np.max(np.abs(v))


def test_a_run_that_declares_its_high_pass_is_read_undone(tmp_path):
    t, y, v = _recorded(0.5)
    run = Run(t, None, y, metadata={**META, "sensor_high_pass": {"cutoff_Hz": 0.5}})
    path = write_run(run, tmp_path / "geophone.csv")
    read = read_run(path)
    record = read.metadata[UNDONE]
    assert record["cutoff_Hz"] == 0.5 and record["order"] == 1
    assert record["channels"] == ["velocity"] and "noise" in record
    assert np.std(read.velocity - v) < 1.5 * NOISE  # the recorded noise, a little walk
    # read once: again, and through as_run, nothing changes
    assert undone(read) is read and as_run(read) == read
    with pytest.raises(RunFormatError, match="sensor_high_pass"):
        read_run(path, metadata={"sensor_high_pass": {"cutoff_Hz": 0.5, "order": 4}})


def test_the_option_declares_it(tmp_path, capsys):
    t, y, _ = _recorded(0.5)
    path = write_run(Run(t, None, y, metadata=META), tmp_path / "geophone.csv")
    assert main(["inspect", str(path), "--sensor-high-pass", "0.5"]) in (0, 1)
    said = capsys.readouterr().out
    assert "the sensor's high-pass at 0.5 Hz (one pole; --sensor-high-pass 0.5)" in said
    with pytest.raises(SystemExit):
        main(["inspect", str(path), "--sensor-high-pass", "0.5:3"])
    assert "HZ[:ORDER[:DAMPING]]" in capsys.readouterr().err


@pytest.mark.parametrize("cutoff", [0.3, 0.5, 0.9])
def test_the_sign_gives_the_corner(cutoff):
    t, y, _ = _recorded(cutoff)
    tt = prepare(Run(t, None, y, metadata=META)).decay.turning_times
    sign = detect_high_pass(t, y, tt, velocity=True)
    assert sign is not None and sign.cutoff_Hz == pytest.approx(cutoff, rel=0.02)
    assert f"--sensor-high-pass {sign.cutoff_Hz:.3g}" in sign.advice()


@pytest.mark.parametrize("cutoff", [0.5, 0.9])
def test_the_sign_tells_a_geophones_two_poles(cutoff):
    t, y, _ = _recorded(cutoff, 2)
    tt = prepare(Run(t, None, y, metadata=META)).decay.turning_times
    sign = detect_high_pass(t, y, tt, velocity=True)
    assert sign is not None and sign.order == 2
    assert sign.cutoff_Hz == pytest.approx(cutoff, rel=0.03)
    assert sign.damping == pytest.approx(0.7, abs=0.03)
    assert "--sensor-high-pass " + f"{sign.cutoff_Hz:.3g}:2:" in sign.advice()
    # one-pole records are not taken for two
    t, y, _ = _recorded(cutoff, 1)
    tt = prepare(Run(t, None, y, metadata=META)).decay.turning_times
    assert detect_high_pass(t, y, tt, velocity=True).order == 1


def test_a_corner_beyond_the_calibrated_is_said():
    t, y, _ = _recorded(0.9)  # a corner at 0.3 times the oscillation's frequency
    high = prepare(Run(t, None, y, metadata={**META, "sensor_high_pass": 0.9}))
    assert _high_corner(high) == pytest.approx(0.3, rel=0.01)
    t, y, _ = _recorded(0.25)
    low = prepare(Run(t, None, y, metadata={**META, "sensor_high_pass": 0.25}))
    assert _high_corner(low) is None


def test_no_sign_without_a_high_pass():
    t, _, v = _recorded(0.5)
    y = v + np.random.default_rng(5).normal(0.0, NOISE, v.size)
    prepared = prepare(Run(t, None, y, metadata=META))
    assert _high_pass_sign(prepared) is None
    # nor where the run declares it
    t, y, _ = _recorded(0.5)
    declared = prepare(Run(t, None, y, metadata={**META, "sensor_high_pass": 0.5}))
    assert _high_pass_sign(declared) is None


def test_the_misfit_names_the_high_pass_instead_of_another_law():
    t, y, _ = _recorded(0.5)
    sign = _high_pass_sign(prepare(Run(t, None, y, metadata=META)))
    assert sign is not None
    shape = SimpleNamespace(p_value=1.0)  # no smooth departure: the χ² alone misfits
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_misfit(
            "geophone", (500.0, 31, 1e-20), shape, False, "viscous+coulomb", high_pass=sign
        )
    texts = [(w.category, str(w.message)) for w in caught]
    assert len(texts) == 1 and texts[0][0] is HighPassWarning
    assert issubclass(HighPassWarning, MisfitWarning)  # the fit exits 1
    assert re.search(r"--sensor-high-pass 0\.(49|50)\d*\b", texts[0][1])
    assert "--law auto" not in texts[0][1]


def test_the_advice_followed_answers(tmp_path, capsys):
    t, y, _ = _recorded(0.5)
    path = write_run(Run(t, None, y, metadata=META), tmp_path / "geophone.csv")
    sign = _high_pass_sign(prepare(read_run(path)))
    option = sign.advice().split("(--sensor-high-pass ")[1].split(")")[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(read_run(path, metadata={"sensor_high_pass": float(option)}), seed=1)
    # no misfit; at 0.17 f the corner is beyond the calibrated and said so (exit 1)
    said = [w for w in caught if issubclass(w.category, MisfitWarning)]
    assert [w.category for w in said] == [HighPassWarning]
    assert "may be too narrow" in str(said[0].message)
    for name, true in (("zeta", ZETA), ("mu_k", MU_K)):
        lo, hi = result.interval(name)
        assert lo <= true <= hi, (name, lo, hi)
    assert result.metadata[UNDONE]["cutoff_Hz"] == float(option)
    assert main(["fit", str(path), "--sensor-high-pass", option, "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert "high_pass_undone" in json.dumps(out)
