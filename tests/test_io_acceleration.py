"""Accelerometer records: an acceleration read, its bias removed, integrated into the
velocity, and fitted.

Independent reference: the viscous free decay from x₀ at rest in closed form,
v(t) = −x₀ (Ω²/ω_d) e^{−ζΩt} sin ω_d t, sampled as an accelerometer with an anti-alias
filter samples it (the mean acceleration over each sample interval, (v(t + Δt/2) −
v(t − Δt/2))/Δt), with a bias and white noise, rest before the release and a decay
into the noise after.
"""

from __future__ import annotations

import functools
import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from bayestribo import fit, read_run
from bayestribo.errors import ReadingWarning, RecordingError, RunFormatError
from bayestribo.io.acceleration import (
    CUTOFF_RATIO,
    CUTOFF_RATIO_OPEN,
    from_acceleration,
    integrate_acceleration,
    principal_axis,
)
from bayestribo.io.columns import STANDARD_GRAVITY, parse_column
from bayestribo.io.sidecar import sidecar_path, write_sidecar

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

F_HZ, ZETA, X0, RATE, REST = 2.5, 0.02, 0.03, 200.0, 2.0
NOISE, BIAS, DURATION = 0.02, 0.3, 24.0


def _velocity(t: np.ndarray, zeta: float = ZETA) -> np.ndarray:
    """The closed-form velocity [m/s] of the decay released at t = REST."""
    omega = 2 * math.pi * F_HZ
    wd = omega * math.sqrt(1 - zeta**2)
    s = np.maximum(t - REST, 0.0)
    return -X0 * omega**2 / wd * np.exp(-zeta * omega * s) * np.sin(wd * s)


def _record(seed: int = 1, noise: float = NOISE, bias: float = BIAS, zeta: float = ZETA):
    """Time [s], measured acceleration [m/s²] and the true velocity [m/s]."""
    t = np.arange(0.0, DURATION, 1.0 / RATE)
    dt = 1.0 / RATE
    a = (_velocity(t + dt / 2, zeta) - _velocity(t - dt / 2, zeta)) / dt
    rng = np.random.default_rng(seed)
    return t, a + bias + noise * rng.standard_normal(t.size), _velocity(t, zeta)


def _csv(path: Path, header: str, columns: list[np.ndarray], meta: dict | None = None) -> Path:
    rows = np.column_stack(columns)
    np.savetxt(path, rows, delimiter=",", header=header, comments="")
    write_sidecar(meta or {"natural_frequency_Hz": F_HZ}, sidecar_path(path))
    return path


@pytest.mark.parametrize(
    ("name", "canonical", "factor"),
    [
        ("acceleration_m_per_s2", "acceleration_m_per_s2", 1.0),
        ("Acceleration (m/s^2)", "acceleration_m_per_s2", 1.0),
        ("Acceleration [mm/s²]", "acceleration_m_per_s2", 1e-3),
        ("accel_g", "acceleration_m_per_s2", STANDARD_GRAVITY),
        ("a [g]", "acceleration_m_per_s2", STANDARD_GRAVITY),
        ("Acceleration x (m/s^2)", "acceleration_x_m_per_s2", 1.0),
        ("Linear Acceleration z (m/s^2)", "acceleration_z_m_per_s2", 1.0),
        ("accel_y_g", "acceleration_y_m_per_s2", STANDARD_GRAVITY),
        ("angular_acceleration_deg_per_s2", "angular_acceleration_rad_per_s2", math.pi / 180),
        ("Angular acceleration (rad/s^2)", "angular_acceleration_rad_per_s2", 1.0),
    ],
)
def test_acceleration_columns_and_units(name: str, canonical: str, factor: float) -> None:
    assert parse_column(name) == (canonical, pytest.approx(factor, rel=1e-15))


def test_an_acceleration_without_a_unit_or_in_a_velocity_unit_is_refused() -> None:
    with pytest.raises(ValueError, match=r"'accel' has no unit.*'g'"):
        parse_column("accel")
    with pytest.raises(ValueError, match=r"unknown unit 'm/s' for acceleration_m_per_s2"):
        parse_column("Acceleration (m/s)")


