"""One table of length and time units, read alike by every reader (text, UFF, TDMS)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.io.columns import parse_column
from bayestribo.io.units import LENGTHS, TIMES, length_unit

RATE = 2000.0
N = 600
T = np.arange(N) / RATE
X = 1.0e-3 * np.exp(-3.0 * T) * np.cos(2 * np.pi * 25.0 * T)
V = np.gradient(X, T)


@pytest.mark.parametrize(
    ("label", "factor", "per_second"),
    [
        ("in", 0.0254, False),
        ("inch", 0.0254, False),
        ("mil", 2.54e-5, False),
        ("micron", 1e-6, False),
        ("\u03bcm", 1e-6, False),  # the Greek letter mu
        ("\u00b5m", 1e-6, False),  # the micro sign
        ("MM", 1e-3, False),
        ("in/s", 0.0254, True),
        ("ips", 0.0254, True),
        ("mil/s", 2.54e-5, True),
        ("mm/sec", 1e-3, True),
        ("mm_per_sec", 1e-3, True),
        ("um / s", 1e-6, True),
        ("m/s", 1.0, True),
    ],
)
def test_a_length_or_velocity_unit_gives_its_si_factor(
    label: str, factor: float, per_second: bool
) -> None:
    parsed = length_unit(label)
    assert parsed is not None
    assert math.isclose(parsed[0], factor, rel_tol=1e-15) and parsed[1] is per_second


@pytest.mark.parametrize("label", ["V", "mV", "g", "px", "ft", "m/s^2", "s", ""])
def test_a_label_that_is_no_length_is_none(label: str) -> None:
    assert length_unit(label) is None


def test_the_inch_is_the_international_inch_and_a_mil_its_thousandth() -> None:
    assert LENGTHS["in"] == 0.0254 and math.isclose(LENGTHS["mil"] * 1000, LENGTHS["in"])
    assert TIMES["msec"] == TIMES["ms"] == 1e-3 and TIMES["min"] == 60.0


@pytest.mark.parametrize(
    ("label", "canonical", "factor"),
    [
        ("Time [sec]", "time_s", 1.0),
        ("time (seconds)", "time_s", 1.0),
        ("Time (msec)", "time_s", 1e-3),
        ("disp_mm", "displacement_m", 1e-3),
        ("pos [mm]", "displacement_m", 1e-3),
        ("Deflection (um)", "displacement_m", 1e-6),
        ("Displacement (in)", "displacement_m", 0.0254),
        ("vel (mm/s)", "velocity_m_per_s", 1e-3),
        ("Velocity (mm/sec)", "velocity_m_per_s", 1e-3),
        ("Velocity (in/s)", "velocity_m_per_s", 0.0254),
        ("vel_ips", "velocity_m_per_s", 0.0254),
        ("Angular velocity (deg/sec)", "angular_velocity_rad_per_s", math.pi / 180),
    ],
)
def test_a_header_as_acquisition_software_writes_it(
    label: str, canonical: str, factor: float
) -> None:
    parsed = parse_column(label)
    assert parsed is not None and parsed[0] == canonical
    assert math.isclose(parsed[1], factor, rel_tol=1e-15)


def test_a_text_file_in_inches_and_seconds_reads_in_metres(tmp_path: Path) -> None:
    path = tmp_path / "shaker.csv"
    rows = "\n".join(
        f"{t:.6f},{x / 0.0254:.12e},{v / 0.0254:.12e}" for t, x, v in zip(T, X, V, strict=True)
    )
    path.write_text("Time [sec],Displacement (in),Velocity (in/s)\n" + rows + "\n")
    run = read_run(path)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-11, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-11, atol=0)


def test_a_tdms_channel_in_inches_per_second_reads_in_metres_per_second(tmp_path: Path) -> None:
    from nptdms import ChannelObject, TdmsWriter

    path = tmp_path / "vib.tdms"
    props = {"wf_increment": 1.0 / RATE, "wf_start_offset": 0.0}
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(
            [
                ChannelObject("G", "Disp", X / 2.54e-5, properties=props | {"unit_string": "mil"}),
                ChannelObject("G", "Vel", V / 0.0254, properties=props | {"unit_string": "in/s"}),
            ]
        )
    run = read_run(path, channels={"displacement_m": "Disp", "velocity_m_per_s": "Vel"})
    np.testing.assert_allclose(run.displacement, X, rtol=1e-14, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-14, atol=0)


def test_a_uff_record_in_inches_per_second_with_a_millisecond_axis(tmp_path: Path) -> None:
    import pyuff

    record = pyuff.prepare_58(
        binary=1,
        id1="Vib in/s",
        func_type=1,
        rsp_node=1,
        rsp_dir=1,
        ref_node=1,
        ref_dir=1,
        abscissa_spacing=1,
        data=V / 0.0254,
        x=1e3 * T,
        abscissa_spec_data_type=17,
        abscissa_axis_units_lab="msec",
        ordinate_spec_data_type=0,
        ordinate_axis_units_lab="in/s",
        orddenom_spec_data_type=0,
        z_axis_spec_data_type=0,
    )
    path = tmp_path / "vib.uff"
    pyuff.UFF(str(path)).write_sets([record], mode="add")
    run = read_run(path)
    assert run.displacement is None
    np.testing.assert_allclose(run.velocity, V, rtol=1e-14, atol=0)
    np.testing.assert_allclose(run.time, T, rtol=0, atol=1e-9)
