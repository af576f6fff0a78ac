"""The law cache: a private folder of generated law modules and numba's compiled code.

Each law's integrator is generated as Python source (:mod:`.integrator`) and compiled
by numba, which keeps the machine code in pickled files (an index ``.nbi`` and data
``.nbc`` per function). Loading a pickle runs code, so the cache is guarded three ways:

* the folder is the user's own and writable by no one else: created with mode 0o700,
  and not used (with a :class:`LawCacheWarning`) when it belongs to another user or
  others may write in it; every process then compiles its laws;
* a generated module is executed from the text this package generated, never read
  back from the folder (nor from a ``.pyc`` beside it); the file on disk is only what
  numba's cache is keyed to, and is rewritten when it differs;
* numba's files of a generated module are written to ``<folder>/numba`` by
  :class:`VerifiedCacheFile`, which records the SHA-256 of every file it writes in a
  ``.sha256`` file beside it and checks it before unpickling the file: a file that
  does not match (changed, truncated, or written by something else) is deleted and
  the function compiled again, never loaded.

The records live in the same folder, so they prove no more than the folder's privacy:
they catch files that this package did not write, not an attacker who can write in a
folder the checks above accept.
"""

from __future__ import annotations

import hashlib
import io
import os
import pickle
import stat
import sys
import tempfile
import threading
import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType

from numba.core import caching as numba_caching
from numba.core import config as numba_config
from numba.core.caching import IndexDataCacheFile

__all__ = ["CACHE_ENV", "LawCacheWarning", "VerifiedCacheFile", "law_cache_dir", "load_module"]

#: Environment variable naming the folder of the compiled laws (default: the user's
#: cache folder, ``$XDG_CACHE_HOME/bayestribo/laws`` or ``~/.cache/bayestribo/laws``).
CACHE_ENV = "BAYESTRIBO_CACHE_DIR"
#: Sub-folder of the law cache holding numba's index and data files.
NUMBA_FOLDER = "numba"
#: Suffix of the file recording a cache file's SHA-256.
RECORD_SUFFIX = ".sha256"


class LawCacheWarning(UserWarning):
    """The law cache folder is not private: laws are compiled in each process instead."""


_warned: set[str] = set()


def _not_private(folder: Path) -> str | None:
    """Why ``folder`` may not hold code this process will run, or None when it may."""
    try:
        info = folder.stat()
    except OSError as exc:
        return f"cannot be read ({exc.strerror or exc})"
    if not stat.S_ISDIR(info.st_mode):
        return "is not a folder"
    if hasattr(os, "geteuid") and info.st_uid != os.geteuid():
        return f"belongs to another user (uid {info.st_uid})"
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"may be written by other users (mode {stat.S_IMODE(info.st_mode):o})"
    return None


def _private_folder(folder: Path) -> bool:
    """Create ``folder`` (mode 0o700) if absent; whether it is private and writable."""
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        return False
    reason = _not_private(folder)
    if reason is not None:
        if str(folder) not in _warned:
            _warned.add(str(folder))
            warnings.warn(
                f"{folder}: the law cache folder {reason}, so its compiled code is not used "
                f"and each process compiles its laws; make it your own with mode 700 "
                f"(chmod 700), or set {CACHE_ENV} to a private folder",
                LawCacheWarning,
                stacklevel=3,
            )
        return False
    try:
        probe = tempfile.NamedTemporaryFile(dir=folder, delete=True)
        probe.close()
    except OSError:
        return False
    return True


def law_cache_dir() -> Path | None:
    """The folder where each law's integrator is written and numba caches it, or None
    when no private folder can be had (then every process compiles its laws).

    The folder and its ``numba`` sub-folder are created with mode 0o700; an existing
    folder that belongs to another user or that others may write in is not used
    (a :class:`LawCacheWarning` says so, once per folder).
    """
    base = os.environ.get(CACHE_ENV)
    if base:
        folder = Path(base)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        folder = (Path(xdg) if xdg else Path.home() / ".cache") / "bayestribo" / "laws"
    if not (_private_folder(folder) and _private_folder(folder / NUMBA_FOLDER)):
        return None
    return folder


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _record_path(path: str) -> str:
    return path + RECORD_SUFFIX


def _remove(path: str) -> None:
    for stale in (path, _record_path(path)):
        try:
            os.unlink(stale)
        except OSError:
            pass


class _Untrusted(OSError):
    """A cache file whose bytes this package did not record (removed, not loaded)."""