def test_the_integrated_velocity_follows_the_true_one_and_the_bias_is_measured_at_rest():
    t, a, v = _record()
    result = integrate_acceleration(t, a)
    # the bias: the mean of the rest, within 4 standard errors of the truth
    assert abs(result.bias - BIAS) < 4 * result.bias_se
    # never below the white noise's σ/√n (the faded decay's last swings add to it)
    assert result.bias_se > 0.9 * NOISE / math.sqrt(result.rest_samples)
    assert result.frequency_Hz == pytest.approx(F_HZ, rel=0.01)
    assert result.cutoff_Hz == pytest.approx(CUTOFF_RATIO * result.frequency_Hz)
    # after the first period the error is a small part of the swing: the random walk
    # of 0.02 m/s² at 200 Hz over seconds is of order 1e-3 m/s
    late = t > REST + 1.0 / F_HZ
    peak = np.abs(v).max()
    assert np.abs(result.velocity - v)[late].max() < 0.01 * peak
    # without noise and bias, the integral is exact to 1e-3 of the swing
    t, a, v = _record(noise=0.0, bias=0.0)
    exact = integrate_acceleration(t, a)
    # (the trapezoid rule's gain alone would be 0.8 % off at 80 samples a period)
    assert np.abs(exact.velocity - v)[late].max() < 2e-3 * peak


def test_a_record_read_from_a_file_says_how_its_velocity_was_made(tmp_path: Path) -> None:
    t, a, v = _record()
    path = _csv(tmp_path / "phone.csv", "Time (s),Acceleration (g)", [t, a / STANDARD_GRAVITY])
    with pytest.warns(ReadingWarning) as caught:
        run = read_run(path)
    note = " ".join(str(w.message) for w in caught)
    assert "integrated from the acceleration 'acceleration_m_per_s2'" in note
    assert re.search(r"bias 0\.(29|30|31)\d* ± 0\.000\d+ m/s² removed", note)
    assert "zero-phase high-pass" in note and "rest before the release" in note
    assert run.displacement is None and run.velocity is not None
    record = run.metadata["acceleration"]
    assert record["column"] == "acceleration_m_per_s2"
    assert abs(record["bias"] - BIAS) < 4 * record["bias_se"]  # g converted to m/s²
    assert record["filter"]["cutoff_Hz"] > 0 and record["filter"]["gain_divided_out"]
    late = t > REST + 1.0 / F_HZ
    assert np.abs(run.velocity - v)[late].max() < 0.01 * np.abs(v).max()


def test_an_acceleration_beside_a_displacement_is_not_read(tmp_path: Path) -> None:
    t, a, v = _record()
    x = np.cumsum(v) / RATE
    header = "Time (s),Position (m),Acceleration (m/s^2)"
    path = _csv(tmp_path / "both.csv", header, [t, x, a])
    with pytest.warns(ReadingWarning, match=r"\['Acceleration \(m/s\^2\)'\] not read"):
        run = read_run(path)
    np.testing.assert_array_equal(run.displacement, x)
    assert "acceleration" not in run.metadata


def _phyphox(tmp_path: Path, direction: np.ndarray, other: float = 0.0) -> Path:
    """Three axes: the decay along ``direction``, gravity on z, independent noise, and
    on y ``other`` times a second decay at 1.7 f (another mode of the rig)."""
    t, a, _ = _record(bias=0.0, noise=0.0)
    rng = np.random.default_rng(5)
    axes = [a * d + NOISE * rng.standard_normal(t.size) for d in direction]
    axes[2] = axes[2] + STANDARD_GRAVITY
    s = np.maximum(t - REST, 0.0)
    axes[1] = axes[1] + other * np.exp(-s / 3.0) * np.sin(2 * math.pi * 1.7 * F_HZ * s)
    header = (
        "Time (s),Acceleration x (m/s^2),Acceleration y (m/s^2),Acceleration z (m/s^2),"
        "Absolute acceleration (m/s^2)"
    )
    return _csv(tmp_path / "phyphox.csv", header, [t, *axes, np.hypot(*axes[:2])])


