"""The file formats runs are read from: one protocol and one registry.

A format is a :class:`FileFormat`: its name, the suffixes that select it, the
format-specific reading options it takes, a ``read`` function from a path and
:class:`~bayestribo.io.options.ReadOptions` to the signals, a ``describe`` function for
``bayestribo inspect``, and the optional extra it needs. The format list, the check of
which option applies to which file, ``inspect``, and the command line's ``--format``
choices and help all come from here.

What a format is (:class:`FormatInfo`: name, title, suffixes, options, extra, hint) is
kept apart from the code that reads it. The registry holds the description of every
registered format and imports a built-in format's module, with its reader and the
libraries behind it, only when a file is read or described in it: the command line
builds its options from :func:`format_table` without importing any reader (nor numpy),
and a suffix lookup imports the one module that takes the suffix.

A new built-in format is one module defining ``FORMAT`` (the reader, built from its
description with :meth:`FileFormat.builtin`) and one entry in :data:`BUILTIN_FORMATS`;
one defined elsewhere (a lab's own file layout) is one :func:`register_format` call::

    from bayestribo.io.registry import FileFormat, register_format

    def read_rig(path, options):
        ...  # return {"time_s": t, "displacement_m": x}

    register_format(FileFormat("rig", "our rig's binary log", (".rig",), read_rig))
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bayestribo.errors import BayestriboError, RunFormatError
from bayestribo.io.options import FORMAT_OPTIONS, ReadOptions

if TYPE_CHECKING:
    from numpy.typing import NDArray

__all__ = [
    "BUILTIN_FORMATS",
    "BUILTIN_MODULES",
    "SIGNATURE_BYTES",
    "FileFormat",
    "FormatInfo",
    "check_content",
    "format_for",
    "format_table",
    "get_format",
    "register_format",
    "registered_formats",
]

Reader = Callable[[Path, ReadOptions], Mapping[str, "NDArray"]]
Describer = Callable[[Path, ReadOptions], Mapping[str, Any]]


def _check_description(
    kind: str,
    name: str,
    suffixes: tuple[str, ...],
    options: tuple[str, ...],
    signature: bytes = b"",
) -> None:
    """Refuse a format's name, suffixes, options or signature that the registry cannot
    take."""
    if not name or name != name.lower() or not name.isidentifier():
        raise BayestriboError(f"{kind} name: expected a lower-case identifier, got {name!r}")
    for suffix in suffixes:
        if not suffix.startswith(".") or suffix != suffix.lower():
            raise BayestriboError(
                f"{kind} {name!r} suffixes: expected lower-case suffixes starting with '.', "
                f"got {suffix!r}"
            )
    bad = [o for o in options if o not in FORMAT_OPTIONS]
    if bad:
        raise BayestriboError(
            f"{kind} {name!r} options: {bad} are not format options; expected some of "
            f"{', '.join(FORMAT_OPTIONS)}"
        )
    try:
        re.compile(signature, re.DOTALL)
    except (re.error, TypeError) as exc:
        raise BayestriboError(
            f"{kind} {name!r} signature: expected a regular expression over bytes ({exc})"
        ) from None


@dataclass(frozen=True)
class FormatInfo:
    """What a file format is, without its reader: all the command line and the format
    list need.

    Parameters
    ----------
    name, title, suffixes, options, extra, hint, signature
        As :class:`FileFormat`'s.
    module : str, optional
        A built-in format's module, which defines its :class:`FileFormat` as ``FORMAT``
        and is imported when a file is read or described in the format.
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    options: tuple[str, ...] = ()
    extra: str | None = None
    hint: str = ""
    module: str | None = None
    signature: bytes = b""

    def __post_init__(self) -> None:
        object.__setattr__(self, "suffixes", tuple(self.suffixes))
        object.__setattr__(self, "options", tuple(self.options))
        _check_description("FormatInfo", self.name, self.suffixes, self.options, self.signature)


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
    signature : bytes
        A regular expression (over bytes, ``.`` matching any byte) that the first
        :data:`SIGNATURE_BYTES` bytes of the format's files match, e.g.
        ``rb"\\x89HDF\\r\\n\\x1a\\n"``; empty for files without a fixed start (text). A
        file given to a built-in format without one (by its suffix) that starts as
        another format's files do is refused, naming that format
        (:func:`check_content`).
    """

    name: str
    title: str
    suffixes: tuple[str, ...]
    read: Reader
    options: tuple[str, ...] = ()
    describe: Describer | None = None
    extra: str | None = None
    hint: str = ""
    signature: bytes = b""

    def __post_init__(self) -> None:
        object.__setattr__(self, "suffixes", tuple(self.suffixes))
        object.__setattr__(self, "options", tuple(self.options))
        _check_description("FileFormat", self.name, self.suffixes, self.options, self.signature)
        if not callable(self.read):
            raise BayestriboError(f"FileFormat {self.name!r} read: expected a callable")

    @classmethod
    def builtin(cls, name: str, read: Reader, describe: Describer | None = None) -> FileFormat:
        """The built-in format ``name``: its description in :data:`BUILTIN_FORMATS`, with
        its reader (for the module that defines its ``FORMAT``)."""
        info = _BUILTIN[name]
        return cls(
            info.name,
            info.title,
            info.suffixes,
            read,
            options=info.options,
            describe=describe,
            extra=info.extra,
            hint=info.hint,
            signature=info.signature,
        )

    @property
    def info(self) -> FormatInfo:
        """What the format is, without its reader."""
        return FormatInfo(
            self.name,
            self.title,
            self.suffixes,
            self.options,
            self.extra,
            self.hint,
            signature=self.signature,
        )

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


#: The formats shipped with the package, each read by the ``FORMAT`` of its module; their
#: order is the order of ``--format`` choices and of the suffix lookup.
BUILTIN_FORMATS: tuple[FormatInfo, ...] = (
    FormatInfo(
        "text",
        "delimited text",
        (".csv", ".txt", ".dat", ".tsv", ".asc", ".prn", ".lvm"),
        ("columns", "delimiter", "decimal", "skip_rows", "encoding"),
        hint="canonical CSV, other delimited text, oscilloscope and DAQ exports (Tektronix, "
        "Keysight/Agilent, Rigol, PicoScope CSV, LabVIEW .lvm)",
        module="bayestribo.io.formats.text",
    ),
    FormatInfo(
        "xlsx",
        "Excel workbook",
        (".xlsx", ".xlsm"),
        ("columns", "skip_rows", "sheet"),
        extra="formats",
        hint="Excel .xlsx workbooks (one worksheet of samples in columns; --sheet)",
        module="bayestribo.io.formats.excel",
        signature=rb"PK\x03\x04",
    ),
    FormatInfo(
        "uff",
        "UFF 58",
        (".uff", ".unv", ".uf", ".58"),
        ("channels",),
        extra="formats",
        hint="Universal File Format data-set 58/58b (modal-analysis software)",
        module="bayestribo.io.formats.uff",
    ),
    FormatInfo(
        "tdms",
        "LabVIEW TDMS",
        (".tdms",),
        ("group", "channels"),
        extra="formats",
        hint="LabVIEW TDMS (National Instruments DAQ)",
        module="bayestribo.io.formats.tdms",
        signature=rb"TDSm",
    ),
    FormatInfo(
        "mat",
        "MATLAB .mat",
        (".mat",),
        ("channels",),
        hint="MATLAB .mat, v4 to v7.3 (v7.3 needs the hdf5 extra)",
        module="bayestribo.io.formats.matlab",
        signature=rb"MATLAB \d\.\d MAT-file",
    ),
    FormatInfo(
        "hdf5",
        "HDF5",
        (".h5", ".hdf5", ".hdf", ".he5"),
        ("group", "channels"),
        extra="hdf5",
        hint="HDF5 datasets, one per signal",
        module="bayestribo.io.formats.hdf5",
        signature=rb"\x89HDF\r\n\x1a\n",
    ),
    FormatInfo(
        "wav",
        "WAV sound",
        (".wav", ".wave"),
        ("channels",),
        hint="WAV from a sound card or audio interface (integer PCM as fractions of full "
        "scale, float as stored; --channel x=0 names what a channel holds)",
        module="bayestribo.io.formats.wav",
        signature=rb"(RIFF|RIFX|RF64)....WAVE",
    ),
    FormatInfo(
        "npz",
        "NumPy .npz/.npy",
        (".npz", ".npy"),
        ("channels", "columns"),
        hint="NumPy .npz archives of named arrays (as .mat variables), .npy arrays (--columns)",
        module="bayestribo.io.formats.numpy",
        signature=rb"\x93NUMPY|PK\x03\x04|PK\x05\x06",
    ),
)
_BUILTIN = {info.name: info for info in BUILTIN_FORMATS}

#: The built-in formats' modules, in the order of :data:`BUILTIN_FORMATS`.
BUILTIN_MODULES: tuple[str, ...] = tuple(str(info.module) for info in BUILTIN_FORMATS)

#: What every registered format is, by name, in order (the built-in ones first).
_REGISTRY: dict[str, FormatInfo] = dict(_BUILTIN)
#: The registered formats with their readers at hand: those registered with
#: :func:`register_format`, and the built-in ones whose module was imported (on first use).
_READERS: dict[str, FileFormat] = {}


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
    _REGISTRY[fmt.name] = fmt.info
    _READERS[fmt.name] = fmt
    return fmt


def format_table() -> dict[str, FormatInfo]:
    """What every registered format is, by name (the built-in ones first), without
    importing any reader: the command line's ``--format`` choices and help."""
    return dict(_REGISTRY)


