"""Every registered file format through read_run, inspect and fit; the registry itself.

A format registered without a writer here fails ``test_every_registered_format_has_a_test``:
a new reader comes with its round trip.
"""

from __future__ import annotations

import dataclasses
import importlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bayestribo import fit, read_run
from bayestribo.cli import main
from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io import ReadOptions, as_run
from bayestribo.io.layout import describe_file
from bayestribo.io.registry import (
    FileFormat,
    format_for,
    format_table,
    register_format,
    registered_formats,
)
from bayestribo.io.sidecar import sidecar_path, write_sidecar
from bayestribo.io.text import write_csv
from bayestribo.synthetic import Sensor, simulate

h5py = pytest.importorskip("h5py", reason="HDF5 files need the hdf5 extra (h5py)")
openpyxl = pytest.importorskip("openpyxl", reason="Excel files need the formats extra")
pyuff = pytest.importorskip("pyuff", reason="UFF files need the formats extra")
nptdms = pytest.importorskip("nptdms", reason="TDMS files need the formats extra")

RATE = 2000.0


@pytest.fixture(scope="module")
def run() -> Any:
    return simulate(seed=21, sensor=Sensor(sample_rate_Hz=RATE))


Written = tuple[Path, ReadOptions, list[str]]


def _text(tmp: Path, run: Any) -> Written:
    path = write_csv(run.signals, tmp / "run.csv")
    return path, ReadOptions(), []


def _xlsx(tmp: Path, run: Any) -> Written:
    book = openpyxl.Workbook()
    notes = book.active
    notes.title = "Notes"
    notes.append(["operator", "rig B"])
    sheet = book.create_sheet("Data")
    sheet.append(["Time (s)", "Displacement (mm)", "Velocity (m/s)"])
    for row in zip(run.time, 1e3 * run.displacement, run.velocity, strict=True):
        sheet.append([float(v) for v in row])
    path = tmp / "run.xlsx"
    book.save(path)
    return path, ReadOptions(), []


def _uff(tmp: Path, run: Any) -> Written:
    step = float(run.time[1] - run.time[0])

    def record(data: np.ndarray, spec: int, unit: str) -> dict:
        return pyuff.prepare_58(
            binary=1,
            id1=f"vibrometer {unit}",
            func_type=1,
            rsp_node=1,
            rsp_dir=1,
            ref_node=1,
            ref_dir=1,
            abscissa_spacing=1,
            data=data,
            x=run.time[0] + step * np.arange(data.size),
            abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s",
            ordinate_spec_data_type=spec,
            ordinate_axis_units_lab=unit,
            orddenom_spec_data_type=0,
            z_axis_spec_data_type=0,
        )

    path = tmp / "run.uff"
    pyuff.UFF(str(path)).write_sets(
        [record(run.displacement, 8, "m"), record(run.velocity, 11, "m/s")], mode="add"
    )
    return path, ReadOptions(), []


def _tdms(tmp: Path, run: Any) -> Written:
    props = {"wf_increment": float(run.time[1] - run.time[0]), "wf_start_offset": 0.0}
    path = tmp / "run.tdms"
    with nptdms.TdmsWriter(str(path)) as writer:
        writer.write_segment(
            [
                nptdms.ChannelObject(
                    "Vib", "Disp", run.displacement, {**props, "unit_string": "m"}
                ),
                nptdms.ChannelObject("Vib", "Vel", run.velocity, {**props, "unit_string": "m/s"}),
            ]
        )
    channels = {"displacement_m": "Disp", "velocity_m_per_s": "Vel"}
    options = ReadOptions(channels=channels, group="Vib")
    return path, options, ["--group", "Vib", "--channel", "x=Disp", "--channel", "v=Vel"]


def _mat(tmp: Path, run: Any) -> Written:
    import scipy.io

    path = tmp / "run.mat"
    scipy.io.savemat(
        path, {"meas": {"t": run.time, "x": 1e3 * run.displacement, "v": run.velocity}}
    )
    channels = {"time_s": "meas.t", "displacement_mm": "meas.x", "velocity_m_per_s": "meas.v"}
    cli = ["--channel", "t=meas.t", "--channel", "displacement_mm=meas.x", "--channel", "v=meas.v"]
    return path, ReadOptions(channels=channels), cli


def _hdf5(tmp: Path, run: Any) -> Written:
    path = tmp / "run.h5"
    with h5py.File(path, "w") as handle:
        group = handle.create_group("run1")
        group.create_dataset("time", data=run.time).attrs["units"] = "s"
        group.create_dataset("displacement", data=1e6 * run.displacement).attrs["units"] = "um"
        group.create_dataset("velocity", data=run.velocity).attrs["units"] = "m/s"
    return path, ReadOptions(group="run1"), ["--group", "run1"]


