"""The file formats runs are read from: one protocol and one registry.

A format is a :class:`FileFormat`: its name, the suffixes that select it, the
format-specific reading options it takes, a ``read`` function from a path and
:class:`~bayestribo.io.options.ReadOptions` to the signals, a ``describe`` function for
``bayestribo inspect``, and the optional extra it needs. The format list, the check of
which option applies to which file, ``inspect``, and the command line's ``--format``
choices and help all come from here.

A new format is one module defining ``FORMAT = FileFormat(...)`` and one registration:
its module name in :data:`BUILTIN_MODULES` for a format shipped with the package, or
:func:`register_format` for one defined elsewhere (a lab's own file layout)::

    from bayestribo.io.registry import FileFormat, register_format

    def read_rig(path, options):
        ...  # return {"time_s": t, "displacement_m": x}

    register_format(FileFormat("rig", "our rig's binary log", (".rig",), read_rig))
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io.options import FORMAT_OPTIONS, ReadOptions

__all__ = [
    "BUILTIN_MODULES",
    "FileFormat",
    "format_for",
    "get_format",
    "register_format",
    "registered_formats",
]

#: Modules of the formats shipped with the package, each defining ``FORMAT``; their
#: order is the order of ``--format`` choices and of the suffix lookup.
BUILTIN_MODULES: tuple[str, ...] = (
    "bayestribo.io.formats.text",
    "bayestribo.io.formats.excel",
    "bayestribo.io.formats.uff",
    "bayestribo.io.formats.tdms",
    "bayestribo.io.formats.matlab",
    "bayestribo.io.formats.hdf5",
)

Reader = Callable[[Path, ReadOptions], Mapping[str, NDArray]]
Describer = Callable[[Path, ReadOptions], Mapping[str, Any]]


@dataclass(frozen=True)
class FileFormat:
    """A file format runs are read from.

    Parameters
    ----------
    name : str
        The format's name (``file_format=``, ``--format``), lower case.
    title : str
        What the format is, in words (``"LabVIEW TDMS"``).
    suffixes : tuple of str
        File suffixes, lower case with the dot, that select this format.
    read : callable
        ``read(path, options) -> {canonical column name: array}``: time in s first,
        then displacement in m and/or velocity in m/s (or the file's length unit when
        the run's metadata say ``length_unit: arbitrary``); a rotation's columns as
        ``angle_rad`` and ``angular_velocity_rad_per_s`` (:data:`bayestribo.io.run.ANGULAR`),
        and a sample rate the file states as a :class:`~bayestribo.io.text.StatedRate`
        under :data:`~bayestribo.io.text.PREAMBLE_RATE`, which :func:`bayestribo.read_run`
        takes out. Raises :class:`~bayestribo.errors.RunFormatError` naming the file and
        what is wrong.
    options : tuple of str
        The format-specific options it takes, among :data:`FORMAT_OPTIONS` (``scale``,
        ``metadata`` and the sidecar apply to every format).
    describe : callable, optional
        ``describe(path, options) -> {"reader": str, "columns": [{"label", "unit"}]}``,
        how the file is read, without reading its data (``bayestribo inspect``).
        Default: the title and no columns.
    extra : str, optional
        The ``pip install 'bayestribo[EXTRA]'`` extra that installs what it needs.
    hint : str
        Help text for the format on the command line (what writes such files).
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    read: Reader
    options: tuple[str, ...] = ()
    describe: Describer | None = None
    extra: str | None = None
    hint: str = ""

    def __post_init__(self) -> None:
        if not self.name or self.name != self.name.lower() or not self.name.isidentifier():
            raise BayestriboError(
                f"FileFormat name: expected a lower-case identifier, got {self.name!r}"
            )
        object.__setattr__(self, "suffixes", tuple(self.suffixes))
        object.__setattr__(self, "options", tuple(self.options))
        for suffix in self.suffixes:
            if not suffix.startswith(".") or suffix != suffix.lower():
                raise BayestriboError(
                    f"FileFormat {self.name!r} suffixes: expected lower-case suffixes "
                    f"starting with '.', got {suffix!r}"
                )
        bad = [o for o in self.options if o not in FORMAT_OPTIONS]
        if bad:
            raise BayestriboError(
                f"FileFormat {self.name!r} options: {bad} are not format options; "
                f"expected some of {', '.join(FORMAT_OPTIONS)}"
            )
        if not callable(self.read):
            raise BayestriboError(f"FileFormat {self.name!r} read: expected a callable")

    def describe_file(self, path: Path, options: ReadOptions) -> dict[str, Any]:
        """``{"format", "reader", "columns"}`` for ``inspect``."""
        out: dict[str, Any] = {"format": self.name, "reader": self.title, "columns": []}
        if self.describe is not None:
            try:
                out.update(self.describe(path, options))
            except BayestriboError:
                raise
            except Exception as exc:  # a damaged file, as for read (io/files.py)
                raise RunFormatError(
                    f"the file is not a readable {self.title} file ({type(exc).__name__}: "
                    f"{str(exc)[:200]})",
                    str(path),
                ) from exc
        return out


_REGISTRY: dict[str, FileFormat] = {}
_LOADED = False


def _load_builtin() -> None:
    global _LOADED
    if _LOADED:
        return
    _LOADED = True
    added = []
    for module in BUILTIN_MODULES:
        fmt = importlib.import_module(module).FORMAT
        if fmt.name not in _REGISTRY:
            added.append(fmt)
    # Formats registered from outside before the first use keep their place after the
    # built-in ones.
    outside = dict(_REGISTRY)
    _REGISTRY.clear()
    for fmt in added:
        _REGISTRY[fmt.name] = fmt
    _REGISTRY.update(outside)


def register_format(fmt: FileFormat, *, replace: bool = False) -> FileFormat:
    """Add a file format to the registry.

    Parameters
    ----------
    fmt : FileFormat
        The format.
    replace : bool
        Replace a format registered under the same name (otherwise an error).

    Returns
    -------
    FileFormat
        ``fmt``, so that a module can write ``FORMAT = register_format(FileFormat(...))``.

    Raises
    ------
    BayestriboError
        If ``fmt`` is not a FileFormat, its name is taken (and ``replace`` is false), or
        one of its suffixes selects another format already.
    """
    if not isinstance(fmt, FileFormat):
        raise BayestriboError(f"fmt: expected a FileFormat, got {type(fmt).__name__}")
    _load_builtin()
    if fmt.name in _REGISTRY and not replace:
        raise BayestriboError(
            f"a file format named {fmt.name!r} is registered already; pass replace=True"
        )
    for other in _REGISTRY.values():
        clash = set(other.suffixes) & set(fmt.suffixes)
        if other.name != fmt.name and clash:
            raise BayestriboError(
                f"FileFormat {fmt.name!r}: suffix(es) {sorted(clash)} already select the "
                f"{other.name!r} format"
            )
    _REGISTRY[fmt.name] = fmt
    return fmt


def registered_formats() -> Mapping[str, FileFormat]:
    """The registered formats by name (the built-in ones first)."""
    _load_builtin()
    return dict(_REGISTRY)


def get_format(name: str, where: str | None = None) -> FileFormat:
    """The registered format called ``name``.

    Raises
    ------
    RunFormatError
        For a name that is not registered, listing the registered ones.
    """
    formats = registered_formats()
    if name not in formats:
        raise RunFormatError(f"file_format: expected one of {sorted(formats)}, got {name!r}", where)
    return formats[name]


#: Suffixes of files the package does not read, with what to do instead.
_NOT_READ = {
    ".xls": "the old binary Excel format is not read; save the sheet as .xlsx or as CSV",
    ".ods": "OpenDocument sheets are not read; save the sheet as .xlsx or as CSV",
    ".numbers": "Numbers files are not read; export the sheet as CSV",
    ".wav": "sound files are not read; export the channels as CSV",
}


def format_for(path: str | Path, file_format: str | None = None) -> FileFormat:
    """The format a file is read as: ``file_format`` if given, else from its suffix.

    Raises
    ------
    RunFormatError
        For an unknown format or suffix, listing the known ones and saying what to do.
    """
    path = Path(path)
    where = str(path)
    if file_format is not None:
        return get_format(file_format, where)
    suffix = path.suffix.lower()
    if not _LOADED:
        # nothing registered from outside yet (register_format loads the built-in
        # formats first): the built-in formats in their order, each imported only until
        # one takes the suffix, so a CSV imports none of the binary readers
        for module in BUILTIN_MODULES:
            fmt = importlib.import_module(module).FORMAT
            if suffix in fmt.suffixes:
                return fmt
    formats = registered_formats()
    for fmt in formats.values():
        if suffix in fmt.suffixes:
            return fmt
    if suffix in _NOT_READ:
        raise RunFormatError(f"unknown file type {suffix!r}: {_NOT_READ[suffix]}", where)
    known = sorted(s for fmt in formats.values() for s in fmt.suffixes)
    raise RunFormatError(
        f"unknown file type {suffix!r}; expected one of {known}; give file_format= for a "
        "file whose suffix does not say its format, or export the data as CSV (time, "
        "displacement, velocity in columns) from the program that wrote it",
        where,
    )
