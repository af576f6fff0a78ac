"""Canonical CSV + JSON sidecar: exact round trip, sidecar rules, keyword metadata."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from bayestribo import Run, read_run, simulate, write_run
from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io import as_run
from bayestribo.model.scaling import Rig
from bayestribo.synthetic import Release, Sensor


def _run(**meta: object) -> Run:
    t = 12.5 + np.arange(200) / 5000.0
    x = 1e-3 * np.exp(-t) * np.cos(205.0 * t) + 3e-5
    v = np.gradient(x, t)
    return Run(t, x, v, meta)


def test_round_trip_is_exact_with_metadata(tmp_path: Path) -> None:
    run = _run(
        load_N=0.31,
        mass_kg=0.035,
        natural_frequency_Hz=32.6,
        repeat=2,
        lubricant="glycerol",
        user={"operator": "B. Smith", "nested": {"list": [1, 2.5, None, True], "text": "é"}},
    )
    path = write_run(run, tmp_path / "run.csv")
    assert (tmp_path / "run.json").is_file()
    back = read_run(path)
    assert back == run
    assert back.source == str(path)
    assert back.metadata["user"]["nested"]["text"] == "é"
    # Bit-identical floats (== on arrays would accept -0.0 for 0.0).
    assert back.velocity.tobytes() == run.velocity.tobytes()


def test_keys_of_ones_own_are_written_under_user_and_read_back_there(tmp_path: Path) -> None:
    run = _run(load_N=0.31, operator="B. Smith", user={"room": 4})
    back = read_run(write_run(run, tmp_path / "run.csv"))
    assert back.metadata["user"] == {"room": 4, "operator": "B. Smith"}
    assert "operator" not in back.metadata and back.metadata["load_N"] == 0.31


def test_written_header_and_sidecar_follow_the_format(tmp_path: Path) -> None:
    run = Run([0.0, 0.5, 1.0], velocity=[0.0, -0.25, 1e-300], metadata={"load_N": 0})
    write_run(run, tmp_path / "r.csv")
    lines = (tmp_path / "r.csv").read_text().splitlines()
    assert lines == ["time_s,velocity_m_per_s", "0.0,0.0", "0.5,-0.25", "1.0,1e-300"]
    digest = hashlib.sha256((tmp_path / "r.csv").read_bytes()).hexdigest()
    assert json.loads((tmp_path / "r.json").read_text()) == {
        "load_N": 0.0,
        "data_file": {"samples": 3, "sha256": digest},
    }


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=60, deadline=None)
@given(
    data=hnp.arrays(np.float64, st.integers(1, 40), elements=finite),
    signal=st.sampled_from(["displacement", "velocity", "both"]),
)
def test_any_finite_floats_round_trip_bit_exactly(tmp_path_factory, data, signal) -> None:
    path = tmp_path_factory.mktemp("rt") / "run.csv"
    t = np.arange(data.size, dtype=float)
    run = Run(
        t,
        data if signal in ("displacement", "both") else None,
        data[::-1] if signal in ("velocity", "both") else None,
    )
    write_run(run, path)
    back = read_run(path, validate=False)
    assert back == run
    for name, values in run.signals.items():
        assert back.signals[name].tobytes() == values.tobytes()


def test_simulated_run_round_trips(tmp_path: Path) -> None:
    run = simulate(
        rig=Rig(natural_frequency_Hz=32.6, mass_kg=0.035, load_N=0.46),
        release=Release(time_origin_s=3.1415),
        sensor=Sensor(quantise=True),
        seed=11,
    )
    assert read_run(write_run(run, tmp_path / "sim.csv")) == run


def test_missing_sidecar_is_allowed_and_keywords_fill_or_override(tmp_path: Path) -> None:
    run = _run(load_N=0.31, repeat=1)
    path = write_run(run, tmp_path / "r.csv")
    assert read_run(path, metadata={"load_N": 0.46}).metadata["load_N"] == 0.46
    assert read_run(path, metadata={"temperature_C": 21.5}).metadata["repeat"] == 1
    (tmp_path / "r.json").unlink()
    bare = read_run(path)
    assert dict(bare.metadata) == {}
    assert bare.rig() is None
    assert read_run(path, metadata={"natural_frequency_Hz": 32.6}).rig().load_N is None


def test_sidecar_can_be_skipped_or_given(tmp_path: Path) -> None:
    path = write_run(_run(load_N=0.31), tmp_path / "r.csv")
    assert dict(read_run(path, sidecar=False).metadata) == {}
    other = tmp_path / "other.json"
    other.write_text('{"load_N": 0.07}')
    assert read_run(path, sidecar=other).metadata["load_N"] == 0.07
    with pytest.raises(RunFormatError, match=r"missing\.json: no such sidecar file"):
        read_run(path, sidecar=tmp_path / "missing.json")


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("{not json", "not valid JSON"),
        ("[1, 2]", "one JSON object"),
        ('{"load_N": 0.3, "load_N": 0.4}', "appears twice"),
        ('{"load_N": NaN}', "NaN is not a JSON number"),
        ('{"load_N": "0.31"}', "metadata 'load_N'.*expected a finite number.*got str"),
        ('{"repeat": 1.0}', "metadata 'repeat'.*expected an integer"),
    ],
)
def test_bad_sidecar_raises_naming_file_and_key(tmp_path: Path, text: str, match: str) -> None:
    path = write_run(_run(), tmp_path / "r.csv")
    (tmp_path / "r.json").write_text(text)
    with pytest.raises(RunFormatError, match=match) as info:
        read_run(path)
    assert "r.json" in str(info.value)


def test_sidecar_not_utf8_raises(tmp_path: Path) -> None:
    path = write_run(_run(), tmp_path / "r.csv")
    (tmp_path / "r.json").write_bytes(b'{"lubricant": "\xff"}')
    with pytest.raises(RunFormatError, match=r"r\.json.*not UTF-8"):
        read_run(path)


@pytest.mark.parametrize(
    ("suffix", "says"),
    [
        (".trk", r"Tracker .* File > Export > Data .* --length-unit arbitrary .*pixels"),
        (".trz", r"Tracker"),
        (".cmbl", r"Logger Pro .* Export As"),
        (".cap", r"Capstone .* Export Data"),
        (".phyphox", r"phyphox .* holds no measurement"),
    ],
)
def test_a_teaching_labs_project_file_is_refused_with_its_export(
    tmp_path: Path, suffix: str, says: str
) -> None:
    # a teaching lab's program saves its own project; the refusal names how that
    # program writes the data as text (a Tracker project was refused with a list of
    # suffixes only)
    path = tmp_path / f"damping{suffix}"
    path.write_text('<?xml version="1.0" encoding="UTF-8"?>\n<object/>\n')
    with pytest.raises(RunFormatError, match=says):
        read_run(path)


def test_write_needs_csv_suffix_and_read_needs_known_type(tmp_path: Path) -> None:
    with pytest.raises(RunFormatError, match=r"\.csv"):
        write_run(_run(), tmp_path / "r.txt.gz")
    (tmp_path / "r.xyz").write_text("1,2\n")
    with pytest.raises(RunFormatError, match=r"unknown file type \'\.xyz\'"):
        read_run(tmp_path / "r.xyz")
    with pytest.raises(RunFormatError, match=r"nope\.csv: no such run file"):
        read_run(tmp_path / "nope.csv")


def test_option_for_another_format_is_refused(tmp_path: Path) -> None:
    path = write_run(_run(), tmp_path / "r.csv")
    with pytest.raises(RunFormatError, match="option 'group' applies to tdms"):
        read_run(path, group="Vibrometer")


def test_a_misspelt_reading_option_is_an_error_with_a_suggestion(tmp_path):
    path = write_run(simulate(seed=1), tmp_path / "sim.csv")
    with pytest.raises(BayestriboError, match=r"'delimeter' \(did you mean 'delimiter'\?\)"):
        read_run(path, delimeter=",")
    with pytest.raises(BayestriboError, match=r"metadata=\{'load_N'"):
        read_run(path, load_N=0.31)


def test_as_run_passes_a_run_through_and_reads_a_path(tmp_path):
    run = simulate(seed=1)
    path = write_run(run, tmp_path / "sim.csv")
    assert as_run(run) is run
    assert as_run(path) == run and as_run(str(path)) == run
    assert as_run(path, metadata={"load_N": 0.46}).metadata["load_N"] == 0.46
    with pytest.raises(BayestriboError, match="already a Run"):
        as_run(run, delimiter=",")
    with pytest.raises(BayestriboError, match="run: expected a bayestribo Run or the path"):
        as_run(42)