def _verified_bytes(path: str) -> bytes | None:
    """The bytes of a cache file when they match their record; None when there is no
    file. A file without a matching record is deleted and :class:`_Untrusted` raised."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        return None
    try:
        with open(_record_path(path), encoding="ascii") as fh:
            recorded = fh.read().strip()
    except (OSError, ValueError):
        recorded = ""
    if recorded != _digest(data):
        _remove(path)
        raise _Untrusted(f"{path}: not the file this package wrote; removed")
    return data


class VerifiedCacheFile(IndexDataCacheFile):
    """numba's index and data files of one function, written with a SHA-256 record
    beside each and read only when they match it (a file that does not is deleted,
    never loaded).

    Parameters
    ----------
    cache_path : str
        The folder of the files (the law cache's ``numba`` sub-folder).
    filename_base : str
        numba's name of the function's files (``<module>.<function>-<line>.py311``).
    source_stamp : object
        numba's stamp of the source file (its modification time and size).
    """

    def __init__(self, cache_path: str, filename_base: str, source_stamp: object) -> None:
        super().__init__(cache_path, filename_base, source_stamp)
        # only a law cache's files are verified: a function of another module compiled
        # while a law is loaded keeps numba's own files
        self._verified = os.path.abspath(cache_path) in _LAW_FOLDERS

    def _write(self, path: str, data: bytes) -> None:
        with self._open_for_write(path) as fh:
            fh.write(data)
        record = _record_path(path)
        tmp = f"{record}.{os.getpid()}.tmp"
        with open(tmp, "w", encoding="ascii") as fh:
            fh.write(_digest(data) + "\n")
        os.replace(tmp, record)

    def _load_index(self) -> dict:
        if not self._verified:
            return super()._load_index()
        try:
            data = _verified_bytes(self._index_path)
        except _Untrusted:
            return {}
        if data is None:
            return {}
        stream = io.BytesIO(data)
        version = pickle.load(stream)
        if version != self._version:
            return {}
        stamp, overloads = pickle.loads(stream.read())
        return overloads if stamp == self._source_stamp else {}

    def _save_index(self, overloads: dict) -> None:
        if not self._verified:
            return super()._save_index(overloads)
        data = pickle.dumps(self._version, protocol=-1)
        self._write(self._index_path, data + self._dump((self._source_stamp, overloads)))

    def _load_data(self, name: str) -> object:
        if not self._verified:
            return super()._load_data(name)
        path = self._data_path(name)
        data = _verified_bytes(path)  # _Untrusted is an OSError: numba compiles again
        if data is None:
            raise FileNotFoundError(path)
        return pickle.loads(data)

    def _save_data(self, name: str, data: object) -> None:
        if not self._verified:
            return super()._save_data(name, data)
        self._write(self._data_path(name), self._dump(data))


#: The law caches' ``numba`` folders in use (absolute paths).
_LAW_FOLDERS: set[str] = set()
_SWAP = threading.Lock()


class _LawCacheLocator(numba_caching._SourceFileBackedLocatorMixin, numba_caching._CacheLocator):
    """numba's cache locator for a generated law module: its files in ``<folder>/numba``."""

    def __init__(self, py_func: object, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno  # type: ignore[attr-defined]
        self._cache_path = os.path.join(os.path.dirname(py_file), NUMBA_FOLDER)

    def get_cache_path(self) -> str:
        return self._cache_path

    @classmethod
    def from_function(cls, py_func: object, py_file: str) -> _LawCacheLocator | None:
        folder = os.path.join(os.path.dirname(os.path.abspath(py_file)), NUMBA_FOLDER)
        if folder not in _LAW_FOLDERS:
            return None
        return super().from_function(py_func, py_file)


@contextmanager
def _law_caching(folder: Path) -> Iterator[None]:
    """While a law module is executed (its functions decorated, some compiled), numba
    locates their caches in ``folder/numba`` and reads and writes them through
    :class:`VerifiedCacheFile`; each function keeps both after."""
    _LAW_FOLDERS.add(os.path.abspath(folder / NUMBA_FOLDER))
    impl = numba_caching.CacheImpl
    with _SWAP:
        locators, file_class = impl._locator_classes, numba_caching.IndexDataCacheFile
        impl._locator_classes = [_LawCacheLocator, *locators]
        numba_caching.IndexDataCacheFile = VerifiedCacheFile
        try:
            yield
        finally:
            impl._locator_classes, numba_caching.IndexDataCacheFile = locators, file_class


def load_module(
    name: str, text: str, folder: Path | None, namespace: Mapping[str, object] | None = None
) -> ModuleType:
    """Execute generated source as the module ``name``, its file kept in ``folder``.

    The file ``folder/<name>.py`` is (re)written when it differs from ``text``: numba
    keys its cache to it. The module is executed from ``text`` itself, its compiled
    functions cached in ``folder/numba`` through :class:`VerifiedCacheFile`.

    Parameters
    ----------
    name : str
        Module name (registered in ``sys.modules``: numba finds a function's module by
        name).
    text : str
        The module's source.
    folder : Path or None
        The law cache (:func:`law_cache_dir`), or None for a new temporary folder
        (nothing cached across processes).
    namespace : mapping, optional
        Names set in the module before it is executed (compiled functions that cannot
        be imported by name).

    Returns
    -------
    ModuleType
        The executed module.
    """
    if folder is not None and numba_config.CACHE_LOCATOR_CLASSES:
        # numba's locators chosen in the environment (NUMBA_CACHE_LOCATOR_CLASSES) would
        # put the files where they are not verified: compiled in this process only
        text, folder = text.replace("cache=True", "cache=False"), None
    if folder is None:
        folder = Path(tempfile.mkdtemp(prefix="bayestribo-law-"))
    path = folder / f"{name}.py"
    try:
        current = path.read_text(encoding="utf-8") if path.is_file() else None
    except (OSError, UnicodeDecodeError):
        current = None
    if current != text:
        # written whole under another name, then renamed: a concurrent process
        # reads either no file or the whole one
        tmp = folder / f".{name}.{os.getpid()}.tmp"
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    module = ModuleType(name)
    module.__file__ = str(path)
    module.__dict__.update(namespace or {})
    sys.modules[name] = module
    code = compile(text, str(path), "exec")  # the text generated here, not the file
    (folder / NUMBA_FOLDER).mkdir(mode=0o700, exist_ok=True)
    with _law_caching(folder):
        exec(code, module.__dict__)
    return module
