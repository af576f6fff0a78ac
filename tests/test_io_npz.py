"""NumPy files: a free decay saved as an .npz archive of named arrays (picked as a .mat
file's variables) and as an .npy array of columns, read back exactly and fitted; pickled
objects refused and never unpickled; bad files refused naming what is wrong."""

from __future__ import annotations

import io
import pickle
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest
from _free_decay import METADATA, RATE_HZ, X_C, ZETA, free_decay

from bayestribo import fit, read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.layout import describe_file
from bayestribo.io.registry import format_for

ARBITRARY = {"length_unit": "arbitrary"}


@pytest.fixture(scope="module")
def decay():
    return free_decay()


class _Opens:
    """An object whose unpickling creates a file: proof that it was unpickled."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple:
        return (open, (str(self.marker), "w"))


def test_arrays_named_with_units_are_read_exactly(tmp_path, decay) -> None:
    path = tmp_path / "run.npz"
    np.savez_compressed(
        path, time_s=decay.time, displacement_mm=decay.displacement, note=np.arange(3)
    )
    run = read_run(path, metadata=ARBITRARY)
    np.testing.assert_array_equal(run.time, decay.time)
    np.testing.assert_allclose(run.displacement, decay.displacement * 1e-3, rtol=1e-15, atol=0)
    reader = describe_file(path)["reader"]
    assert reader.startswith("NumPy .npz archive of 3 array(s): time_s (2400 float64)")


def test_other_names_are_picked_with_channels_as_on_the_command_line(
    tmp_path, decay, capsys
) -> None:
    path = tmp_path / "run.npz"
    np.savez(path, t=decay.time, x=decay.displacement, v=decay.velocity)
    with pytest.raises(RunFormatError, match=r"'t', 'x', 'v' name a quantity without a unit"):
        read_run(path)
    run = read_run(
        path,
        channels={"time_s": "t", "displacement_m": "x", "velocity_m_per_s": "v"},
        metadata=ARBITRARY,
    )
    np.testing.assert_array_equal(run.displacement, decay.displacement)
    np.testing.assert_array_equal(run.velocity, decay.velocity)
    assert main(["inspect", str(path)]) == 2
    assert "--channel t=t --channel x=x" in capsys.readouterr().err
    cli = ["--channel", "t=t", "--channel", "x=x", "--length-unit", "arbitrary"]
    assert main(["inspect", str(path), *cli]) == 0
    assert "time_s, displacement (arbitrary length unit)" in capsys.readouterr().out


def test_an_acceleration_alone_is_picked_with_channels(tmp_path, decay) -> None:
    # channels= naming an acceleration and no displacement or velocity: integrated
    path = tmp_path / "accelerometer.npz"
    np.savez(path, t=decay.time, a=decay.acceleration / 9.80665)
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = read_run(path, channels={"time_s": "t", "acceleration_g": "a"}, metadata=ARBITRARY)
    assert run.displacement is None and run.velocity is not None
    assert run.metadata["acceleration"]["column"] == "acceleration_m_per_s2"


def test_an_angle_is_read_as_a_rotation(tmp_path, decay) -> None:
    path = tmp_path / "pendulum.npz"
    degrees = 10.0 * decay.displacement
    np.savez(path, time_s=decay.time, angle_deg=degrees, theta=degrees)
    for channels in (None, {"time_s": "time_s", "angle_deg": "theta"}):
        run = read_run(path, channels=channels)
        assert run.length_unit == "rad"
        np.testing.assert_allclose(run.displacement, np.deg2rad(degrees), rtol=1e-15)


def test_an_npy_array_is_read_by_columns(tmp_path, decay, capsys) -> None:
    path = tmp_path / "run.npy"
    np.save(path, np.column_stack([decay.time, decay.displacement, decay.velocity]))
    with pytest.raises(RunFormatError, match=r"one array without names \(2400x3 float64\)"):
        read_run(path)
    assert main(["inspect", str(path), "--length-unit", "arbitrary"]) == 2
    err = capsys.readouterr().err
    advice = re.search(r"--columns( \S+){3}", err)
    assert advice is not None, err
    options = advice.group(0).split()
    assert main(["inspect", str(path), *options, "--length-unit", "arbitrary"]) == 0
    capsys.readouterr()
    run = read_run(path, columns=["time_s", "ignore", "velocity_mm_per_s"], metadata=ARBITRARY)
    assert run.displacement is None
    np.testing.assert_allclose(run.velocity, decay.velocity * 1e-3, rtol=1e-15, atol=0)
    # one vector: timed by the sample rate
    vector = tmp_path / "x.npy"
    np.save(vector, decay.displacement.astype(np.float32))
    run = read_run(vector, columns=["displacement_m"], sample_rate_Hz=RATE_HZ, metadata=ARBITRARY)
    np.testing.assert_array_equal(run.displacement, decay.displacement.astype(np.float32))
    np.testing.assert_array_equal(run.time, np.arange(decay.time.size) / RATE_HZ)


def test_pickled_objects_are_refused_and_never_unpickled(tmp_path, decay) -> None:
    marker = tmp_path / "unpickled"
    objects = np.array([_Opens(marker)], dtype=object)
    archive = tmp_path / "objects.npz"
    np.savez(archive, t=decay.time, x=decay.displacement, extra=objects)
    with pytest.raises(RunFormatError, match=r"array 'extra' \(1 object\) holds Python objects"):
        read_run(archive, channels={"time_s": "t", "displacement_m": "extra"})
    # an archive whose other arrays name the run: read, the objects left unread
    named = tmp_path / "named.npz"
    np.savez(named, time_s=decay.time, displacement_m=decay.displacement, extra=objects)
    run = read_run(named, metadata=ARBITRARY)
    np.testing.assert_array_equal(run.displacement, decay.displacement)
    single = tmp_path / "objects.npy"
    np.save(single, objects, allow_pickle=True)
    with pytest.raises(RunFormatError, match=r"the array \(1 object\) holds Python objects"):
        read_run(single, columns=["displacement_m"])
    plain = tmp_path / "plain.npz"
    plain.write_bytes(pickle.dumps(_Opens(marker)))
    with pytest.raises(RunFormatError, match=r"a Python pickle, which is never loaded"):
        read_run(plain)
    assert not marker.exists()  # nothing was unpickled
    # the test itself can unpickle: the marker is the proof it looks for
    pickle.loads(pickle.dumps(_Opens(marker))).close()
    assert marker.exists()


def _huge_archive(path: Path) -> Path:
    """An .npz whose one array's header claims 10⁹ float64 values, with 8 bytes of data."""
    buffer = io.BytesIO()
    header = {"descr": "<f8", "fortran_order": False, "shape": (10**9,)}
    np.lib.format.write_array_header_1_0(buffer, header)
    with zipfile.ZipFile(path, "w") as handle:
        handle.writestr("displacement_m.npy", buffer.getvalue() + bytes(8))
        handle.writestr("time_s.npy", buffer.getvalue() + bytes(8))
    return path


