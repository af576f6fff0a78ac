"""A run belongs to one logger: exclusive raw logs, safe run ids, robust session files."""

from __future__ import annotations

import json
import os
import threading

import pytest

from bayestribo.acquisition.faults import RunInUseError
from bayestribo.acquisition.logger import (
    OperatorInputs,
    check_run_id,
    claim_raw_log,
    make_run_id,
)
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


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX")
def test_two_loggers_on_two_ports_into_one_folder_both_record(tmp_path, monkeypatch):
    # Both make up the same run id (started in the same second): the second is suffixed,
    # each raw log holds exactly its own device's bytes, the catalog gets two runs.
    from bayestribo.acquisition import session as session_module
    from bayestribo.acquisition.instrument import SimulatedInstrument, SimulationConfig
    from bayestribo.acquisition.session import acquire_run
    from bayestribo.campaign.catalog import list_runs

    monkeypatch.setattr(session_module, "make_run_id", lambda inputs: "20261122T061500Z_g_r1")
    inputs = OperatorInputs(load_N=0.31, lubricant="g", repeat=1, mass_kg=0.035)
    sims = [
        SimulatedInstrument(
            SimulationConfig(sample_rate_Hz=2000.0, duration_s=0.3, samples_per_frame=32, x0_m=x0)
        )
        for x0 in (4e-4, 5e-4)  # two rigs: other samples
    ]
    ports = [sim.start_pty() for sim in sims]
    results: dict[str, object] = {}

    def log(port: str) -> None:
        try:
            results[port] = acquire_run(port, tmp_path, inputs, catalog=tmp_path / "c.sqlite")
        except BaseException as exc:  # reported below
            results[port] = exc

    threads = [threading.Thread(target=log, args=(port,)) for port in ports]
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
    finally:
        for sim in sims:
            sim.stop()
    ids = sorted(results[port].run_id for port in ports)  # an exception has no run_id
    assert ids == ["20261122T061500Z_g_r1", "20261122T061500Z_g_r1_2"]
    for sim, port in zip(sims, ports, strict=True):
        result = results[port]
        assert result.complete
        assert result.files.raw.read_bytes() == bytes(sim.sent)
    assert sorted(r.run_id for r in list_runs(tmp_path / "c.sqlite")) == ids


def test_a_made_up_run_id_is_a_valid_one_whatever_the_lubricant():
    inputs = {"lubricant": "../" + "very long name " * 30 + "..", "load_N": 1e-5, "repeat": 3}
    run_id = make_run_id(inputs)
    assert check_run_id(run_id) == run_id and len(run_id) <= 128
