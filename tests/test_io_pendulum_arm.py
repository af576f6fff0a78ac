"""A pendulum recorded as a length, x = r sin θ: read as its angle, and advised so.

Independent simulations (``solve_ivp``, :mod:`_pendulum_decay`): a simple pendulum with
viscous damping and Coulomb friction at the pivot, f₀ = 0.7 Hz, its bob recorded as
x = r sin θ with r = g/ω₀² (its length), in metres with 0.2 mm of noise.
"""

from __future__ import annotations

import functools
import json
import math
import warnings

import numpy as np
import pytest
from _pendulum_decay import Swing, swing

from bayestribo import fit, read_run
from bayestribo.cli.main import main
from bayestribo.errors import (
    ArmNoiseWarning,
    ClippingWarning,
    LinearSpringWarning,
    MisfitWarning,
    RecordingError,
    RunFormatError,
)
from bayestribo.inference.restoring_choice import simple_pendulum_arm
from bayestribo.io import as_run
from bayestribo.io.files import write_run
from bayestribo.io.pendulum_arm import as_angle
from bayestribo.io.run import Run
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.peaks import find_peaks
from bayestribo.signal.pendulum_arm import GRAVITY, simple_radius

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

F0, ZETA, MU = 0.7, 0.003, 0.004
RADIUS = GRAVITY / (2 * math.pi * F0) ** 2  # 0.507 m
NOISE = 2e-4  # m


@functools.lru_cache(maxsize=4)
def _bob(degrees: float = 30.0, rate: float = 200.0, duration: float = 40.0):
    """Time [s], x = r sin θ [m] with noise, and the noise-free θ [rad] and θ' [rad/s]."""
    case = Swing(
        f0=F0,
        zeta=ZETA,
        friction=MU,
        x0=math.radians(degrees),
        rate=rate,
        duration=duration,
        noise=0.0,
        noise_v=0.0,
    )
    t, theta, omega = swing(case, 0)
    x = RADIUS * np.sin(theta) + np.random.default_rng(4).normal(0.0, NOISE, t.size)
    return t, x, theta, omega


def test_a_length_is_read_as_the_angle_it_records():
    t, x, theta, omega = _bob()
    centre = 0.013  # the tracker's origin is not the pivot's vertical
    v = RADIUS * np.cos(theta) * omega
    run = Run(t, x + centre, v, metadata={"pendulum_radius_m": RADIUS})
    angle = as_angle(run)
    assert angle.length_unit == "rad" and angle.metadata["restoring"] == "pendulum"
    arm = angle.metadata["pendulum_arm"]
    assert arm["radius_m"] == RADIUS and arm["source"] == "given"
    assert arm["centre_m"] == pytest.approx(centre, abs=2e-5)
    assert arm["largest_angle_deg"] == pytest.approx(30.0, abs=0.1)
    # θ within the noise's reach (2e-4 / r / cos θ), the velocity θ' = v/(r cos θ)
    assert np.max(np.abs(angle.displacement - theta)) < 6 * NOISE / RADIUS / math.cos(0.53)
    assert np.max(np.abs(angle.velocity - omega)) < 1e-3
    # read once: again, and through as_run, nothing changes
    assert as_angle(angle) is angle and as_run(angle) == angle
    assert as_run(run) == angle


def test_a_simple_pendulums_length_is_measured_from_its_turning_times():
    t, x, *_ = _bob(50.0, 200.0, 50.0)
    peaks = find_peaks(t, x, offset="constant")
    radius, frequency = simple_radius(peaks.t, peaks.value)
    # the half period at 50° is 5 % longer than the small swings': r is g/ω₀², not the
    # length the first swings' period would give (10 % longer)
    assert radius == pytest.approx(RADIUS, rel=2e-3)
    assert frequency == pytest.approx(F0, rel=1e-3)
    first = np.mean(np.diff(peaks.t[:6]))
    assert GRAVITY * (first / math.pi) ** 2 > 1.05 * RADIUS


def test_the_simple_radius_is_read_and_said(tmp_path):
    t, x, *_ = _bob()
    path = write_run(Run(t, x, metadata={"natural_frequency_Hz": F0}), tmp_path / "bob.csv")
    side = json.loads(path.with_suffix(".json").read_text())
    side["pendulum_radius_m"] = "simple"
    path.with_suffix(".json").write_text(json.dumps(side))
    run = read_run(path)
    arm = run.metadata["pendulum_arm"]
    assert arm["radius_m"] == pytest.approx(RADIUS, rel=2e-3)
    assert "a simple pendulum: r = g/ω₀²" in arm["source"] and "an assumption" in arm["source"]
    # the command line's option is the sidecar's key
    assert main(["inspect", str(path)]) == 0
    path.with_suffix(".json").write_text(json.dumps({"natural_frequency_Hz": F0}))
    assert read_run(path).length_unit == "m"
    assert main(["inspect", str(path), "--pendulum-radius", "simple"]) == 0