def test_bad_numpy_files_are_refused_naming_what_is_wrong(tmp_path, decay) -> None:
    path = tmp_path / "run.npz"
    np.savez(path, t=decay.time, x=decay.displacement)
    with pytest.raises(RunFormatError, match=r"channels\['displacement_m'\]: no array 'y'; the"):
        read_run(path, channels={"time_s": "t", "displacement_m": "y"})
    with pytest.raises(RunFormatError, match=r"columns: an \.npz archive names its arrays"):
        read_run(path, columns=["time_s", "displacement_m"])
    with pytest.raises(RunFormatError, match=r"'sheet' applies to xlsx files, not to a npz"):
        read_run(path, sheet=0)
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    with pytest.raises(RunFormatError, match=r"empty \(0 bytes\); expected a NumPy"):
        read_run(empty)
    nothing = tmp_path / "nothing.npz"
    np.savez(nothing)
    with pytest.raises(RunFormatError, match=r"holds no arrays"):
        read_run(nothing)
    with pytest.raises(RunFormatError, match=r"claims 1000000000 values"):
        read_run(_huge_archive(tmp_path / "huge.npz"))
    text = tmp_path / "text.npz"
    text.write_text("time_s,displacement_m\n0,1\n")
    with pytest.raises(RunFormatError, match=r"not a NumPy file: it starts with b'time_s,d'"):
        read_run(text)
    table = tmp_path / "table.npy"
    np.save(table, np.column_stack([decay.time, decay.displacement]))
    with pytest.raises(RunFormatError, match=r"columns: 3 name\(s\) given for an array of 2"):
        read_run(table, columns=["time_s", "displacement_m", "velocity_m_per_s"])
    with pytest.raises(RunFormatError, match=r"columns\[1\]: column 'position' has no unit"):
        read_run(table, columns=["time_s", "position"])
    with pytest.raises(RunFormatError, match=r"columns: no displacement, velocity"):
        read_run(table, columns=["time_s", "ignore"])
    with pytest.raises(RunFormatError, match=r"channels: an \.npy file holds one array"):
        read_run(table, channels={"displacement_m": "x"})
    cube = tmp_path / "cube.npy"
    np.save(cube, np.zeros((4, 3, 2)))
    with pytest.raises(RunFormatError, match=r"expected real numbers, one vector or a 2-D"):
        read_run(cube, columns=["displacement_m"])
    fields = tmp_path / "fields.npy"
    np.save(fields, np.zeros(10, dtype=[("t", "f8"), ("x", "f8")]))
    with pytest.raises(RunFormatError, match=r"structured array \(fields \['t', 'x'\]\)"):
        read_run(fields, columns=["displacement_m"])


