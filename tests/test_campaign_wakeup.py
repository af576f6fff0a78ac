"""The folder events that wake a watch (:mod:`bayestribo.campaign.wakeup`), and the
watch's side of them: polling alone where they cannot be had, and each answer said once,
when its fit is back, before it is recorded.

The filtering is checked on watchdog's own event objects, handed to the handler as the
observer hands them; the observer itself on a real folder, where a file landing must
resolve the armed future (a deadline far beyond its need fails the test; nothing is
asserted about time).
"""

from __future__ import annotations

import io
import os
from concurrent.futures import wait
from pathlib import Path

import pytest
from watchdog.events import (
    DirCreatedEvent,
    DirModifiedEvent,
    FileClosedEvent,
    FileClosedNoWriteEvent,
    FileCreatedEvent,
    FileDeletedEvent,
    FileModifiedEvent,
    FileMovedEvent,
    FileOpenedEvent,
)

from bayestribo.campaign.wakeup import Wakeup

#: Longest wait for an event (a deadline that fails the test, never a measurement) [s].
DEADLINE = 60.0


def test_a_file_landing_in_the_folder_resolves_the_armed_future(tmp_path):
    (tmp_path / "sub").mkdir()
    wakeup = Wakeup(tmp_path)
    assert wakeup.start() is None and wakeup.running
    try:
        armed = wakeup.armed()
        assert not armed.done()
        assert wakeup.armed() is armed  # the same until a change resolves it
        staged = tmp_path / ".staging"
        staged.mkdir()
        (staged / "run.csv").write_text("t,x\n0,1\n")
        os.replace(staged / "run.csv", tmp_path / "sub" / "run.csv")
        done, _ = wait([armed], timeout=DEADLINE)
        assert armed in done
        fresh = wakeup.armed()
        assert fresh is not armed and not fresh.done()
        (tmp_path / "sub" / "run.csv").unlink()
        done, _ = wait([fresh], timeout=DEADLINE)
        assert fresh in done
    finally:
        wakeup.stop()
    assert not wakeup.running
    wakeup.stop()  # idempotent


@pytest.mark.parametrize(
    ("kind", "paths"),
    [
        (FileCreatedEvent, ["run.csv"]),
        (FileCreatedEvent, ["sub/run.csv"]),
        (FileClosedEvent, ["run.csv"]),  # closed after writing
        (FileDeletedEvent, ["run.csv"]),
        (DirCreatedEvent, ["sub"]),
        (FileMovedEvent, [".staging/run.csv", "run.csv"]),  # the acquisition's rename
        (FileMovedEvent, ["out/run.csv", "run.csv"]),  # out of the output folder
        (FileMovedEvent, ["run.csv", ".trash/run.csv"]),  # away into a hidden folder
        (FileCreatedEvent, ["out-2/run.csv"]),  # beside the output folder, not in it
        (FileCreatedEvent, ["catalog.sqlite.csv"]),
    ],
)
def test_changes_in_the_folder_wake(tmp_path, kind, paths):
    assert _handled(tmp_path, kind, paths).done()


@pytest.mark.parametrize(
    ("kind", "paths"),
    [
        (FileOpenedEvent, ["run.csv"]),  # a fit reading a run
        (FileClosedNoWriteEvent, ["run.csv"]),
        (FileModifiedEvent, ["run.csv"]),  # each write of a file streamed in
        (DirModifiedEvent, ["sub"]),
        (FileCreatedEvent, [".run.staging-1/run.csv"]),  # the acquisition's staging
        (FileClosedEvent, ["sub/.hidden.csv"]),
        (FileModifiedEvent, ["out/watch.html"]),  # the watch's own page
        (FileMovedEvent, ["out/.watch.html.tmp", "out/watch.html"]),
        (FileCreatedEvent, ["out/fits/run.nc"]),
        (FileClosedEvent, ["catalog.sqlite"]),
        (FileCreatedEvent, ["catalog.sqlite-journal"]),
    ],
)
def test_reads_writes_hidden_names_and_the_watchs_own_files_do_not_wake(tmp_path, kind, paths):
    assert not _handled(tmp_path, kind, paths).done()


