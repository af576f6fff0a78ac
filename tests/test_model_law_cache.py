"""The law cache runs only code this package wrote: a private folder, verified files.

numba keeps compiled code in pickles, and loading a pickle runs code: a cache file this
package did not write (changed, or put there) is deleted and compiled again, never
loaded; a folder that others may write in is not used at all.
"""

from __future__ import annotations

import os
import pickle
import stat
from pathlib import Path

import pytest

from bayestribo.model.laws import cache as cache_module
from bayestribo.model.laws.cache import (
    CACHE_ENV,
    NUMBA_FOLDER,
    RECORD_SUFFIX,
    LawCacheWarning,
    law_cache_dir,
    load_module,
)

# A function compiled while its module is executed (as the template's tables are) and
# one compiled at its first call.
SOURCE = """
import numba

@numba.njit(cache=True)
def table(n):
    return n * 2.0

TABLE = table(3)

@numba.njit(cache=True)
def f(x):
    return x + TABLE
"""


class _Opens:
    """Unpickled, it creates the file it names: proof that a pickle was loaded."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def __reduce__(self):
        return (open, (str(self.path), "w"))


def _load(folder: Path, name: str):
    module = load_module(name, SOURCE, folder)
    value = module.f(1.0)
    hits = sum(module.f.stats.cache_hits.values())
    misses = sum(module.f.stats.cache_misses.values())
    return value, hits, misses


def test_a_cache_file_changed_after_it_was_written_is_compiled_again_never_loaded(
    tmp_path, monkeypatch
):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "laws"))
    folder = law_cache_dir()
    assert folder is not None
    name = f"bayestribo_law_test_{os.getpid()}"
    assert _load(folder, name) == (7.0, 0, 1)  # compiled, written with its records
    assert _load(folder, name) == (7.0, 1, 0)  # loaded: its records match
    files = sorted((folder / NUMBA_FOLDER).glob(f"{name}.*.nb[ic]"))
    assert len(files) == 4 and all(Path(f"{p}{RECORD_SUFFIX}").is_file() for p in files)
    marker = tmp_path / "loaded"
    for path in files:
        path.write_bytes(pickle.dumps(_Opens(marker)))
    assert _load(folder, name) == (7.0, 0, 1)  # compiled again
    assert not marker.exists()  # no changed file was unpickled
    for path in files:  # written again by this package, with records that match
        record = Path(f"{path}{RECORD_SUFFIX}").read_text().strip()
        assert record == cache_module._digest(path.read_bytes())
    assert _load(folder, name) == (7.0, 1, 0)


def test_a_cache_file_without_a_record_is_removed_unread(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "laws"))
    folder = law_cache_dir()
    assert folder is not None
    name = f"bayestribo_law_norecord_{os.getpid()}"
    _load(folder, name)
    [index] = (folder / NUMBA_FOLDER).glob(f"{name}.f-*.nbi")
    Path(f"{index}{RECORD_SUFFIX}").unlink()  # a file put there by something else
    marker = tmp_path / "loaded"
    index.write_bytes(pickle.dumps(_Opens(marker)))
    assert _load(folder, name) == (7.0, 0, 1)
    assert not marker.exists()


def test_the_cache_folder_is_made_private(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "new" / "laws"))
    folder = law_cache_dir()
    assert folder == tmp_path / "new" / "laws"
    for path in (folder, folder / NUMBA_FOLDER):
        assert stat.S_IMODE(path.stat().st_mode) == 0o700


@pytest.mark.skipif(not hasattr(os, "geteuid"), reason="POSIX owners and modes")
@pytest.mark.parametrize("case", ["others may write", "another user's"])
def test_a_cache_folder_that_is_not_private_is_not_used(tmp_path, monkeypatch, case):
    shared = tmp_path / "shared"
    shared.mkdir()
    if case == "others may write":
        shared.chmod(0o777)
        reason = "may be written by other users"
    else:
        monkeypatch.setattr(cache_module.os, "geteuid", lambda: shared.stat().st_uid + 1)
        reason = "belongs to another user"
    monkeypatch.setenv(CACHE_ENV, str(shared))
    with pytest.warns(LawCacheWarning, match=rf"{shared}: the law cache folder {reason}"):
        assert law_cache_dir() is None
    assert not (shared / NUMBA_FOLDER).exists()