def test_npz_is_listed_and_chosen_by_suffix_or_format(tmp_path, decay, capsys) -> None:
    assert main(["inspect", "--formats"]) == 0
    assert re.search(r"^npz\s+\.npz \.npy", capsys.readouterr().out, re.MULTILINE)
    assert format_for("x.NPZ").name == "npz" and format_for("x.npy").name == "npz"
    path = tmp_path / "record.bin"  # an archive saved under another suffix
    with path.open("wb") as handle:
        np.savez(handle, time_s=decay.time, displacement_m=decay.displacement)
    run = read_run(path, file_format="npz", metadata=ARBITRARY)
    np.testing.assert_array_equal(run.displacement, decay.displacement)
    # under a text suffix: named as what it is, not parsed as text
    table = tmp_path / "table.txt"
    with table.open("wb") as handle:
        np.save(handle, np.column_stack([decay.time, decay.displacement]))
    with pytest.raises(
        RunFormatError, match=r"first bytes .* are those of NumPy .*\(--format npz\)"
    ):
        read_run(table, columns=["time_s", "displacement_m"])
    archive = tmp_path / "archive.csv"
    archive.write_bytes(path.read_bytes())
    with pytest.raises(RunFormatError, match=r"Excel workbook \(xlsx\) or NumPy"):
        read_run(archive)


def test_an_npz_record_is_fitted_with_its_truth_inside_the_intervals(tmp_path, decay) -> None:
    path = tmp_path / "decay.npz"
    np.savez(path, t=decay.time, x=decay.displacement)
    channels = {"time_s": "t", "displacement_m": "x"}
    result = fit(
        path, read_options={"channels": channels, "metadata": METADATA}, seed=3, grid_points=32
    )
    assert result.converged
    for name, truth in (("zeta", ZETA), ("friction_displacement", X_C)):
        low, high = result.interval(name)
        assert low < truth < high, (name, low, high, truth)