def test_phyphox_axes_are_projected_on_the_principal_axis_and_said(tmp_path: Path) -> None:
    direction = np.array([0.6, -0.48, 0.64])  # a unit vector
    path = _phyphox(tmp_path, direction)
    with pytest.warns(ReadingWarning) as caught:
        run = read_run(path)
    text = " ".join(str(w.message) for w in caught)
    assert "projected on the principal axis" in text
    assert "'Absolute acceleration (m/s^2)'] not read" in text  # a magnitude: never read
    # the exact columns= that reads one axis instead
    assert "columns=['time_s', 'acceleration_m_per_s2', 'ignore', 'ignore', 'ignore']" in text
    weights = run.metadata["acceleration"]["axes"]["weights"]
    found = np.array([weights[f"acceleration_{c}_m_per_s2"] for c in "xyz"])
    assert np.abs(found @ direction) == pytest.approx(1.0, abs=1e-3)
    assert found[np.argmax(np.abs(found))] > 0  # the sign: the largest component positive
    # gravity's share along the axis is a bias like any other, taken at rest
    bias = run.metadata["acceleration"]["bias"]
    assert bias == pytest.approx(found[2] * STANDARD_GRAVITY, abs=0.01)


def test_axes_that_do_not_move_along_one_line_are_refused_naming_the_columns(tmp_path: Path):
    path = _phyphox(tmp_path, np.array([1.0, 0.0, 0.0]), other=7.0)
    with pytest.raises(RunFormatError, match="do not move along one line") as caught:
        read_run(path)
    for names in (
        "['time_s', 'acceleration_m_per_s2', 'ignore', 'ignore', 'ignore']",
        "['time_s', 'ignore', 'acceleration_m_per_s2', 'ignore', 'ignore']",
        "--columns time_s ignore ignore acceleration_m_per_s2 ignore",
    ):
        assert names in caught.value.message
    # the spelling given reads the file
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = read_run(
            path, columns=["time_s", "acceleration_m_per_s2", "ignore", "ignore", "ignore"]
        )
    assert run.metadata["acceleration"]["column"] == "acceleration_m_per_s2"


def test_principal_axis_of_a_line() -> None:
    rng = np.random.default_rng(2)
    s = np.sin(np.linspace(0, 40, 2000))
    axes = {"x": -0.8 * s + 3.0, "y": 0.6 * s + 0.001 * rng.standard_normal(s.size)}
    axis = principal_axis(axes)
    assert axis.weights["x"] == pytest.approx(0.8, abs=1e-3)  # sign: largest positive
    assert axis.weights["y"] == pytest.approx(-0.6, abs=1e-3)
    assert axis.spread < 1e-4
    np.testing.assert_allclose(axis.values, 2.4 - s, atol=0.01)  # the bias projected too


def test_an_acceleration_with_no_free_decay_is_refused(tmp_path: Path) -> None:
    t = np.arange(0.0, 10.0, 1.0 / RATE)
    noise = BIAS + NOISE * np.random.default_rng(3).standard_normal(t.size)
    path = _csv(tmp_path / "still.csv", "time_s,acceleration_m_per_s2", [t, noise])
    with pytest.raises(RecordingError, match="no free decay in the acceleration"):
        read_run(path)


def test_a_magnitude_alone_is_refused(tmp_path: Path) -> None:
    t, a, _ = _record()
    path = _csv(tmp_path / "magnitude.csv", "Time (s),Absolute acceleration (m/s^2)", [t, a])
    with pytest.raises(RunFormatError, match="no displacement, velocity or acceleration column"):
        read_run(path)


def test_no_rest_after_the_motion_is_said() -> None:
    t, a, _ = _record()
    keep = t < REST + 3.0  # cut while the decay still swings
    result = integrate_acceleration(t[keep], a[keep])
    assert "at the release only" in result.drift_from
    assert "the high-pass takes the displacement's step there" in result.drift_from
    assert result.cutoff_Hz == pytest.approx(CUTOFF_RATIO_OPEN * result.frequency_Hz)


