"""A full disk leaves no file cut short: each output is its previous content, absent, or
whole, no temporary is left, and the message names the file it was writing.

The disk fills after a budget of bytes: every byte the package writes from Python goes
through :func:`os.write` (``bayestribo._files``), which is patched to write what fits and
then fail with ``ENOSPC``; the netCDF C library, which writes by itself, is charged the
same way (its file cut where the budget ends). Each command runs once with room to
spare to learn the bytes it writes, then with budgets that end half way and one byte
before its end (the first with a previous version of every output, the second without).
"""

from __future__ import annotations

import csv
import errno
import importlib
import io
import json
import os
import re
import shutil
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from _paths import RUNS

from bayestribo.cli import main
from bayestribo.io import read_run

PREVIOUS = b"the previous version\n"
_REAL_WRITE = os.write


class FullDisk:
    """``os.write`` and ``to_netcdf`` on a device with ``budget`` bytes free."""

    def __init__(self, budget: int) -> None:
        self.budget = budget
        self.written = 0

    def write(self, fd: int, data: bytes) -> int:
        room = self.budget - self.written
        if room <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        n = _REAL_WRITE(fd, bytes(memoryview(data)[:room]))
        self.written += n
        return n

    def netcdf(self, real: Callable[..., object]) -> Callable[..., object]:
        def to_netcdf(idata: object, filename: str, *args: object, **kwargs: object) -> object:
            out = real(idata, filename, *args, **kwargs)
            size = os.path.getsize(filename)
            room = self.budget - self.written
            if size > room:
                os.truncate(filename, max(room, 0))  # what fitted before the disk was full
                self.written = self.budget
                raise OSError(errno.ENOSPC, "No space left on device")
            self.written += size
            return out

        return to_netcdf


@pytest.fixture
def on_disk(monkeypatch, capsys) -> Callable[[list[str], int], tuple[int, str, int]]:
    """Run the command line with ``budget`` bytes free: (status, stderr, bytes written)."""

    def run(argv: list[str], budget: int) -> tuple[int, str, int]:
        disk = FullDisk(budget)
        capsys.readouterr()
        with monkeypatch.context() as m:
            m.setattr(os, "write", disk.write)
            if "arviz" in sys.modules:  # a command that writes fits has it loaded
                data = sys.modules["arviz"].InferenceData
                m.setattr(data, "to_netcdf", disk.netcdf(data.to_netcdf))
            status = main([str(a) for a in argv])
        return status, capsys.readouterr().err, disk.written

    return run


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.suffix != ".sqlite" and not p.name.startswith(".bayestribo")
    }


def _whole(path: Path) -> None:
    """Fail unless ``path`` is a whole file of its kind."""
    suffix = path.suffix
    if suffix in (".json", ".ipynb"):
        json.loads(path.read_text(encoding="utf-8"))
    elif suffix == ".csv" and path.with_suffix(".json").is_file():
        read_run(path, validate=False)  # a run: its sidecar's sample count and SHA-256
    elif suffix == ".csv":
        text = path.read_text(encoding="utf-8")
        rows = list(csv.reader(io.StringIO(text)))
        assert text == "" or (text.endswith("\n") and len({len(r) for r in rows}) == 1), path
    elif suffix == ".png":
        from PIL import Image

        with Image.open(path) as image:
            image.load()
    elif suffix == ".nc":
        from bayestribo.inference import FitResult

        FitResult.load(path)
    elif suffix == ".pdf":
        data = path.read_bytes()
        assert data.startswith(b"%PDF") and data.rstrip().endswith(b"%%EOF"), path
    elif suffix == ".html":
        assert path.read_text(encoding="utf-8").rstrip().endswith("</html>"), path
    else:
        raise AssertionError(f"no check of a whole {suffix} file ({path})")


def _named(err: str) -> Path:
    found = re.search(r"no space left on the device writing (\S+);", err)
    assert found, err
    return Path(found.group(1))