def _handled(folder: Path, kind, paths: list[str]):
    """The armed future of a wake-up of ``folder`` (its ``out`` folder and catalog left
    out) once handed an event of ``kind`` on ``paths`` (relative to the folder), as the
    observer hands it."""
    own = [folder / "out", folder / "catalog.sqlite", folder / "catalog.sqlite-journal"]
    wakeup = Wakeup(folder, exclude=own)
    armed = wakeup.armed()
    wakeup._event(kind(*(str(folder / p) for p in paths)))
    return armed


def test_a_folder_that_cannot_be_watched_is_said_and_polled(tmp_path):
    """An observer that cannot start gives the reason, and the watch says it polls."""
    from bayestribo.campaign.watch import CampaignWatch, WatchOptions
    from bayestribo.inference.spec import FitSpec

    missing = tmp_path / "gone"
    assert Wakeup(missing).start() is not None  # no such folder: a reason, no raise
    said: list[str] = []
    watch = CampaignWatch(
        missing,
        tmp_path / "out",
        tmp_path / "out" / "catalog.sqlite",
        FitSpec(),
        WatchOptions(poll_s=0.5),
        by=("load_N",),
        suffixes=[".csv"],
        stream=io.StringIO(),
        say=said.append,
    )
    watch._watch_events()
    assert watch._wakeup is None
    (message,) = said
    assert message.startswith(f"no change events from {missing} (")
    assert message.endswith("looking at it every 0.5 s (--poll)")


def _watch(tmp_path: Path, **options):
    from bayestribo.campaign.watch import CampaignWatch, WatchOptions
    from bayestribo.inference.spec import FitSpec

    stream = io.StringIO()
    watch = CampaignWatch(
        tmp_path,
        tmp_path / "out",
        tmp_path / "out" / "catalog.sqlite",
        FitSpec(),
        WatchOptions(**options),
        by=("load_N",),
        suffixes=[".csv"],
        stream=stream,
        say=lambda message: None,
    )
    return watch, stream


def _fitted(name: str):
    from types import SimpleNamespace

    from bayestribo.campaign.fitting import RunOutcome

    digest = SimpleNamespace(
        law="viscous",
        converged=True,
        summaries={"zeta": {"median": 0.02, "interval": (0.019, 0.021)}},
        quantities={"zeta": {"symbol": "ζ", "unit": "1"}},
    )
    return RunOutcome(name, 1, digest, None, None, 0.05)


def test_an_answer_announced_is_not_said_again_unless_its_recording_failed(tmp_path):
    """A run is answered once, when its fit is back; the recording that follows adds a
    line only where it failed, and that line does not count towards --max-runs."""
    from bayestribo.campaign.fitting import RunOutcome

    watch, stream = _watch(tmp_path, max_runs=2)
    kept, lost = tmp_path / "kept.csv", tmp_path / "lost.csv"
    for path in (kept, lost):
        watch._answer(path, _fitted(path.stem))
        watch._announced[path] = True
    assert not watch._finished(kept, _fitted("kept"))  # saved and recorded: said once
    failed = RunOutcome("lost", 1, None, "fitted but not saved or recorded: OSError: full")
    assert watch._finished(lost, failed)
    lines = stream.getvalue().splitlines()
    assert [line.split()[0] for line in lines] == ["kept", "lost", "FAILED"]
    assert "fitted but not saved or recorded" in lines[-1]
    assert watch.n_answered == 2
    assert not watch.answers[str(lost)].ok and watch.answers[str(kept)].ok
    # a run never announced (read back from the catalog) is answered when it finishes
    assert watch._finished(tmp_path / "cached.csv", _fitted("cached"))
    assert watch.n_answered == 3
