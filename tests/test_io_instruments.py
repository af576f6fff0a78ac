"""Oscilloscope and DAQ text exports: each vendor's layout is recognised, time is
converted from the export's unit, channels in volts need a sensitivity, and nothing
is read under a wrong unit without an error."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bayestribo.cli import main
from bayestribo.errors import RunFormatError
from bayestribo.io import read_run
from bayestribo.io.instruments import detect_export
from bayestribo.synthetic import simulate

#: Sensor sensitivities of the exports below: 0.2 mm/V and 5 (mm/s)/V.
X_PER_V = 2e-4
V_PER_V = 5e-3


@pytest.fixture(scope="module")
def run():
    return simulate(seed=11)


def _volts(run):
    return run.displacement / X_PER_V, run.velocity / V_PER_V


def _tektronix(run, sep=",", dec="."):
    xv, vv = _volts(run)
    head = [
        "Model,MSO44",
        "Firmware Version,1.26.7",
        "",
        "Waveform Type,ANALOG",
        "Horizontal Units,s",
        f"Sample Interval,{run.time[1] - run.time[0]:.6e}",
        f"Record Length,{run.time.size}",
        "Vertical Units,V,V",
        "Label,,",
        "TIME,CH1,CH2",
    ]
    rows = [f"{t:.12e},{a:.12e},{b:.12e}" for t, a, b in zip(run.time, xv, vv, strict=True)]
    text = "\n".join([*head, *rows])
    if sep != ",":
        text = text.replace(",", sep)
    if dec != ".":
        body = "\n".join(rows).replace(",", sep).replace(".", dec)
        text = "\n".join(h.replace(",", sep) for h in head) + "\n" + body
    return text


def _keysight(run):
    xv, vv = _volts(run)
    rows = [f"{t:.12e},{a:.12e},{b:.12e}" for t, a, b in zip(run.time, xv, vv, strict=True)]
    return "\n".join(["x-axis,1,2", "second,Volt,Volt", *rows])


def _rigol(run):
    xv, vv = _volts(run)
    dt = run.time[1] - run.time[0]
    rows = [f"{i},{a:.12e},{b:.12e}," for i, (a, b) in enumerate(zip(xv, vv, strict=True))]
    return "\n".join(
        ["X,CH1,CH2,Start,Increment,", f"Sequence,Volt,Volt,{run.time[0]:.17g},{dt:.17g}", *rows]
    )


def _picoscope(run):
    xv, vv = _volts(run)
    rows = [
        f"{1e3 * t:.12e},{1e3 * a:.12e},{b:.12e}" for t, a, b in zip(run.time, xv, vv, strict=True)
    ]
    return "\n".join(["Time,Channel A,Channel B", "(ms),(mV),(V)", "", *rows])


def _lvm(run, x_columns="One"):
    xv, vv = _volts(run)
    dt = run.time[1] - run.time[0]
    header = [
        "LabVIEW Measurement\t",
        "Writer_Version\t2",
        "Reader_Version\t2",
        "Separator\tTab",
        "Decimal_Separator\t.",
        "Multi_Headings\tNo",
        f"X_Columns\t{x_columns}",
        "Time_Pref\tRelative",
        "***End_of_Header***\t",
        "",
        "Channels\t2\t",
        f"Samples\t{run.time.size}\t{run.time.size}",
        "Y_Unit_Label\tVolts\tVolts",
        "X_Dimension\tTime\tTime",
        f"X0\t{run.time[0]:.17g}\t{run.time[0]:.17g}",
        f"Delta_X\t{dt:.17g}\t{dt:.17g}",
        "***End_of_Header***\t",
    ]
    if x_columns == "No":
        labels = "Untitled\tUntitled 1\tComment"
        rows = [f"{a:.12e}\t{b:.12e}" for a, b in zip(xv, vv, strict=True)]
    elif x_columns == "Multi":
        labels = "X_Value\tUntitled\tX_Value\tUntitled 1\tComment"
        rows = [
            f"{t:.12e}\t{a:.12e}\t{t:.12e}\t{b:.12e}"
            for t, a, b in zip(run.time, xv, vv, strict=True)
        ]
    else:
        labels = "X_Value\tUntitled\tUntitled 1\tComment"
        rows = [f"{t:.12e}\t{a:.12e}\t{b:.12e}" for t, a, b in zip(run.time, xv, vv, strict=True)]
    return "\n".join([*header, labels, *rows])


EXPORTS = {
    "tektronix": (_tektronix, "Tektronix CSV", ".csv"),
    "keysight": (_keysight, "Keysight/Agilent CSV", ".csv"),
    "rigol": (_rigol, "Rigol CSV", ".csv"),
    "picoscope": (_picoscope, "PicoScope CSV", ".csv"),
    "lvm": (_lvm, "LabVIEW LVM", ".lvm"),
}

SCALE = {"displacement_m": X_PER_V, "velocity_m_per_s": V_PER_V}
ROLES = ["time_s", "displacement_m", "velocity_m_per_s"]


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text + "\n", encoding="utf-8")
    return path


def _same_run(got, run):
    # The exports write 13 significant digits; the tolerance is that rounding.
    np.testing.assert_allclose(got.time, run.time, rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-11, atol=1e-18)
    np.testing.assert_allclose(got.velocity, run.velocity, rtol=1e-11, atol=1e-18)


@pytest.mark.parametrize("kind", sorted(EXPORTS))
def test_each_export_is_recognised_and_read_in_si_units(tmp_path, run, kind):
    make, vendor, suffix = EXPORTS[kind]
    path = _write(tmp_path, f"{kind}{suffix}", make(run))
    lines = path.read_text(encoding="utf-8").splitlines()[:200]
    assert detect_export(lines).vendor == vendor
    got = read_run(path, columns=ROLES, scale=SCALE, metadata=dict(run.metadata))
    _same_run(got, run)


@pytest.mark.parametrize("x_columns", ["No", "Multi"])
def test_lvm_time_from_the_header_or_from_several_x_columns(tmp_path, run, x_columns):
    path = _write(tmp_path, "run.lvm", _lvm(run, x_columns))
    roles = ROLES[1:] if x_columns == "No" else ROLES
    got = read_run(path, columns=roles, scale=SCALE, metadata=dict(run.metadata))
    _same_run(got, run)


def test_european_export_with_semicolons_and_decimal_commas(tmp_path, run):
    path = _write(tmp_path, "eu.csv", _tektronix(run, sep=";", dec=","))
    export = detect_export(path.read_text(encoding="utf-8").splitlines()[:200])
    assert (export.delimiter, export.decimal) == (";", ",")
    _same_run(read_run(path, columns=ROLES, scale=SCALE, metadata=dict(run.metadata)), run)


@pytest.mark.parametrize("kind", sorted(EXPORTS))
def test_channels_in_volts_are_never_read_as_metres(tmp_path, run, kind):
    make, vendor, suffix = EXPORTS[kind]
    path = _write(tmp_path, f"{kind}{suffix}", make(run))
    with pytest.raises(RunFormatError, match=r"columns=\[\.\.\.\].*scale=\{\.\.\.\}") as info:
        read_run(path)
    assert vendor in str(info.value)
    with pytest.raises(RunFormatError, match=r"sensitivity in \(m/s\)/V"):
        read_run(path, columns=ROLES, scale={"displacement_m": X_PER_V})


def test_a_unit_in_a_role_name_that_contradicts_the_export_is_refused(tmp_path, run):
    path = _write(tmp_path, "k.csv", _keysight(run))
    with pytest.raises(RunFormatError, match="not in the unit its name states"):
        read_run(path, columns=["time_s", "displacement_um", "velocity_m_per_s"], scale=SCALE)
    with pytest.raises(RunFormatError, match=r"first column .* is the time axis"):
        read_run(path, columns=["displacement_m", "time_s", "velocity_m_per_s"], scale=SCALE)
    with pytest.raises(RunFormatError, match="expected 3, one per column"):
        read_run(path, columns=["time_s", "displacement_m"], scale=SCALE)


def test_channels_in_physical_units_need_no_roles(tmp_path, run):
    rows = [
        f"{1e3 * t:.12e},{1e3 * x:.12e},{1e3 * v:.12e}"
        for t, x, v in zip(run.time, run.displacement, run.velocity, strict=True)
    ]
    path = _write(
        tmp_path, "pico.csv", "\n".join(["Time,Channel A,Channel B", "(ms),(mm),(mm/s)", *rows])
    )
    _same_run(read_run(path, metadata=dict(run.metadata)), run)
    with pytest.raises(RunFormatError, match="convert it twice"):
        read_run(path, columns=ROLES, scale=SCALE)
    # A displacement channel named as the velocity is a swapped order, refused.
    with pytest.raises(RunFormatError, match="check the order of the columns"):
        read_run(path, columns=["time_s", "velocity_m_per_s", "displacement_m"])


def test_over_range_marks_are_reported_as_clipping(tmp_path, run):
    text = _picoscope(run).splitlines()
    text[10] = text[10].split(",")[0] + ",∞," + text[10].split(",")[2]
    path = _write(tmp_path, "clip.csv", "\n".join(text))
    with pytest.raises(RunFormatError, match=r"line 11, column 'Channel A'.*over-range"):
        read_run(path, columns=ROLES, scale=SCALE)


def test_a_plain_header_starting_with_model_is_not_an_export():
    assert detect_export(["Model,Amplitude", "0,1", "1,2"]) is None
    assert detect_export(["time_s,displacement_m", "0,1"]) is None
    assert detect_export(["X,V", "0.1,0.2"]) is None  # not a Rigol export
    assert detect_export(["x-axis,y", "1,2"]) is None  # not a Keysight export


def test_the_command_line_reads_an_export_and_names_the_options(tmp_path, run, capsys):
    path = _write(tmp_path, "scope.csv", _tektronix(run))
    meta = ["--frequency", "32.6", "--load", "0.31", "--mass", "0.035"]
    assert main(["decay", str(path), "--json", *meta]) == 2
    err = capsys.readouterr().err
    assert "Tektronix CSV" in err and "--columns" in err and "--scale NAME=FACTOR" in err
    argv = ["decay", str(path), "--json", "--columns", "t", "x", "v"]
    argv += ["--scale", f"x={X_PER_V}", "--scale", f"v={V_PER_V}", *meta]
    assert main(argv) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["natural_frequency_Hz"] == pytest.approx(32.6, rel=2e-3)


@pytest.mark.parametrize("x_columns", ["One", "No"])
def test_an_lvm_channel_whose_label_states_its_unit_is_read_in_that_unit(tmp_path, run, x_columns):
    # a LabVIEW file without Y_Unit_Label whose labels end with the unit, as exports
    # that set the channel names do: read in that unit with no options, the roles
    # named with the same unit agree with it, and volts in a label still need a scale
    text = _lvm(run, x_columns).replace("Y_Unit_Label\tVolts\tVolts\n", "")
    text = text.replace("\tUntitled\tUntitled 1\t", "\tDisplacement (mm)\tVelocity [mm/s]\t")
    text = text.replace("Untitled\tUntitled 1\t", "Displacement (mm)\tVelocity [mm/s]\t")
    rows = text.splitlines()
    first = next(i for i, r in enumerate(rows) if "Displacement (mm)" in r) + 1
    xv, vv = _volts(run)
    mm = (1e3 * X_PER_V, 1e3 * V_PER_V)
    for k, row in enumerate(rows[first:]):
        fields = row.split("\t")
        fields[-2] = f"{xv[k] * mm[0]:.12e}"
        fields[-1] = f"{vv[k] * mm[1]:.12e}"
        rows[first + k] = "\t".join(fields)
    path = _write(tmp_path, "named.lvm", "\n".join(rows))
    assert "Y_Unit_Label" not in path.read_text(encoding="utf-8")
    _same_run(read_run(path, metadata=dict(run.metadata)), run)
    roles = ["displacement_mm", "velocity_mm_per_s"]
    roles = roles if x_columns == "No" else ["time_s", *roles]
    _same_run(read_run(path, columns=roles, metadata=dict(run.metadata)), run)
    volts = _write(tmp_path, "volts.lvm", "\n".join(rows).replace("(mm)", "(V)"))
    with pytest.raises(RunFormatError, match="sensitivity"):
        read_run(volts, metadata=dict(run.metadata))