def _coulomb_velocity(t: np.ndarray, mu: float, static: float) -> np.ndarray:
    """Closed-form velocity [m/s] of dry friction alone (ζ = 0), released from X0 at
    t = REST: each half cycle a cosine about ±x_c (x_c = μ g / Ω²) from the turning
    point X_n, until |X_n| <= (μ_s/μ_k) x_c, where it sticks."""
    omega = 2 * math.pi * F_HZ
    xc = mu * STANDARD_GRAVITY / omega**2
    v = np.zeros_like(t)
    start, x = REST, X0
    while abs(x) > static * xc:
        centre = math.copysign(xc, x)  # friction opposes the motion towards -x
        inside = (t >= start) & (t < start + math.pi / omega)
        v[inside] = -(x - centre) * omega * np.sin(omega * (t[inside] - start))
        start, x = start + math.pi / omega, 2 * centre - x
    return v


def test_a_fit_of_an_accelerometer_record_covers_the_truth() -> None:
    mu, dt = 0.02, 1.0 / RATE
    t = np.arange(0.0, 10.0, dt)
    a = (_coulomb_velocity(t + dt / 2, mu, 1.3) - _coulomb_velocity(t - dt / 2, mu, 1.3)) / dt
    a = a + BIAS + NOISE * np.random.default_rng(4).standard_normal(t.size)
    mass = 0.25
    meta = {"load_N": mass * STANDARD_GRAVITY, "mass_kg": mass, "natural_frequency_Hz": F_HZ}
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = from_acceleration(t, a, meta)
    result = fit(run, seed=2)
    assert result.converged
    low, high = result.interval("mu_k")
    assert low <= mu <= high
    assert result.metadata["acceleration"]["column"] == "acceleration_m_per_s2"
    assert "velocity  integrated from the acceleration" in result.to_text()


def test_an_angular_acceleration_is_read_as_a_rotation(tmp_path: Path) -> None:
    t, a, v = _record()  # the same numbers read as radians
    degrees = np.degrees(a)
    path = _csv(tmp_path / "gyro.csv", "time_s,angular_acceleration_deg_per_s2", [t, degrees])
    with pytest.warns(ReadingWarning, match="'angular_acceleration_rad_per_s2'.*rad/s²"):
        run = read_run(path)
    assert run.length_unit == "rad"
    late = t > REST + 1.0 / F_HZ
    assert np.abs(run.velocity - v)[late].max() < 0.01 * np.abs(v).max()


def test_a_window_is_integrated_alone(tmp_path: Path) -> None:
    """A second disturbance after the decay: the window keeps the decay and its rests."""
    t, a, v = _record()
    kick = (t > 21.0) & (t < 21.5)
    a = np.where(kick, a + 5.0, a)
    path = _csv(tmp_path / "kicked.csv", "time_s,acceleration_m_per_s2", [t, a])
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = read_run(path, window=(0.0, 20.0))
    assert run.time[-1] <= 20.0 and run.metadata["window_s"][1] <= 20.0
    late = run.time > REST + 1.0 / F_HZ
    assert np.abs(run.velocity - v[: run.time.size])[late].max() < 0.01 * np.abs(v).max()


def test_a_matlab_file_of_an_acceleration_is_read_too(tmp_path: Path) -> None:
    scipy_io = pytest.importorskip("scipy.io")
    t, a, v = _record()
    path = tmp_path / "accel.mat"
    scipy_io.savemat(path, {"time_s": t, "acceleration_g": a / STANDARD_GRAVITY})
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = read_run(path, sidecar=False)
    late = t > REST + 1.0 / F_HZ
    assert np.abs(run.velocity - v)[late].max() < 0.01 * np.abs(v).max()