def _loaded(name: str) -> FileFormat:
    """The registered format ``name``, its built-in module imported on first use."""
    fmt = _READERS.get(name)
    if fmt is None:
        fmt = _READERS[name] = importlib.import_module(str(_REGISTRY[name].module)).FORMAT
    return fmt


def registered_formats() -> Mapping[str, FileFormat]:
    """The registered formats by name (the built-in ones first), every reader imported.

    :func:`format_table` says the same without importing the readers.
    """
    return {name: _loaded(name) for name in list(_REGISTRY)}


def get_format(name: str, where: str | None = None) -> FileFormat:
    """The registered format called ``name``.

    Raises
    ------
    RunFormatError
        For a name that is not registered, listing the registered ones.
    """
    if name not in _REGISTRY:
        raise RunFormatError(
            f"file_format: expected one of {sorted(_REGISTRY)}, got {name!r}", where
        )
    return _loaded(name)


#: Suffixes of files the package does not read, with what to do instead.
#: What a Tracker project's refusal says (its positions are in pixels of the video,
#: its calibration in the project: the exported table is in the calibrated unit).
_TRACKER = (
    "a Tracker video-analysis project is not read; in Tracker, File > Export > Data "
    "writes the track's t and x (and y) as delimited text in the unit of its calibration: "
    "read that with --columns naming each with its unit (time_s, displacement_cm, ...), "
    "or with --length-unit arbitrary where the video was not calibrated (pixels)"
)
_NOT_READ = {
    ".xls": "the old binary Excel format is not read; save the sheet as .xlsx or as CSV",
    ".ods": "OpenDocument sheets are not read; save the sheet as .xlsx or as CSV",
    ".numbers": "Numbers files are not read; export the sheet as CSV",
    # the projects of a teaching lab's programs: their data are exported as text
    ".trk": _TRACKER,
    ".trz": _TRACKER,
    ".cmbl": "a Vernier Logger Pro file is not read; export its data as text (File > "
    "Export As > Text or CSV) and read that with --columns naming each column's unit",
    ".gambl": "a Vernier Graphical Analysis file is not read; export its data as CSV and "
    "read that with --columns naming each column's unit",
    ".cap": "a PASCO Capstone project is not read; export its data as CSV (File > Export "
    "Data), which is read as it is",
    ".phyphox": "a phyphox experiment file holds no measurement; export the data from "
    "the app as CSV (the menu's Export data) and read that",
}


