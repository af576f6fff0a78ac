"""MATLAB .mat (v5 and v7.3) and HDF5 files: signals picked by name and unit, or named
by the user, and never read under a unit nobody stated."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from bayestribo.cli import main
from bayestribo.errors import RunFormatError
from bayestribo.io import read_run
from bayestribo.synthetic import simulate

h5py = pytest.importorskip("h5py", reason="HDF5 reading needs the hdf5 extra (h5py)")


@pytest.fixture(scope="module")
def run():
    return simulate(seed=12)


def _meta(run):
    return dict(run.metadata)


def _same(got, run):
    np.testing.assert_array_equal(got.time, run.time)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    np.testing.assert_allclose(got.velocity, run.velocity, rtol=1e-15)


def test_mat_with_canonical_names(tmp_path, run):
    path = tmp_path / "run.mat"
    scipy.io.savemat(
        path,
        {"time_s": run.time, "displacement_m": run.displacement, "velocity_m_per_s": run.velocity},
    )
    _same(read_run(path, metadata=_meta(run)), run)


def test_mat_structure_with_units_in_names(tmp_path, run):
    path = tmp_path / "run.mat"
    data = {"time_ms": 1e3 * run.time, "displacement_um": 1e6 * run.displacement}
    scipy.io.savemat(path, {"data": data, "notes": "free text"})
    got = read_run(path, metadata=_meta(run))
    np.testing.assert_allclose(got.time, run.time, rtol=1e-15)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    assert got.velocity is None


def test_mat_short_names_need_channels_and_units(tmp_path, run):
    path = tmp_path / "short.mat"
    scipy.io.savemat(path, {"t": run.time, "x": 1e3 * run.displacement, "fs": 1e4})
    with pytest.raises(RunFormatError, match=r"'t', 'x' name a quantity without a unit") as info:
        read_run(path)
    assert "t (1x" in str(info.value) or "t (" in str(info.value)
    got = read_run(path, channels={"time_s": "t", "displacement_mm": "x"}, metadata=_meta(run))
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    with pytest.raises(RunFormatError, match="no variable 'y'"):
        read_run(path, channels={"time_s": "t", "displacement_m": "y"})
    with pytest.raises(RunFormatError, match="expected a real numeric array of samples"):
        read_run(path, channels={"time_s": "fs", "displacement_m": "x"})


def _write_v73(path, arrays):
    """A MATLAB 7.3 file: HDF5 with MATLAB's 512-byte user block."""
    with h5py.File(path, "w", userblock_size=512) as handle:
        for name, values in arrays.items():
            handle.create_dataset(name, data=np.asarray(values)[None, :])
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 ."
    header = text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    with open(path, "r+b") as handle:
        handle.write(header)


def test_mat_v73_is_read_through_hdf5(tmp_path, run):
    path = tmp_path / "v73.mat"
    _write_v73(path, {"time_s": run.time, "velocity_m_per_s": run.velocity})
    with pytest.raises(NotImplementedError):
        scipy.io.loadmat(path)
    got = read_run(path, metadata=_meta(run))
    np.testing.assert_array_equal(got.velocity, run.velocity)


def test_hdf5_units_from_attributes_and_groups(tmp_path, run):
    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as handle:
        group = handle.create_group("runs/r1")
        group.create_dataset("time", data=run.time).attrs["units"] = "s"
        group.create_dataset("displacement", data=1e3 * run.displacement).attrs["units"] = "mm"
        group.create_dataset("velocity", data=run.velocity).attrs["units"] = b"m/s"
        other = handle.create_group("runs/r2")
        other.create_dataset("time", data=run.time).attrs["units"] = "s"
    with pytest.raises(RunFormatError, match="both name time_s"):
        read_run(path)
    got = read_run(path, group="runs/r1", metadata=_meta(run))
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    got = read_run(
        path,
        channels={"time_s": "runs/r1/time", "displacement_m": "runs/r1/displacement"},
        metadata=_meta(run),
    )
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    with pytest.raises(RunFormatError, match="contradicts the unit in 'displacement_um'"):
        read_run(
            path, channels={"time_s": "runs/r1/time", "displacement_um": "runs/r1/displacement"}
        )
    with pytest.raises(RunFormatError, match=r"names 2 datasets \(runs/r1/time, runs/r2/time\)"):
        read_run(path, channels={"time_s": "time", "displacement_m": "displacement"})
    with pytest.raises(RunFormatError, match="no group 'runs/r9'"):
        read_run(path, group="runs/r9")


def test_hdf5_lengths_must_agree(tmp_path, run):
    path = tmp_path / "bad.h5"
    with h5py.File(path, "w") as handle:
        handle["time_s"] = run.time
        handle["displacement_m"] = run.displacement[:-3]
    with pytest.raises(RunFormatError, match="different lengths"):
        read_run(path)


def test_not_an_hdf5_or_mat_file(tmp_path):
    for name in ("fake.h5", "fake.mat"):
        path = tmp_path / name
        path.write_text("time_s,displacement_m\n0,1\n", encoding="utf-8")
        with pytest.raises(RunFormatError, match="not a readable"):
            read_run(path)


def test_command_line_names_variables_with_channel_options(tmp_path, run, capsys):
    path = tmp_path / "short.mat"
    scipy.io.savemat(path, {"t": run.time, "x": run.displacement, "v": run.velocity})
    meta = ["--frequency", "32.6", "--load", "0.31", "--mass", "0.035"]
    assert main(["decay", str(path), "--json", *meta]) == 2
    err = capsys.readouterr().err
    assert "--channel t=t --channel x=x" in err and "channels=" not in err
    argv = ["decay", str(path), "--json", "--channel", "t=t", "--channel", "x=x"]
    assert main([*argv, "--channel", "v=v", *meta]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["natural_frequency_Hz"] == pytest.approx(32.6, rel=2e-3)
    assert main([*argv, "--channel", "v", *meta]) == 2
    assert "--channel: expected NAME=SOURCE" in capsys.readouterr().err


def test_a_structure_with_one_unitless_field_is_named_as_it_is_and_read_so(tmp_path, run, capsys):
    """``rec.t`` beside ``rec.x_mm``: the refusal names the fields as the options that
    read them, and the field picked by its role keeps the unit its name states."""
    path = tmp_path / "struct.mat"
    scipy.io.savemat(path, {"rec": {"t": run.time, "x_mm": 1e3 * run.displacement}})
    meta = ["--frequency", "32.6", "--load", "0.31", "--mass", "0.035"]
    assert main(["decay", str(path), "--json", *meta]) == 2
    assert "e.g. --channel t=rec.t --channel x=rec.x_mm" in capsys.readouterr().err
    got = read_run(
        path, channels={"time_s": "rec.t", "displacement_m": "rec.x_mm"}, metadata=_meta(run)
    )
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)


def test_hdf5_one_dataset_without_time_is_named_with_the_sample_rate(tmp_path, run, capsys):
    path = tmp_path / "one.h5"
    with h5py.File(path, "w") as handle:
        handle.create_dataset("disp", data=1e6 * run.displacement).attrs["units"] = "um"
    assert main(["decay", str(path), "--json"]) == 2
    assert "e.g. --channel x=disp with --sample-rate HZ" in capsys.readouterr().err
    rate = run.sample_rate_Hz
    got = read_run(path, channels={"displacement_m": "disp"}, sample_rate_Hz=rate)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-12)
