"""When a watched run file counts as complete (:mod:`bayestribo.campaign.arrivals`).

The clock is a variable the test moves: no sleeping, no race. A file without a manifest
is complete once it and its sidecar kept their size and modification time for the settle
interval; a file listed with its sidecar in a matching ``.sha256`` manifest (as
``bayestribo acquire`` writes it) is complete at once.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bayestribo.campaign.arrivals import Arrivals

SETTLE = 2.0


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _arrivals(folder: Path, **kwargs) -> tuple[Arrivals, Clock]:
    clock = Clock()
    return Arrivals(folder, [".csv"], SETTLE, clock=clock, **kwargs), clock


def _append(path: Path, text: str, stamp: int) -> None:
    with open(path, "a", encoding="utf-8") as fh:
        fh.write(text)
    # the modification time set explicitly: a chunk written within the file system's
    # time resolution still shows as a change of the file
    os.utime(path, ns=(stamp, stamp))


def _run(folder: Path, name: str, rows: str = "time_s,x\n0,1\n") -> Path:
    (folder / f"{name}.json").write_text(json.dumps({"run_id": name}), encoding="utf-8")
    path = folder / f"{name}.csv"
    path.write_text(rows, encoding="utf-8")
    return path


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_growing_file_waits_until_it_stops_then_is_given_once(tmp_path):
    arrivals, clock = _arrivals(tmp_path)
    (tmp_path / "slow.json").write_text('{"run_id": "slow"}', encoding="utf-8")
    path = tmp_path / "slow.csv"
    for chunk in range(5):  # a chunk every second, within the settle interval
        _append(path, f"{chunk},{chunk}\n", stamp=10**9 * (chunk + 1))
        assert arrivals.poll() == []
        assert arrivals.pending() == [path]
        clock.now += 1.0
    clock.now += SETTLE - 1.0  # no chunk for the settle interval
    assert arrivals.poll() == [path]
    assert arrivals.pending() == []
    clock.now += 10 * SETTLE
    assert arrivals.poll() == []  # given once
    # rewritten: a new version, given again once it settles
    _append(path, "5,5\n", stamp=10**10)
    assert arrivals.poll() == []
    clock.now += SETTLE
    assert arrivals.poll() == [path]


def test_a_file_without_its_sidecar_is_not_a_run(tmp_path):
    arrivals, clock = _arrivals(tmp_path)
    path = tmp_path / "alone.csv"
    path.write_text("time_s,x\n0,1\n", encoding="utf-8")
    arrivals.poll()
    clock.now += 10 * SETTLE
    assert arrivals.poll() == []
    assert arrivals.pending() == []  # nor waited for
    (tmp_path / "alone.json").write_text('{"run_id": "alone"}', encoding="utf-8")
    assert arrivals.poll() == []  # the sidecar has to settle too
    assert arrivals.pending() == [path]
    clock.now += SETTLE
    assert arrivals.poll() == [path]


def test_a_file_in_its_manifest_is_complete_at_once(tmp_path):
    arrivals, _ = _arrivals(tmp_path)
    path = _run(tmp_path, "acquired")
    side = path.with_suffix(".json")
    manifest = path.with_suffix(".sha256")
    manifest.write_text(f"{'0' * 64}  {path.name}\n{_sha(side)}  {side.name}\n", encoding="utf-8")
    assert arrivals.poll() == []  # the digest listed is not the file's
    manifest.write_text(f"{_sha(path)}  {path.name}\n{_sha(side)}  {side.name}\n", encoding="utf-8")
    assert arrivals.poll() == [path]  # the clock has not moved


def test_hidden_and_excluded_folders_and_other_suffixes_are_not_looked_at(tmp_path):
    staging = tmp_path / ".run.staging-x"
    out = tmp_path / "results"
    for folder in (staging, out):
        folder.mkdir()
        _run(folder, "inside")
    _run(tmp_path, "notes", rows="")
    (tmp_path / "notes.csv").rename(tmp_path / "notes.raw")
    arrivals, clock = _arrivals(tmp_path, exclude=[out])
    arrivals.poll()
    clock.now += SETTLE
    assert arrivals.poll() == []


def test_links_to_run_files_are_runs_and_links_to_folders_are_not_followed(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    real = _run(elsewhere, "real")
    watched = tmp_path / "watched"
    watched.mkdir()
    for suffix in (".csv", ".json"):
        os.symlink(real.with_suffix(suffix), watched / f"linked{suffix}")
    os.symlink(watched, watched / "loop")  # a folder that holds itself
    arrivals, clock = _arrivals(watched)
    arrivals.poll()
    clock.now += SETTLE
    assert arrivals.poll() == [watched / "linked.csv"]


def test_a_file_removed_and_put_back_arrives_again(tmp_path):
    arrivals, clock = _arrivals(tmp_path)
    path = _run(tmp_path, "back")
    arrivals.poll()
    clock.now += SETTLE
    assert arrivals.poll() == [path]
    moved = path.rename(tmp_path / "back.tmp")
    assert arrivals.poll() == []
    moved.rename(path)
    arrivals.poll()
    clock.now += SETTLE
    assert arrivals.poll() == [path]


@pytest.mark.parametrize("settle", [0.0, -1.0, float("nan")])
def test_the_settle_interval_must_be_positive(tmp_path, settle):
    with pytest.raises(ValueError, match="settle_s"):
        Arrivals(tmp_path, [".csv"], settle)


@settings(max_examples=60, deadline=None)
@given(
    gaps=st.lists(
        # not within rounding of the interval itself: the clock is a sum of floats, and
        # a gap of exactly SETTLE after 1.0 + 5.29672900845764 measured 1.9999999999999991
        st.floats(0.0, 3 * SETTLE).filter(lambda gap: abs(gap - SETTLE) > 1e-9),
        min_size=1,
        max_size=8,
    )
)
def test_a_file_is_given_each_time_it_rests_for_the_settle_interval(gaps):
    """Appended to, then left alone for each gap in turn: given after every gap of at
    least the settle interval, and at no other poll."""
    with tempfile.TemporaryDirectory() as folder:
        arrivals, clock = _arrivals(Path(folder))
        path = _run(Path(folder), "run")
        given = []
        for i, gap in enumerate(gaps):
            _append(path, f"{i},{i}\n", stamp=10**9 * (i + 1))
            assert arrivals.poll() == []  # just written
            clock.now += gap
            given.append(arrivals.poll() == [path])
        assert given == [gap >= SETTLE for gap in gaps]


def test_the_next_file_due_is_told_in_seconds_from_the_clock(tmp_path):
    """A waiting loop can sleep until the soonest file waiting may have settled."""
    arrivals, clock = _arrivals(tmp_path)
    assert arrivals.next_due() is None  # nothing seen
    _run(tmp_path, "first")
    assert arrivals.poll() == []
    clock.now += 0.5
    assert arrivals.next_due() == SETTLE - 0.5
    _run(tmp_path, "second")
    assert arrivals.poll() == []
    clock.now += 1.0
    assert arrivals.next_due() == SETTLE - 1.5  # the first one's, the sooner
    clock.now += 10 * SETTLE
    assert arrivals.next_due() == 0.0  # overdue: due now
    assert arrivals.poll() == [tmp_path / "first.csv", tmp_path / "second.csv"]
    assert arrivals.next_due() is None  # given: none waits