def _wav(tmp: Path, run: Any) -> Written:
    import scipy.io.wavfile

    path = tmp / "run.wav"  # float64 samples: read as stored
    scipy.io.wavfile.write(path, int(RATE), np.column_stack([run.displacement, run.velocity]))
    options = ReadOptions(channels={"displacement_m": "0", "velocity_m_per_s": "1"})
    return path, options, ["--channel", "x=0", "--channel", "v=1"]


def _npz(tmp: Path, run: Any) -> Written:
    path = tmp / "run.npz"
    np.savez(
        path,
        time_s=run.time,
        displacement_um=1e6 * run.displacement,
        velocity_m_per_s=run.velocity,
    )
    return path, ReadOptions(), []


WRITERS: dict[str, Callable[[Path, Any], Written]] = {
    "text": _text,
    "xlsx": _xlsx,
    "uff": _uff,
    "tdms": _tdms,
    "mat": _mat,
    "hdf5": _hdf5,
    "wav": _wav,
    "npz": _npz,
}


def test_every_registered_format_has_a_test() -> None:
    assert set(registered_formats()) == set(WRITERS)


def test_the_format_table_says_what_each_reader_reads() -> None:
    # the light table the command line builds --format from, and each module's FORMAT
    # with its reader: one description, in the same order
    table = format_table()
    formats = registered_formats()
    assert list(table) == list(formats)
    for name, fmt in formats.items():
        assert dataclasses.replace(table[name], module=None) == fmt.info
        assert importlib.import_module(str(table[name].module)).FORMAT is fmt


@pytest.fixture(scope="module")
def reference(run: Any) -> Any:
    return fit(run, seed=3, grid_points=32)


@pytest.mark.parametrize("name", list(WRITERS))
def test_every_registered_format_reads_inspects_and_fits(
    name: str, tmp_path: Path, run: Any, reference: Any, capsys: pytest.CaptureFixture
) -> None:
    path, options, cli = WRITERS[name](tmp_path, run)
    write_sidecar(run.metadata, sidecar_path(path))
    assert format_for(path).name == name

    got = read_run(path, options=options)
    # Files in mm or µm round twice (the writer's x1e3, the reader's x1e-3): a few ulp.
    np.testing.assert_allclose(got.time, run.time, rtol=1e-15, atol=0)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15, atol=0)
    np.testing.assert_allclose(got.velocity, run.velocity, rtol=1e-15, atol=0)
    assert got.metadata["load_N"] == run.metadata["load_N"]

    layout = describe_file(path, options)
    assert layout["format"] == name
    assert layout["sidecar"] == str(sidecar_path(path))
    assert main(["inspect", str(path), *cli, "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["reading"]["format"] == name
    assert shown["samples"]["n"] == run.time.size

    result = fit(path, read_options=options, seed=3, grid_points=32)
    # The same samples up to a few ulp: the same posterior within Monte Carlo error. An
    # ulp moves the chains apart, so the means differ by the Monte Carlo error of each
    # (sd / sqrt(ESS), ESS >= 1000: about 0.03 sd); 0.15 sd is 3.5 sigma of a difference.
    # A unit or channel slip would move them by thousands of sd.
    assert result.converged
    for key in ("zeta", "mu_k"):
        ours, theirs = result.summary()[key], reference.summary()[key]
        assert abs(ours.mean - theirs.mean) <= 0.15 * theirs.sd, (key, ours, theirs)


def test_an_option_of_another_format_is_refused_naming_the_formats_that_take_it(
    tmp_path: Path, run: Any
) -> None:
    path, _, _ = _text(tmp_path, run)
    with pytest.raises(RunFormatError, match=r"'sheet' applies to xlsx files, not to a text"):
        read_run(path, sheet="Data")
    with pytest.raises(RunFormatError, match=r"'group' applies to tdms and hdf5 files"):
        read_run(path, group="run1")


def test_a_format_defined_outside_the_package_reads_inspects_and_fits(
    tmp_path: Path, run: Any, capsys: pytest.CaptureFixture
) -> None:
    """One FileFormat and one register_format call: read_run, inspect and the CLI take it."""

    def read_npz(path: Path, options: ReadOptions) -> dict[str, np.ndarray]:
        with np.load(path) as data:
            return {
                "time_s": data["t"],
                "displacement_m": data["x"] * (options.scale or {}).get("displacement_m", 1.0),
            }

    fmt = FileFormat(
        "labnpz",
        "our rig's numpy archive",
        (".labnpz",),
        read_npz,
        describe=lambda path, options: {"columns": [{"label": "x", "unit": "m"}]},
    )
    register_format(fmt)
    try:
        path = tmp_path / "run.labnpz"
        with path.open("wb") as handle:
            np.savez(handle, t=run.time, x=run.displacement)
        write_sidecar(run.metadata, sidecar_path(path))
        got = read_run(path)
        np.testing.assert_array_equal(got.displacement, run.displacement)
        assert describe_file(path)["reader"] == "our rig's numpy archive"
        assert main(["inspect", str(path), "--format", "labnpz", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["reading"]["format"] == "labnpz"
        assert main(["inspect", "--formats"]) == 0
        assert "labnpz" in capsys.readouterr().out
        with pytest.raises(BayestriboError, match="registered already"):
            register_format(fmt)
        with pytest.raises(BayestriboError, match=r"\['.csv'\] already select the 'text'"):
            register_format(FileFormat("other", "other", (".csv",), read_npz))
    finally:
        from bayestribo.io import registry

        registry._REGISTRY.pop("labnpz")
        registry._READERS.pop("labnpz")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"name": "Bad Name"}, "lower-case identifier"),
        ({"suffixes": ("csv",)}, "starting with '.'"),
        ({"options": ("columns", "colour")}, r"\['colour'\] are not format options"),
        ({"signature": b"(RIFF"}, "signature: expected a regular expression over bytes"),
    ],
)
def test_a_malformed_format_is_refused_naming_the_field(kwargs: dict, match: str) -> None:
    base = {"name": "fine", "title": "t", "suffixes": (".fine",), "read": lambda p, o: {}}
    with pytest.raises(BayestriboError, match=match):
        FileFormat(**{**base, **kwargs})


