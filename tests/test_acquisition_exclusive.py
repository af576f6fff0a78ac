"""A run belongs to one logger: exclusive raw logs, safe run ids, robust session files."""

from __future__ import annotations

import json
import threading

import pytest

from bayestribo.acquisition.faults import RunInUseError
from bayestribo.acquisition.logger import check_run_id, claim_raw_log
from bayestribo.acquisition.recover import recover_run
from bayestribo.errors import AcquisitionError


def test_a_taken_run_id_is_refused_or_suffixed(tmp_path):
    run_id, path = claim_raw_log(
        tmp_path, "20261122T061500Z_glycerol_N0.31_r1", suffix_if_taken=False
    )
    assert path.is_file() and path.stat().st_size == 0
    with pytest.raises(RunInUseError, match=r"exists already.*another --run-id"):
        claim_raw_log(tmp_path, run_id, suffix_if_taken=False)
    second, other = claim_raw_log(tmp_path, run_id, suffix_if_taken=True)
    assert second == run_id + "_2" and other != path


def test_two_loggers_in_the_same_second_get_distinct_runs(tmp_path):
    # Many threads claiming one generated id at once: every claim is distinct.
    claimed: list[str] = []
    lock = threading.Lock()

    def claim() -> None:
        run_id, _ = claim_raw_log(tmp_path, "20261122T061500Z_x_N0.1_r1", suffix_if_taken=True)
        with lock:
            claimed.append(run_id)

    threads = [threading.Thread(target=claim) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(claimed)) == 8
    assert len(list(tmp_path.glob("*.raw"))) == 8


@pytest.mark.parametrize(
    "bad", ["../escaped/evil", "/abs", "a/b", "", ".hidden", "a..b", "x" * 200, 7, None]
)
def test_run_ids_that_are_not_file_names_are_refused(bad):
    with pytest.raises(AcquisitionError, match="is not a run id"):
        check_run_id(bad)


def test_a_session_file_cannot_steer_recovery_outside_its_folder(tmp_path):
    raw = tmp_path / "r1.raw"
    raw.write_bytes(b"")
    session = tmp_path / "r1.session.json"
    inputs = {"load_N": 0.31, "lubricant": "glycerol", "repeat": 1}
    session.write_text(json.dumps({"run_id": "../escaped/evil", "operator_inputs": inputs}))
    with pytest.raises(AcquisitionError, match="is not a run id"):
        recover_run(raw)
    assert not (tmp_path.parent / "escaped").exists()


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ('{"run_id": "r1", "operator_inputs": [1]}', "mapping 'operator_inputs'"),
        (
            '{"run_id": "r1", "operator_inputs": {"lubricant": "g", "repeat": 1, "load_N": 1'
            + "0" * 400
            + "}}",
            "load_N",
        ),
        (
            '{"run_id": "r1", "operator_inputs": {"load_N": 0.3, "lubricant": "g", '
            '"repeat": 1, "colour": "red"}}',
            "unknown operator inputs \\['colour'\\]",
        ),
    ],
    ids=["deep", "inputs not a mapping", "400-digit load", "unknown input"],
)
def test_a_session_file_of_any_shape_gives_the_packages_error(tmp_path, text, match):
    raw = tmp_path / "r1.raw"
    raw.write_bytes(b"")
    (tmp_path / "r1.session.json").write_text(text)
    with pytest.raises(AcquisitionError, match=match):
        recover_run(raw)
