"""TDMS files written by npTDMS itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from nptdms import ChannelObject, TdmsWriter

from bayestribo import read_run
from bayestribo.errors import ReadingWarning, RunFormatError

RATE = 5000.0
N = 800
X = 1.2e-3 * np.exp(-4.8 * np.arange(N) / RATE) * np.cos(2 * np.pi * 32.6 * np.arange(N) / RATE)
V = np.gradient(X, 1.0 / RATE)


def _write(path: Path, *channels: ChannelObject) -> Path:
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(list(channels))
    return path


def _wave(group: str, name: str, data: np.ndarray, **props: object) -> ChannelObject:
    base = {"wf_increment": 1.0 / RATE, "wf_start_offset": 2.5}
    base.update(props)
    return ChannelObject(
        group, name, data, properties={k: v for k, v in base.items() if v is not None}
    )


def test_channels_by_name_with_units_and_waveform_time(tmp_path: Path) -> None:
    path = _write(
        tmp_path / "vib.tdms",
        _wave("Vibrometer", "Disp", 1e3 * X, unit_string="mm"),
        _wave("Vibrometer", "Vel", V, unit_string="m/s"),
        _wave("Vibrometer", "Trigger", np.zeros(N)),
    )
    run = read_run(path, channels={"displacement_m": "Disp", "velocity_m_per_s": "Vel"})
    np.testing.assert_allclose(run.time, 2.5 + np.arange(N) / RATE, rtol=0, atol=1e-15)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15)
    np.testing.assert_array_equal(run.velocity, V)


def test_time_channel_and_group_choice(tmp_path: Path) -> None:
    t = np.arange(N) / RATE
    path = _write(
        tmp_path / "two.tdms",
        ChannelObject("Setup", "Load", np.array([0.31])),
        ChannelObject("Data", "t", t),
        ChannelObject("Data", "x", X),
    )
    channels = {"time_s": "t", "displacement_m": "x"}
    with pytest.raises(RunFormatError, match=r"2 groups \['Data', 'Setup'\].*group="):
        read_run(path, channels=channels)
    run = read_run(path, group="Data", channels=channels)
    np.testing.assert_array_equal(run.time, t)
    np.testing.assert_array_equal(run.displacement, X)


@pytest.mark.parametrize(
    ("channels", "group", "match"),
    [
        ({"displacement_m": "Nope"}, None, r"channel 'Nope'.*\['Disp', 'Vel'\]"),
        ({"displacement_m": "Disp"}, "Other", r"group 'Other' is not in the file"),
        (None, None, r"name the channels.*\['Disp', 'Vel'\]"),
        ({"position": "Disp"}, None, "'position' is not a canonical name"),
        ({"time_s": "Disp"}, None, "a 'displacement_m' or 'velocity_m_per_s' channel"),
    ],
)
def test_bad_choices_list_what_is_in_the_file(
    tmp_path: Path, channels: dict | None, group: str | None, match: str
) -> None:
    path = _write(tmp_path / "vib.tdms", _wave("Vib", "Disp", X), _wave("Vib", "Vel", V))
    with pytest.raises(RunFormatError, match=match):
        read_run(path, channels=channels, group=group)


def test_missing_time_information_and_mismatched_lengths(tmp_path: Path) -> None:
    path = _write(tmp_path / "notime.tdms", ChannelObject("G", "x", X))
    with pytest.raises(RunFormatError, match=r"no time information.*time_s"):
        read_run(path, channels={"displacement_m": "x"})
    path = _write(tmp_path / "len.tdms", _wave("G", "x", X), _wave("G", "v", V[:-1]))
    with pytest.raises(RunFormatError, match="different lengths"):
        read_run(path, channels={"displacement_m": "x", "velocity_m_per_s": "v"})


def test_unit_of_the_wrong_kind_needs_a_scale(tmp_path: Path) -> None:
    path = _write(tmp_path / "u.tdms", _wave("G", "x", X, unit_string="V"))
    with pytest.raises(RunFormatError, match=r"G/x: unit_string 'V'.*scale="):
        read_run(path, channels={"displacement_m": "x"})
    run = read_run(path, channels={"displacement_m": "x"}, scale={"displacement_m": 1.0})
    np.testing.assert_array_equal(run.displacement, X)


def test_not_a_tdms_file(tmp_path: Path) -> None:
    (tmp_path / "junk.tdms").write_bytes(b"TDSm garbage that is not a lead in")
    with pytest.raises(RunFormatError, match=r"junk\.tdms.*(not a TDMS file|as TDMS)"):
        read_run(tmp_path / "junk.tdms", channels={"displacement_m": "x"})


def test_a_daqs_channels_are_read_by_their_units_and_said(tmp_path: Path) -> None:
    path = _write(
        tmp_path / "daq.tdms",
        _wave("Dev1", "ai0", X * 1e3, unit_string="mm"),
        _wave("Dev1", "ai1", V * 1e3, NI_UnitDescription="mm/s"),
        _wave("Dev1", "ai2", np.zeros(N), unit_string="V"),
    )
    with pytest.warns(ReadingWarning, match="'ai0' as displacement_m, 'ai1' as velocity_m_per_s"):
        run = read_run(path)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-12)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-12)
    np.testing.assert_allclose(run.time, 2.5 + np.arange(N) / RATE)


def test_channels_whose_units_do_not_decide_are_refused_with_the_files_own_names(
    tmp_path: Path,
) -> None:
    path = _write(
        tmp_path / "two.tdms",
        _wave("Dev1", "ai0", X * 1e3, unit_string="mm"),
        _wave("Dev1", "ai1", X * 2e3, unit_string="mm"),
    )
    with pytest.raises(RunFormatError, match=r"channels=\{'displacement_m': 'ai0'\}"):
        read_run(path)
    # the example followed reads the file
    assert read_run(path, channels={"displacement_m": "ai0"}).displacement.size == N
