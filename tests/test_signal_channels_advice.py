"""Unit advice of the channel and plausibility checks leads to the truth when followed.

A damped sinusoid at f with its analytic velocity is written in wrong units (a column
in metres labelled mm, a velocity in mm/s labelled m/s, both channels in cm labelled m,
...). Every ``scale={...}`` a refusal gives is applied with ``read_run(path,
scale=...)``: a refusal that names one reading must give back the true run; one that
cannot decide must name every reading, the true one among them, and what decides.
"""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.errors import RecordingError
from bayestribo.signal.channels import check_plausible_motion

F_HZ = 32.6
SWING_M = 1.5e-3
#: The paper rig's mass and load: k = 1468 N/m, μN/k = 6 µm for μ = 0.03.
RIG = {"load_N": 0.31, "mass_kg": 0.035, "natural_frequency_Hz": F_HZ}
SCALE = re.compile(r"scale=(\{[^}]*\})")


def _truth(frequency_Hz: float = F_HZ, swing_m: float = SWING_M):
    """Time [s], displacement [m] and velocity [m/s] of a damped sinusoid (ζ = 0.02)."""
    omega = 2.0 * np.pi * frequency_Hz
    zeta = 0.02
    damped = omega * np.sqrt(1.0 - zeta**2)
    t = np.arange(0.0, 30.0 / frequency_Hz, 1.0 / (300.0 * frequency_Hz))
    envelope = swing_m * np.exp(-zeta * omega * t)
    x = envelope * np.cos(damped * t)
    v = envelope * (-zeta * omega * np.cos(damped * t) - damped * np.sin(damped * t))
    return t, x, v


def _write(
    tmp_path: Path,
    header: str,
    x_factor: float,
    v_factor: float,
    sidecar: dict | None,
    frequency_Hz: float = F_HZ,
    swing_m: float = SWING_M,
) -> Path:
    """The truth as a CSV whose numbers are x * x_factor and v * v_factor under
    ``header``."""
    t, x, v = _truth(frequency_Hz, swing_m)
    path = tmp_path / "run.csv"
    np.savetxt(
        path,
        np.column_stack([t, x * x_factor, v * v_factor]),
        delimiter=",",
        header=header,
        comments="",
    )
    if sidecar is not None:
        (tmp_path / "run.json").write_text(json.dumps(sidecar))
    return path


def _refusal(path: Path) -> str:
    with pytest.raises(RecordingError) as info:
        read_run(path)
    return str(info.value)


def _scales(message: str) -> list[dict[str, float]]:
    """Every ``scale={...}`` the message advises, as given."""
    return [ast.literal_eval(found) for found in SCALE.findall(message)]


def _is_truth(path: Path, scale: dict[str, float], **motion: float) -> bool:
    """Whether the run read with ``scale`` is the truth (and passes the checks)."""
    t, x, v = _truth(**motion)
    try:
        run = read_run(path, scale=scale)
    except RecordingError:
        return False
    return bool(
        np.allclose(run.time, t, rtol=1e-9, atol=1e-12)
        and np.allclose(run.displacement, x, rtol=1e-9, atol=1e-12)
        and np.allclose(run.velocity, v, rtol=1e-9, atol=1e-12)
    )


def _follow_the_one(message: str, path: Path, **motion: float) -> None:
    scales = _scales(message)
    assert len(scales) == 1, message
    assert "does not tell which" not in message
    assert _is_truth(path, scales[0], **motion), (scales[0], message)


# -- channels a power of ten apart -------------------------------------------------------

HEADER_MM = "time_s,displacement_mm,velocity_m_per_s"
HEADER_M = "time_s,displacement_m,velocity_m_per_s"


def test_metres_labelled_mm_with_mass_and_load_advise_the_displacement(tmp_path):
    """The issue's case: the velocity is right, the displacement read 1000 times too
    small. Before, the advice scaled the velocity and the fit gave μ 1000 times too
    small; the stated load rules that reading out, and the advice given is the truth."""
    path = _write(tmp_path, HEADER_MM, 1.0, 1.0, RIG)
    message = _refusal(path)
    assert "scale={'velocity_m_per_s': 0.001}" not in message
    assert "displacement read 1000 times too small (metres in a column labelled mm)" in message
    assert "not velocity in mm/s: a swing of 1.45e-06 m" in message
    assert "friction coefficient of at most" in message
    _follow_the_one(message, path)


def test_metres_labelled_mm_with_a_resolution_advise_the_displacement(tmp_path):
    path = _write(
        tmp_path,
        HEADER_MM,
        1.0,
        1.0,
        {"natural_frequency_Hz": F_HZ, "displacement_resolution_m": 1e-5},
    )
    message = _refusal(path)
    assert "below the sensor's stated displacement_resolution_m = 1e-05 m" in message
    _follow_the_one(message, path)