def test_read_options_travel_as_one_object_and_name_a_misspelt_option(
    tmp_path: Path, run: Any
) -> None:
    path = tmp_path / "run.txt"
    rows = zip(run.time.tolist(), (1e3 * run.displacement).tolist(), strict=True)
    path.write_text("".join(f"{t!r};{x!r}\n" for t, x in rows))
    options = ReadOptions.of({"metadata": dict(run.metadata), "columns": ["t", "x"]}).replace(
        columns=["time_s", "displacement_mm"], delimiter=";"
    )
    got = as_run(path, options)
    np.testing.assert_allclose(got.displacement, run.displacement, rtol=1e-15)
    assert ReadOptions.of(options.as_kwargs()) == options
    with pytest.raises(BayestriboError, match=r"'delimeter' \(did you mean 'delimiter'\?\)"):
        ReadOptions.of({"delimeter": ";"})
    with pytest.raises(BayestriboError, match=r"'load_N' \(a metadata key"):
        as_run(path, load_N=0.3)
    with pytest.raises(BayestriboError, match="expected ReadOptions or a mapping"):
        ReadOptions.of(["columns"])  # type: ignore[arg-type]


def test_unknown_suffixes_say_what_to_do(tmp_path: Path) -> None:
    old = tmp_path / "run.xls"
    old.write_bytes(b"\xd0\xcf\x11\xe0")
    with pytest.raises(RunFormatError, match=r"save the sheet as \.xlsx or as CSV"):
        read_run(old)
    other = tmp_path / "run.bin"
    other.write_bytes(b"\x00")
    with pytest.raises(RunFormatError, match="export the data as CSV"):
        read_run(other)


def test_a_csv_is_read_without_importing_the_other_readers(tmp_path: Path, run: Any) -> None:
    # a fresh interpreter: the suffix lookup imports the built-in formats in their order
    # only until one takes the file, and gives the format the whole registry gives
    import subprocess
    import sys
    import textwrap

    path = tmp_path / "run.csv"
    write_csv(run.signals, path)
    code = textwrap.dedent(
        f"""
        import json, sys
        from bayestribo.io import read_run
        from bayestribo.io.registry import BUILTIN_MODULES, format_for, registered_formats
        read_run({str(path)!r}, validate=False)
        loaded = [m for m in BUILTIN_MODULES if m in sys.modules]
        suffixes = (".csv", ".txt", ".xlsx", ".uff", ".tdms", ".mat", ".h5")
        lazily = [format_for("x" + s).name for s in suffixes]
        whole = {{s: f.name for f in registered_formats().values() for s in f.suffixes}}
        print(json.dumps([loaded, lazily, [whole[s] for s in suffixes]]))
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    loaded, lazily, whole = json.loads(done.stdout)
    assert loaded == ["bayestribo.io.formats.text"]
    assert lazily == whole