@functools.lru_cache(maxsize=4)
def _quadratic_drag(q: float, x0: float):
    """The dense solution (x [m], v [m/s]) of quadratic drag and weak viscous damping
    released from x0 [m] at rest (solve_ivp of ẍ = -Ω²x - 2ζΩẋ - q ẋ|ẋ|, q [1/m],
    ζ = 0.007), over 40 s."""
    from scipy.integrate import solve_ivp

    omega, zeta = 2 * math.pi * F_HZ, 0.007
    return solve_ivp(
        lambda _, y: [y[1], -(omega**2) * y[0] - 2 * zeta * omega * y[1] - q * y[1] * abs(y[1])],
        (0.0, 40.0),
        [x0, 0.0],
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        dense_output=True,
    ).sol


def _quadratic_drag_velocity(
    t: np.ndarray, which: int = 1, q: float = 1.43, x0: float = 0.044
) -> np.ndarray:
    """The velocity [m/s] (``which`` 0: the displacement [m]) of :func:`_quadratic_drag`
    released at t = REST (q = 1.43 /m from 4.4 cm: it loses a quarter of its energy in
    its first cycle)."""
    s = t - REST
    held = x0 if which == 0 else 0.0
    return np.where(s > 0.0, _quadratic_drag(q, x0)(np.maximum(s, 0.0))[which], held)


def test_a_fast_decay_keeps_its_first_swings_after_the_high_pass() -> None:
    # a record ending in motion (the high-pass at 0.3 f), noise-free: what the release
    # holds below f_c is kept, so that the swings of the first cycles after the first
    # period (where quadratic drag loses most) are those of the motion; with the edge's
    # terms unsmoothed, they were 0.17 % low and a fit moved the loss from c₂ to ζ
    dt = 1.0 / RATE
    t = np.arange(0.0, REST + 18.0, dt)
    v = _quadratic_drag_velocity(t)
    a = (_quadratic_drag_velocity(t + dt / 2) - _quadratic_drag_velocity(t - dt / 2)) / dt
    result = integrate_acceleration(t, a)
    assert result.cutoff_Hz == pytest.approx(CUTOFF_RATIO_OPEN * result.frequency_Hz)
    turns = np.flatnonzero((np.sign(v[1:]) != np.sign(v[:-1])) & (t[1:] > REST)) + 1
    late = turns[t[turns] > REST + 1.0 / F_HZ][:5]
    ratios = [
        np.abs(result.velocity[i0:i1]).max() / np.abs(v[i0:i1]).max()
        for i0, i1 in itertools.pairwise(late)
    ]
    assert np.max(np.abs(np.array(ratios) - 1.0)) < 6e-4, ratios


def test_the_derived_displacements_equilibrium_follows_the_decay_not_its_wander() -> None:
    # quadratic drag recorded by an accelerometer at 130 µg/√Hz for 36 s, integrated
    # into the velocity and then into the displacement, which wanders by some 0.1 mm:
    # the equilibrium fitted through its turning points, each weighted by a noise that
    # holds that wander, leaves the first swings centred (weighted by the
    # sample-to-sample noise alone, the last small swings set the equilibrium's drift:
    # the first swings were off centre by up to 11 % of their size in these records)
    from bayestribo.signal.decay import energy_decay

    dt = 1.0 / RATE
    t = np.arange(0.0, REST + 36.0, dt)
    motion = {"q": 1.875, "x0": 0.0388}
    a = (
        _quadratic_drag_velocity(t + dt / 2, **motion)
        - _quadratic_drag_velocity(t - dt / 2, **motion)
    ) / dt
    meta = {"natural_frequency_Hz": F_HZ, "load_N": 0.0, "mass_kg": 0.25}
    for seed in range(4):
        noisy = a - 0.17 + 0.026 * np.random.default_rng(seed).standard_normal(t.size)
        with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
            run = from_acceleration(t, noisy, meta)
        decay = energy_decay(run.time, None, run.velocity, rig=run.rig())
        x = _quadratic_drag_velocity(decay.t, 0, **motion)
        early = decay.t < decay.t[0] + 2.0
        offset = np.mean(decay.y[early] * decay.scaling.length_scale - x[early])
        assert abs(offset) < 0.02 * np.abs(x[early]).max(), (seed, offset)