def test_metres_labelled_mm_without_what_decides_name_both_and_what_decides(tmp_path):
    path = _write(tmp_path, HEADER_MM, 1.0, 1.0, {"natural_frequency_Hz": F_HZ})
    message = _refusal(path)
    scales = _scales(message)
    assert scales == [{"displacement_m": 1000.0}, {"velocity_m_per_s": 0.001}], message
    assert "the record does not tell which" in message
    assert "displacement_resolution_m" in message and "mass_kg and load_N" in message
    assert "check the sensor's output unit" in message
    # one of the two is the truth, the other is not: only the sidecar or the sensor decides
    assert [_is_truth(path, s) for s in scales] == [True, False]


def test_a_velocity_in_mm_per_s_is_advised_alone_and_says_why_not_the_displacement(tmp_path):
    path = _write(tmp_path, HEADER_M, 1.0, 1e3, RIG)
    message = _refusal(path)
    assert "likely velocity in mm/s: scale={'velocity_m_per_s': 0.001}" in message
    assert "not displacement read 1000 times too small" in message
    assert "is no free-decay rig's motion" in message
    _follow_the_one(message, path)


def test_a_displacement_in_mm_labelled_m_is_advised_alone(tmp_path):
    path = _write(tmp_path, HEADER_M, 1e3, 1.0, RIG)
    message = _refusal(path)
    assert "likely displacement in mm: scale={'displacement_m': 0.001}" in message
    _follow_the_one(message, path)


def test_a_displacement_in_cm_labelled_m_is_advised_as_cm(tmp_path):
    path = _write(tmp_path, HEADER_M, 1e2, 1.0, RIG)
    message = _refusal(path)
    assert "likely displacement in cm: scale={'displacement_m': 0.01}" in message
    _follow_the_one(message, path)


def test_a_slow_rig_a_velocity_in_mm_per_s_is_ambiguous_until_the_range_is_stated(tmp_path):
    """At 1 Hz with 0.1 mm, a displacement 1000 times larger (0.1 m, 0.6 m/s) is a
    motion too, and so is a time in ms (1 kHz): without the sidecar all three are named;
    the stated natural frequency and sensor range leave one, the truth."""
    slow = {"frequency_Hz": 1.0, "swing_m": 1e-4}
    path = _write(tmp_path, HEADER_M, 1.0, 1e3, None, **slow)
    message = _refusal(path)
    assert "the record does not tell which" in message
    scales = _scales(message)
    assert {"velocity_m_per_s": 0.001} in scales and {"displacement_m": 1000.0} in scales
    assert sum(_is_truth(path, s, **slow) for s in scales) == 1
    (tmp_path / "run.json").write_text(
        json.dumps({"natural_frequency_Hz": 1.0, "displacement_range_m": 0.01})
    )
    message = _refusal(path)
    assert "beyond the sensor's stated displacement_range_m = 0.01 m" in message
    assert "not the stated natural_frequency_Hz" in message
    _follow_the_one(message, path, **slow)


def test_a_velocity_resolution_decides_too(tmp_path):
    # the velocity read 1000 times too small (m/s in a column labelled mm/s): its
    # other reading, a displacement 1000 times too large, has a peak speed of 0.3 mm/s,
    # below the stated velocity resolution
    path = _write(
        tmp_path,
        "time_s,displacement_m,velocity_mm_per_s",
        1.0,
        1.0,
        {"natural_frequency_Hz": F_HZ, "velocity_resolution_m_per_s": 1e-3},
    )
    message = _refusal(path)
    assert "velocity read 1000 times too small (m/s in a column labelled mm/s)" in message
    assert "below the sensor's stated velocity_resolution_m_per_s" in message
    _follow_the_one(message, path)


# -- both channels in one wrong unit: the plausibility check -----------------------------


@pytest.mark.parametrize(
    ("factor", "words"),
    [(1e2, "displacement in cm and velocity in cm/s"), (1e6, "displacement in µm")],
)
def test_a_swing_too_large_names_the_unit_that_makes_it_a_rigs(tmp_path, factor, words):
    path = _write(tmp_path, HEADER_M, factor, factor, None)
    message = _refusal(path)
    assert message.count("plausibility: a swing of") == 1
    assert f"likely {words}" in message
    scales = _scales(message)
    assert sum(_is_truth(path, s) for s in scales) == 1
    assert _is_truth(path, scales[0])  # the likeliest, a swing nearest 1 mm, first


