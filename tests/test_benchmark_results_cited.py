"""Every file in ``benchmarks/results/`` is cited, and every cited one exists.

A result is *cited* when its file name appears in ``README.md``,
``benchmarks/README.md``, ``docs/``, ``tests/`` or ``notebooks/``, alone or at the
end of a path (``results/NAME.json``), or when a glob written there matches it
(``coarse_placements_*.json``; not one that starts with ``*``). A script that writes
a result does not cite it: the file is regenerable and is kept only where a reader is
sent to it.

A name in ``README.md`` or ``benchmarks/README.md`` is a *citation of a result*
when its path ends in ``results/``, or when it is a bare name that starts with the
name of the benchmark script that writes it (``benchmarks/NAME.py`` writes
``NAME.json`` and ``NAME_*.json``); a bare name no script writes (``run.json``, a
run's sidecar) is about something else. Names with placeholders (``<name>.json``,
``{law}.json``) are patterns of the text, not citations.
"""

from __future__ import annotations

import fnmatch
import re
from collections.abc import Iterable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
READMES = (ROOT / "README.md", ROOT / "benchmarks" / "README.md")
CITING = (*READMES, ROOT / "docs", ROOT / "tests", ROOT / "notebooks")
TEXT_SUFFIXES = {".md", ".py", ".ipynb", ".txt", ".rst"}

# a file name with the extensions benchmarks write, alone or at the end of a path
NAME = re.compile(r"[\w*./<>{}-]*[\w*<>{}-]\.(?:jsonl|json|png)(?![\w])")


def _texts(paths: Iterable[Path], skip: Path | None = None) -> list[str]:
    """Read every text file of ``paths`` (files, or folders walked recursively)."""
    out = []
    for path in paths:
        files = [path] if path.is_file() else sorted(path.rglob("*"))
        for file in files:
            if file.is_file() and file.suffix in TEXT_SUFFIXES and file != skip:
                out.append(file.read_text(encoding="utf-8", errors="replace"))
    return out


def _names(text: str) -> list[str]:
    """The file names ``text`` mentions, with their paths, placeholders dropped."""
    return [m.group(0) for m in NAME.finditer(text) if not re.search(r"[<>{}]", m.group(0))]


def uncited(results: Path, texts: Iterable[str]) -> list[str]:
    """Files of ``results`` that no name or glob in ``texts`` cites."""
    cited = {name.rsplit("/", 1)[-1] for text in texts for name in _names(text)}
    # a glob cites the files of one stem (``laws_*.json``), not every file (``*.json``)
    globs = [name for name in cited if "*" in name and not name.startswith("*")]
    return sorted(
        f.name
        for f in results.iterdir()
        if f.is_file()
        and f.name not in cited
        and not any(fnmatch.fnmatchcase(f.name, g) for g in globs)
    )


def dangling(results: Path, texts: Iterable[str], scripts: Iterable[str]) -> list[str]:
    """Citations of a result in ``texts`` that name no file of ``results``.

    ``scripts`` are the names of the benchmark scripts (without ``.py``); a bare name
    is a citation of a result when it starts with one of them.
    """
    stems = sorted(scripts, key=len, reverse=True)
    present = [f.name for f in results.iterdir() if f.is_file()]
    missing = set()
    for text in texts:
        for name in _names(text):
            folder, _, base = name.rpartition("/")
            if folder:
                is_result = folder == "results" or folder.endswith("/results")
            else:
                is_result = any(re.match(rf"{re.escape(s)}(?:[_.*]|$)", base) for s in stems)
            if is_result and not any(fnmatch.fnmatchcase(p, base) for p in present):
                missing.add(name)
    return sorted(missing)


def _scripts() -> list[str]:
    return [p.stem for p in (ROOT / "benchmarks").glob("*.py") if not p.name.startswith("_")]


def test_every_result_is_cited() -> None:
    stray = uncited(RESULTS, _texts(CITING, skip=Path(__file__).resolve()))
    assert not stray, (
        f"benchmarks/results/ holds files nothing cites: {stray}; cite each where its "
        "figures are quoted (benchmarks/README.md), or git rm it (its script writes it again)"
    )


def test_every_cited_result_exists() -> None:
    missing = dangling(RESULTS, _texts(READMES), _scripts())
    assert not missing, (
        f"README.md or benchmarks/README.md cites results that do not exist: {missing}"
    )


def test_the_checks_find_a_stray_and_a_missing_file(tmp_path: Path) -> None:
    results = tmp_path / "results"
    results.mkdir()
    for name in ("fit.json", "fit_before_abc1234.json", "sbc_ranks.png", "laws_3.json"):
        (results / name).write_text("{}")
    text = (
        "From `fit.json` and `results/sbc_ranks.png`; every level in `laws_*.json`; "
        "a run's sidecar `run.json`; `benchmarks/results/<name>.json`, `results/*.json`; "
        "gone: `fit_after.json`, `results/other.json`, `sbc_check_*.json`."
    )
    assert uncited(results, [text]) == ["fit_before_abc1234.json"]
    assert dangling(results, [text], ["fit", "sbc", "laws"]) == [
        "fit_after.json",
        "results/other.json",
        "sbc_check_*.json",
    ]
