"""A data file is read only if it is the one its sidecar records (``data_file``)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from bayestribo.cli import main
from bayestribo.io import read_run, write_run
from bayestribo.io.run import Run
from bayestribo.io.sidecar import DataFileMismatchError, file_sha256
from tests._paths import RUNS

BUNDLED = "glycerol-N0.31-r1"


@pytest.fixture
def run_file(tmp_path: Path) -> Path:
    """A copy of a bundled run and its sidecar (which records the CSV)."""
    for suffix in (".csv", ".json"):
        shutil.copy(RUNS / f"{BUNDLED}{suffix}", tmp_path / f"{BUNDLED}{suffix}")
    return tmp_path / f"{BUNDLED}.csv"


def _rows(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines(keepends=True)


def test_the_sidecar_written_records_the_files_samples_and_checksum(tmp_path: Path) -> None:
    run = Run([0.0, 0.1, 0.2, 0.3], [1e-3, 0.0, -1e-3, 0.0], metadata={"load_N": 0.31})
    path = write_run(run, tmp_path / "r.csv")
    record = json.loads((tmp_path / "r.json").read_text())["data_file"]
    assert record == {"samples": 4, "sha256": file_sha256(path)}
    back = read_run(path, validate=False)
    assert "data_file" not in back.metadata  # it describes the file, not the run
    assert back.metadata == run.metadata


def test_an_untouched_file_is_read(run_file: Path) -> None:
    recorded = json.loads(run_file.with_suffix(".json").read_text())["data_file"]
    assert read_run(run_file).n_samples == recorded["samples"]


def test_a_file_cut_on_a_row_boundary_is_refused_naming_the_counts(run_file: Path) -> None:
    rows = _rows(run_file)
    expected = len(rows) - 1
    kept = 471
    run_file.write_text("".join(rows[: kept + 1]), encoding="utf-8")
    with pytest.raises(DataFileMismatchError) as caught:
        read_run(run_file)
    message = str(caught.value)
    assert f"holds {kept} samples but its sidecar {BUNDLED}.json records {expected}" in message
    assert "data_file.sha256" in message
    assert caught.value.found["samples"] == kept
    assert caught.value.expected["samples"] == expected


def test_one_value_changed_is_refused_naming_the_checksum(run_file: Path) -> None:
    rows = _rows(run_file)
    middle = len(rows) // 2
    fields = rows[middle].rstrip("\n").split(",")
    fields[-1] = repr(float(fields[-1]) + 0.002)  # a velocity off by 2 mm/s
    rows[middle] = ",".join(fields) + "\n"
    run_file.write_text("".join(rows), encoding="utf-8")
    with pytest.raises(DataFileMismatchError, match=r"SHA-256 .* with the same \d+ samples"):
        read_run(run_file)


def test_a_file_cut_mid_number_is_refused_not_read_short(run_file: Path) -> None:
    data = run_file.read_bytes()
    run_file.write_bytes(data[: len(data) // 2])
    with pytest.raises(DataFileMismatchError, match="data_file"):
        read_run(run_file)


def test_a_sidecar_without_the_record_is_read_as_before(run_file: Path) -> None:
    side = run_file.with_suffix(".json")
    metadata = json.loads(side.read_text())
    del metadata["data_file"]
    side.write_text(json.dumps(metadata))
    rows = _rows(run_file)
    run_file.write_text("".join(rows[:1001]), encoding="utf-8")
    assert read_run(run_file).n_samples == 1000


def test_a_hand_written_sample_count_is_checked(run_file: Path) -> None:
    side = run_file.with_suffix(".json")
    metadata = json.loads(side.read_text())
    metadata["data_file"] = {"samples": 5}
    side.write_text(json.dumps(metadata))
    with pytest.raises(DataFileMismatchError, match=r"records 5 \(data_file.samples\)"):
        read_run(run_file)


def test_the_command_line_refuses_a_changed_file(run_file: Path, capsys) -> None:
    rows = _rows(run_file)
    run_file.write_text("".join(rows[:500]), encoding="utf-8")
    assert main(["inspect", str(run_file)]) == 2
    err = capsys.readouterr().err
    assert f"holds 499 samples but its sidecar {BUNDLED}.json records {len(rows) - 1}" in err