def test_cm_read_as_m_names_cm_and_mm_when_both_are_plausible(tmp_path):
    """A swing in cm read as m was called "likely displacement in mm" (off by 10):
    now cm is named, and mm beside it since nothing tells them apart, with what
    decides; a stated resolution and range leave cm alone."""
    path = _write(tmp_path, HEADER_M, 1e2, 1e2, None)
    message = _refusal(path)
    assert "displacement in cm and velocity in cm/s: scale=" in message
    assert "displacement in mm and velocity in mm/s: scale=" in message
    assert "the record does not tell which: state displacement_resolution_m" in message
    # a stated range the values as read exceed is refused as clipping before this
    # check (bayestribo.io.validation), so the check is asked directly
    sensor = {"displacement_resolution_m": 2e-4, "displacement_range_m": 5e-3}
    (tmp_path / "run.json").write_text(json.dumps({**RIG, **sensor}))
    with pytest.raises(RecordingError) as info:
        check_plausible_motion(read_run(path, validate=False))
    message = str(info.value)
    assert "not displacement in mm and velocity in mm/s: a swing of 0.000145 m" in message
    _follow_the_one(message, path)


@pytest.mark.parametrize(
    ("factor", "words"),
    [
        (1e-3, "displacement read 1000 times too small (metres in a column labelled mm)"),
        (1e-2, "displacement read 100 times too small (metres in a column labelled cm)"),
        (1e-6, "displacement read 1000000 times too small (metres in a column labelled µm)"),
    ],
)
def test_a_swing_below_the_stated_resolution_names_the_unit_that_makes_it_a_rigs(
    tmp_path, factor, words
):
    """The other way: both channels in metres read as mm, cm or µm give a swing below
    the sensor's stated resolution; the refusal names the scale back to metres first,
    and any other reading the record allows beside it, with what decides."""
    path = _write(tmp_path, HEADER_M, factor, factor, {**RIG, "displacement_resolution_m": 2e-4})
    message = _refusal(path)
    assert "plausibility: a swing of" in message
    assert "below the sensor's stated displacement_resolution_m = 0.0002 m" in message
    assert f"likely {words}" in message
    scales = _scales(message)
    assert _is_truth(path, scales[0])
    assert sum(_is_truth(path, s) for s in scales) == 1
    assert len(scales) == 1 or "the record does not tell which" in message
    # with the sensor's range too, the one reading left is the truth
    (tmp_path / "run.json").write_text(
        json.dumps({**RIG, "displacement_resolution_m": 2e-4, "displacement_range_m": 5e-3})
    )
    _follow_the_one(_refusal(path), path)


def test_the_truth_passes_and_arbitrary_units_are_not_judged(tmp_path):
    read_run(_write(tmp_path, HEADER_M, 1.0, 1.0, {**RIG, "displacement_resolution_m": 1e-6}))
    # a swing of 1.5 m in arbitrary units is not refused
    read_run(_write(tmp_path, HEADER_M, 1e3, 1e3, {"length_unit": "arbitrary"}))


def test_channels_of_one_motion_rounded_to_a_few_steps_are_one_motion() -> None:
    """Both channels rounded to a fifth of their swing (a coarse digitiser): over a
    fortieth of a period the displacement moves by one step or none, and its changes
    correlated with the velocity's integral at 0.46; over windows of four steps they
    are one motion. Unrelated channels rounded alike are still refused."""
    from bayestribo.errors import RecordingError
    from bayestribo.io.run import Run
    from bayestribo.signal.channels import check_channels

    t = np.arange(0.0, 20.0, 0.005)
    w = 2 * np.pi * 1.3
    x = np.exp(-0.05 * t) * np.cos(w * t)
    v = np.gradient(x, t)
    qx, qv = np.ptp(x) / 5, np.ptp(v) / 5
    xs, vs = np.round(x / qx) * qx, np.round(v / qv) * qv
    meta = {"length_unit": "arbitrary"}
    check_channels(Run(t, xs, vs, meta))
    other = np.round(np.exp(-0.05 * t) * np.cos(1.7 * w * t + 1.0) * w / qv) * qv
    with pytest.raises(RecordingError, match="do not describe one motion"):
        check_channels(Run(t, xs, other, meta))


def test_channels_of_two_motions_name_the_one_channel_reading_that_reads_them(tmp_path):
    """A motion-sensor export whose velocity column does not follow its position (here
    one of another motion): refused, naming the reading of either channel alone, and
    the position alone, read as that names it, is read."""
    t = np.arange(0.0, 20.0, 0.01)
    w = 2 * np.pi * 1.3
    x = 0.4 + 0.05 * np.exp(-0.05 * t) * np.cos(w * t)
    other = 0.05 * w * np.exp(-0.05 * t) * np.cos(1.7 * w * t + 1.0)
    path = tmp_path / "export.csv"
    path.write_text(
        "time_s,displacement_m,velocity_m_per_s\n"
        + "".join(f"{a:.2f},{b:.5f},{c:.5f}\n" for a, b, c in zip(t, x, other, strict=True))
    )
    with pytest.raises(RecordingError, match=r"read one alone: 'ignore' in the other's place"):
        read_run(path)
    run = read_run(path, columns=["time_s", "displacement_m", "ignore"])
    assert run.velocity is None and run.n_samples == t.size