#: Bytes from the start of a file that the formats' signatures are matched against.
SIGNATURE_BYTES = 32


def check_content(path: str | Path, fmt: FileFormat) -> None:
    """Refuse a file that its suffix gives to a built-in format without a signature
    (delimited text, UFF) but that starts as another format's files do: a WAV, NumPy
    or HDF5 file saved as ``.dat`` or ``.txt`` is named as what it is, not parsed as
    text.

    Parameters
    ----------
    path : str or Path
        The file (one that cannot be opened is left to the reader, which names it).
    fmt : FileFormat
        The format its suffix selects.

    Raises
    ------
    RunFormatError
        Naming the formats whose signature the file's first bytes match and the
        ``file_format`` that reads it.
    """
    if fmt.signature or _BUILTIN.get(fmt.name) is None:
        return  # a format with a signature of its own, or one defined elsewhere
    try:
        with open(path, "rb") as fh:
            head = fh.read(SIGNATURE_BYTES)
    except OSError:
        return
    matches = [
        info
        for info in _REGISTRY.values()
        if info.signature and re.match(info.signature, head, re.DOTALL)
    ]
    if not matches:
        return
    kinds = " or ".join(f"{info.title} ({info.name})" for info in matches)
    ways = " or ".join(f"file_format='{i.name}' (--format {i.name})" for i in matches)
    raise RunFormatError(
        f"the file is not {fmt.title}: its first bytes ({head[:12]!r}) are those of {kinds} "
        f"files; read it as one with {ways}",
        str(path),
    )


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
    formats = format_table()
    for info in formats.values():
        if suffix in info.suffixes:
            return _loaded(info.name)  # the one reader that takes the suffix
    if suffix in _NOT_READ:
        raise RunFormatError(f"unknown file type {suffix!r}: {_NOT_READ[suffix]}", where)
    known = sorted(s for info in formats.values() for s in info.suffixes)
    raise RunFormatError(
        f"unknown file type {suffix!r}; expected one of {known}; give file_format= for a "
        "file whose suffix does not say its format, or export the data as CSV (time, "
        "displacement, velocity in columns) from the program that wrote it",
        where,
    )