def _check(folder: Path, before: dict[str, bytes], status: int, err: str) -> None:
    """Exit 2 naming the file; it is as before; every other file as before or whole."""
    assert status == 2, err
    assert "Traceback" not in err
    left = [p for p in folder.rglob("*") if ".tmp" in p.name]
    assert left == [], left
    target = _named(err)
    after = _files(folder)
    if target.resolve().is_relative_to(folder.resolve()):
        relative = str(target.resolve().relative_to(folder.resolve()))
        assert after.get(relative) == before.get(relative), relative
        if relative in before:
            assert f"{target} is its previous version, whole" in err
        else:
            assert f"no file {target} was made" in err
    else:  # a file of the command's own elsewhere (a temporary folder's summary)
        assert not target.exists() or target.read_bytes() == PREVIOUS
    for name, content in after.items():
        if content != before.get(name):
            _whole(folder / name)


def _budgets(total: int) -> Iterator[int]:
    yield from sorted({total // 2, total - 1})


def _at_start_and_end(total: int) -> Iterator[int]:
    yield from (0, total - 1)


def _run_full(
    on_disk: Callable[[list[str], int], tuple[int, str, int]],
    tmp_path: Path,
    argv: Callable[[Path], list[str]],
    prepare: Callable[[Path], None] = lambda folder: None,
    budgets: Callable[[int], Iterator[int]] = _budgets,
) -> None:
    """The command's outputs once with room, then on full disks, with and without a
    previous version of each."""
    reference = tmp_path / "outR"  # as long as the others: paths written in files
    reference.mkdir()
    prepare(reference)
    status, err, total = on_disk(argv(reference), 1 << 40)
    assert status != 2, err
    names = set(_files(reference))
    assert names and total > 0
    for k, budget in enumerate(budgets(total)):
        folder = tmp_path / f"out{k}"
        folder.mkdir()
        prepare(folder)
        if k % 2 == 0:  # a previous version of every output
            for name in names:
                (folder / name).parent.mkdir(parents=True, exist_ok=True)
                (folder / name).write_bytes(PREVIOUS)
        before = _files(folder)
        status, err, _ = on_disk(argv(folder), budget)
        _check(folder, before, status, err)


def test_simulate(on_disk, tmp_path: Path) -> None:
    _run_full(
        on_disk,
        tmp_path,
        lambda folder: [
            "simulate",
            folder / "run.csv",
            "--seed",
            1,
            "--sample-rate",
            2000,
            "--motion-duration",
            0.2,
        ],
    )


def test_a_simulated_run_cut_in_its_sidecar_keeps_the_previous_pair(on_disk, tmp_path) -> None:
    def simulate(path: Path, seed: int, budget: int) -> tuple[int, str, int]:
        argv = ["simulate", path, "--seed", seed, "--sample-rate", 2000]
        return on_disk([*argv, "--motion-duration", 0.1], budget)

    (tmp_path / "ref").mkdir()
    assert simulate(tmp_path / "ref" / "run.csv", 2, 1 << 40)[0] == 0
    csv_size = (tmp_path / "ref" / "run.csv").stat().st_size
    folder = tmp_path / "out"
    folder.mkdir()
    assert simulate(folder / "run.csv", 1, 1 << 40)[0] == 0
    before = _files(folder)
    # another run: its CSV is written whole, its sidecar is not
    status, err, _ = simulate(folder / "run.csv", 2, csv_size + 40)
    _check(folder, before, status, err)
    assert f"writing {folder / 'run.json'}" in err
    assert _files(folder) == before  # the pair as it was: neither file renamed
    assert read_run(folder / "run.csv", validate=False).n_samples > 0


_CAMPAIGN = ["--max-steps", 200, "--population-steps", 200, "--quiet", "--workers", 1]


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> tuple[Path, Path]:
    """A small campaign: its runs' folder (two bundled runs) and its output folder."""
    runs = tmp_path_factory.mktemp("runs")
    for name in ("glycerol-N0.07-r1", "glycerol-N0.59-r1"):
        for suffix in (".csv", ".json"):
            os.symlink(RUNS / f"{name}{suffix}", runs / f"{name}{suffix}")
    out = tmp_path_factory.mktemp("campaign") / "out"
    # 1: the short samplers do not converge
    assert main([str(a) for a in ["campaign", runs, *_CAMPAIGN, "--out", out]]) in (0, 1)
    return runs, out


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::bayestribo.errors.ConvergenceWarning")
def test_campaign(on_disk, campaign: tuple[Path, Path], tmp_path: Path) -> None:
    """A campaign that reads its fits back and writes its tables and figures again."""
    runs, first = campaign
    folder = tmp_path / "out"
    shutil.copytree(first, folder)
    before = _files(folder)
    # room for population.json and a part of the next table
    budget = len(before["population.json"]) + 100
    status, err, _ = on_disk(["campaign", runs, *_CAMPAIGN, "--out", folder], budget)
    _check(folder, before, status, err)


def test_fit_out(on_disk, campaign: tuple[Path, Path], tmp_path: Path, monkeypatch) -> None:
    """``fit --out``: the fit file (netCDF) and its three figures."""
    import bayestribo.inference
    from bayestribo.inference import FitResult

    importlib.import_module("bayestribo.inference.fitting")  # as the command does

    saved = campaign[1] / "fits" / "glycerol-N0.07-r1.nc"
    monkeypatch.setattr(bayestribo.inference, "fit", lambda *a, **k: FitResult.load(saved))
    run = RUNS / "glycerol-N0.07-r1.csv"
    # full from the first byte (in the netCDF file), and one byte before the end (in the
    # last figure)
    argv = ["fit", run, "--json", "--out"]
    _run_full(on_disk, tmp_path, lambda folder: [*argv, folder], budgets=_at_start_and_end)


_SUMMARY = {
    "name": "a run",
    "fit": {
        "parameters": {
            "zeta": {"mean": 0.0236, "interval": [0.0230, 0.0242]},
            "mu_k": {"mean": 0.0294, "interval": [0.0290, 0.0298]},
        },
        "diagnostics": {"converged": True},
    },
    "runs": {},
    "failed": {},
}


@pytest.fixture
def kernel(monkeypatch) -> None:
    """Reports without a Jupyter kernel: the notebook's writes (a figure through the
    report kit, the summary) and an HTML page of 400 kB."""
    import matplotlib

    from bayestribo.reports import kit, notebooks

    given: dict[str, object] = {}
    real_inject = notebooks.inject_parameters

    def inject(nb: object, params: dict[str, object]) -> object:
        given.clear()
        given.update(params)
        return real_inject(nb, params)

    def execute(nb: object, **kwargs: object) -> object:
        import matplotlib.pyplot as plt

        with matplotlib.rc_context():
            save = kit.setup(given.get("figure_dir"), str(given.get("figure_format", "png")))
            fig = plt.figure(figsize=(3, 2))
            fig.gca().plot([0, 1], [0, 1])
            save(fig, "decay")
            plt.close(fig)
        if given.get("summary_path"):
            kit.write_summary(given["summary_path"], _SUMMARY)
        return nb

    monkeypatch.setattr(notebooks, "inject_parameters", inject)
    monkeypatch.setattr(notebooks, "execute_notebook", execute)
    monkeypatch.setattr(notebooks, "to_html", lambda nb, **k: f"<html>{'x' * 400_000}</html>\n")


def test_report(on_disk, kernel, tmp_path: Path) -> None:
    run = RUNS / "glycerol-N0.31-r1.csv"
    _run_full(
        on_disk,
        tmp_path,
        lambda folder: [
            "report",
            run,
            "--out",
            folder / "run.html",
            "--executed",
            folder / "run.ipynb",
        ],
    )


def test_demo(on_disk, kernel, tmp_path: Path) -> None:
    _run_full(on_disk, tmp_path, lambda folder: ["demo", "--quick", "--out", folder])