@pytest.mark.parametrize(
    ("metadata", "error", "match"),
    [
        ({"pendulum_radius_m": 0.1}, RecordingError, "at or beyond the radius 0.1"),
        ({"pendulum_radius_m": -1.0}, RunFormatError, "0 < r <= 1000, or 'simple'"),
        ({"pendulum_radius_m": "long"}, RunFormatError, "0 < r <= 1000, or 'simple'"),
        (
            {"pendulum_radius_m": "simple", "length_unit": "arbitrary"},
            RunFormatError,
            "give the radius in the displacement's unit",
        ),
        (
            {"pendulum_radius_m": 0.5, "length_unit": "rad"},
            RunFormatError,
            "in radians already",
        ),
    ],
)
def test_a_radius_that_cannot_be_is_refused(metadata, error, match):
    t, x, *_ = _bob()
    with pytest.raises(error, match=match):
        as_angle(Run(t, x, metadata=metadata))


def test_only_a_record_that_changes_as_a_simple_pendulums_is_told_to_read_it_so():
    t, x, theta, _ = _bob()
    with pytest.warns(ClippingWarning) as caught:
        decay = energy_decay(t, x, None)
    # its largest swings bend as a saturating sensor's would: the warning says what
    # they are here, and how to read them
    said = [str(w.message) for w in caught if w.category is ClippingWarning]
    assert len(said) == 1 and "--pendulum-radius simple" in said[0]
    assert simple_pendulum_arm(decay.turning_times, decay.peaks.value) == pytest.approx(
        RADIUS, rel=5e-3
    )
    # the angle itself (in radians, not a length): no simple pendulum of r = g/ω₀²
    # follows it
    angle = energy_decay(t, theta + np.random.default_rng(5).normal(0, 4e-4, t.size), None)
    assert simple_pendulum_arm(angle.turning_times, angle.peaks.value) is None
    # a linear oscillator: its half period is constant
    w = 2 * math.pi * F0
    linear = np.exp(-ZETA * w * t) * 0.25 * np.cos(w * t)
    decay = energy_decay(t, linear + np.random.default_rng(6).normal(0, NOISE, t.size), None)
    assert simple_pendulum_arm(decay.turning_times, decay.peaks.value) is None


def _fit(run):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=2, grid_points=32)
    return result, caught


def test_the_advice_of_the_misfit_names_the_reading_and_followed_it_covers_the_truth():
    t, x, *_ = _bob()
    _, caught = _fit(Run(t, x, metadata={"natural_frequency_Hz": F0}))
    said = [str(w.message) for w in caught if issubclass(w.category, MisfitWarning)]
    assert said, "a pendulum fitted on a linear spring misfits"
    assert all("--pendulum-radius simple" in text for text in said)
    # no restoring force of x is advised: none is a pendulum's
    assert not any("--restoring duffing" in str(w.message) for w in caught)
    # followed literally: the angle, on the pendulum's force, with no misfit
    followed, caught = _fit(
        Run(t, x, metadata={"natural_frequency_Hz": F0, "pendulum_radius_m": "simple"})
    )
    assert not [w for w in caught if issubclass(w.category, MisfitWarning | LinearSpringWarning)]
    assert followed.restoring["name"] == "pendulum"
    assert "θ = arcsin((x - c)/r) with r = 0.50" in followed.to_text()
    for name, truth in (("zeta", ZETA), ("friction_displacement", MU)):
        lo, hi = followed.interval(name, 0.95)
        assert lo <= truth <= hi, (name, lo, hi)


def test_a_misfit_at_large_angles_says_the_noise_grows_there_not_another_law():
    from types import SimpleNamespace

    from bayestribo.inference.checks import _arm_noise_growth, _warn_misfit

    t, x, *_ = _bob(60.0, 100.0, 60.0)
    wide = as_angle(Run(t, x, metadata={"pendulum_radius_m": RADIUS}))
    degrees, grown = _arm_noise_growth(wide)
    assert degrees == pytest.approx(60.0, abs=0.2) and grown == pytest.approx(2.0, rel=0.01)
    # at 40° (1.31×) the intervals covered 10 of 10 (benchmarks/pendulum_arm.py): no flag
    t, x, *_ = _bob(40.0, 100.0, 50.0)
    assert _arm_noise_growth(as_angle(Run(t, x, metadata={"pendulum_radius_m": RADIUS}))) is None
    assert issubclass(ArmNoiseWarning, MisfitWarning)  # the fit beyond 48° exits 1
    shape = SimpleNamespace(p_value=1.0, describe=lambda: "")
    with pytest.warns(MisfitWarning) as caught:
        _warn_misfit("bob", (193.0, 81, 1.5e-10), shape, False, "viscous+coulomb", grown=(60, 2))
    said = str(caught[0].message)
    assert "grows as 1/cos θ, to 2.00× its value at rest" in said and "--law auto" not in said
