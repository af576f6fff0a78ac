"""One entry to read a run from any supported file, and one to write it.

``read_run(path, metadata={...})`` picks the reader from the file suffix (or
``file_format=``), reads the JSON sidecar beside the file when there is one, lets
the given metadata fill or override it, builds a :class:`~bayestribo.io.run.Run` and
checks it with :func:`~bayestribo.io.validation.validate_run`. ``write_run`` writes
the canonical CSV and its sidecar, which read back identically. ``as_run`` is the one
place where "a run or a file" becomes a :class:`~bayestribo.io.run.Run`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._files import atomic_path
from bayestribo._warnings import warn
from bayestribo.errors import BayestriboError, ReadingWarning, RecordingError, RunFormatError
from bayestribo.io.acceleration import integrated_signals
from bayestribo.io.high_pass import undone as high_pass_undone
from bayestribo.io.options import READ_OPTIONS, ReadOptions, unknown_options
from bayestribo.io.pendulum_arm import as_angle
from bayestribo.io.registry import FileFormat, check_content, format_for, registered_formats
from bayestribo.io.run import ACCELERATIONS, ANGULAR, DISPLACEMENT, TIME, VELOCITY, Run
from bayestribo.io.sidecar import (
    DATA_FILE,
    check_data_file,
    data_record,
    file_sha256,
    read_sidecar,
    sidecar_path,
    write_sidecar,
)
from bayestribo.io.stamped_lines import START_TIME
from bayestribo.io.text import FILE_COLUMNS, PREAMBLE_RATE, StatedRate, write_csv
from bayestribo.io.validation import on_one_clock, validate_run, without_repeated_samples

__all__ = ["READ_OPTIONS", "ReadOptions", "as_run", "format_of", "read_run", "write_run"]


def format_of(path: str | Path, file_format: str | None = None) -> str:
    """The name of the format a file is read as: ``file_format`` if given, else by suffix.

    Raises
    ------
    RunFormatError
        For an unknown format or suffix, listing the known ones.
    """
    return format_for(path, file_format).name


def read_run(
    path: str | Path,
    *,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
    sample_rate_Hz: float | None = None,
    delimiter: str | None = None,
    decimal: str = ".",
    skip_rows: int = 0,
    encoding: str | None = None,
    group: str | None = None,
    channels: Mapping[str, Any] | None = None,
    sheet: str | int | None = None,
    file_format: str | None = None,
    sidecar: bool | str | Path = True,
    validate: bool = True,
    metadata: Mapping[str, Any] | None = None,
    window: tuple[float, float] | None = None,
    options: ReadOptions | None = None,
    **unexpected: Any,
) -> Run:
    """Read one run from a file.

    Parameters
    ----------
    path : str or Path
        A file of a registered format (:func:`bayestribo.io.registry.registered_formats`,
        ``bayestribo inspect --formats``): canonical CSV, other delimited text (``.csv
        .txt .dat .tsv .asc .prn``), the text exports of oscilloscopes and DAQ software
        recognised by their preamble (Tektronix, Keysight/Agilent, Rigol, PicoScope CSV
        and LabVIEW ``.lvm``, see :mod:`bayestribo.io.instruments`), Excel (``.xlsx``),
        UFF 58/58b (``.uff .unv .uf .58``), TDMS (``.tdms``), MATLAB (``.mat``, v4 to
        v7.3), HDF5 (``.h5 .hdf5``, the ``hdf5`` extra), WAV (``.wav``,
        :mod:`bayestribo.io.wav`) or NumPy (``.npz .npy``,
        :mod:`bayestribo.io.numpy_files`).
    columns : list of str, optional
        Text files, spreadsheets and ``.npy`` arrays: one canonical name (``time_s``,
        ``displacement_m``, ``velocity_m_per_s``) or ``"ignore"`` per column, in file
        order. Needed when the file has no canonical header row.
    scale : mapping, optional
        Factor per canonical name converting the file's unit to s, m or m/s, e.g.
        ``{"displacement_m": 1e-3}`` for millimetres.
    sample_rate_Hz : float, optional
        The sample rate [Hz] of a file without a time column (an encoder's angles one per
        line, a column of displacements): sample i is at t = i / rate. Without it, the
        sidecar's ``sample_rate_Hz`` is used, else a rate the file's preamble states
        (``Sample rate: 1 kHz``, said with a ``ReadingWarning``); a stated rate that
        disagrees with the one given is refused naming both. For a file with a time column it is the
        run's ``sample_rate_Hz``, which must agree with the time stamps.
    delimiter, decimal, skip_rows
        Text files: column separator (default: guessed), decimal mark (default: a point,
        or a comma found in a file delimited otherwise), lines to skip.
    encoding : str, optional
        Text files: the text encoding (``"cp1252"``, ``"latin-1"``, ...). Default UTF-8,
        and a file that is not UTF-8 is read as Windows-1252 (µ as the byte 0xB5, the
        8-bit encoding of most lab software) with a
        :class:`~bayestribo.errors.ReadingWarning` saying so.
    group : str, optional
        TDMS, HDF5: the group holding the channels.
    channels : mapping, optional
        TDMS: channel name per canonical name (required). UFF: record index per
        canonical name (when the records' types are ambiguous). MATLAB, HDF5, NumPy
        ``.npz``: variable, dataset or array name per column name (a key may carry a
        unit, ``"displacement_um"``), when the names are not canonical. WAV: channel
        number from 0 per column name (required).
    sheet : str or int, optional
        Spreadsheets: the worksheet, by name or position from 0 (needed when several
        hold numbers).
    file_format : str, optional
        A registered format (``"text"``, ``"xlsx"``, ``"uff"``, ``"tdms"``, ``"mat"``,
        ``"hdf5"``, ``"wav"``, ``"npz"``, or one added with
        :func:`~bayestribo.io.registry.register_format`); overrides the choice by suffix.
    sidecar : bool or path
        Read the JSON sidecar with the file's stem if it exists (``True``), do not
        (``False``), or read this sidecar file (which must exist). A sidecar that
        records its data file (``data_file``: sample count and SHA-256, written by the
        package) has the file checked against it.
    validate : bool
        Run the data checks of :func:`~bayestribo.io.validation.validate_run`.
    metadata : mapping, optional
        Metadata that fill or override the sidecar's, e.g.
        ``{"load_N": 0.31, "length_unit": "arbitrary"}``.
    window : (float, float), optional
        Keep the samples with ``t0 <= t <= t1`` [s] only (``--window T0:T1``): a part
        of the record holding one free decay. Recorded in the metadata (``window_s``);
        the checks of ``validate`` apply to the part kept.
    options : ReadOptions, optional
        All of the above as one object (:class:`~bayestribo.io.options.ReadOptions`),
        as the command line and the fitting functions pass them; options given as
        keywords too override its.

    Returns
    -------
    Run
        With ``source`` set to the path.

    Raises
    ------
    RunFormatError
        For a file or sidecar that cannot be read as its format, naming the file, line
        or field and what was expected.
    DataFileMismatchError
        (a ``RunFormatError``) For a file that is not the one its sidecar records (cut
        short, or a value changed): the samples recorded and found, the checksums.
    BayestriboError
        For a keyword argument that is not an option (a misspelt ``delimeter=``, or a
        metadata key given as a keyword instead of in ``metadata=``).
    RecordingError
        For data that fail the checks (NaN, irregular time, clipping, units...).
        A missing file or sidecar is a ``RunFormatError`` too, so that one ``except``
        of the package's errors covers every bad input.

    Examples
    --------
    A two-column text file of time [s] and position in an unknown unit:

    >>> run = read_run("HarmOsc1.txt", columns=["time_s", "displacement_m"],
    ...                metadata={"length_unit": "arbitrary"})  # doctest: +SKIP
    """
    if unexpected:
        raise unknown_options(unexpected)
    given = {
        "columns": columns,
        "scale": scale,
        "sample_rate_Hz": sample_rate_Hz,
        "delimiter": delimiter,
        "decimal": None if decimal == "." else decimal,
        "skip_rows": skip_rows or None,
        "encoding": encoding,
        "group": group,
        "channels": channels,
        "sheet": sheet,
        "file_format": file_format,
        "sidecar": None if sidecar is True else sidecar,
        "validate": None if validate else validate,
        "metadata": metadata,
        "window": window,
    }
    opts = ReadOptions.of(options, **{k: v for k, v in given.items() if v is not None})
    return _read(Path(path), opts)


def _read(path: Path, opts: ReadOptions) -> Run:
    where = str(path)
    if not path.is_file():
        raise RunFormatError("no such run file; expected an existing file", where)
    fmt = format_for(path, opts.file_format)
    if opts.file_format is None:
        check_content(path, fmt)  # a binary file under a text suffix, named as what it is
    for option in opts.format_options():
        if option not in fmt.options:
            takes = [f.name for f in registered_formats().values() if option in f.options]
            raise RunFormatError(
                f"option {option!r} applies to {' and '.join(takes)} files, not to a "
                f"{fmt.name} file",
                where,
            )
    sidecar = opts.sidecar
    metadata = opts.metadata
    validate = opts.validate
    meta: dict[str, Any] = {}
    side = None
    if sidecar is True:
        side = sidecar_path(path)
        if side.is_file() and side != path:
            meta.update(read_sidecar(side))
    elif sidecar is not False:
        side = Path(sidecar)
        if not side.is_file():
            raise RunFormatError("no such sidecar file; expected an existing file", str(side))
        meta.update(read_sidecar(side))
    signals = _checked_signals(fmt, path, opts, meta.pop(DATA_FILE, None), side)
    stated = signals.pop(PREAMBLE_RATE, None)  # the rate a text's preamble states
    file_columns = signals.pop(FILE_COLUMNS, None)  # a text's names, with several axes
    start = signals.pop(START_TIME, None)  # the first of a text's time stamps
    if start is not None:
        meta[START_TIME] = start
    angular = [name for name in ANGULAR if signals.get(name) is not None]
    meta.update(metadata or {})
    if angular:
        signals = _as_rotation(signals, angular, meta, where)
    if opts.sample_rate_Hz is not None:
        rate = _rate(opts.sample_rate_Hz, "sample_rate_Hz", where)
        given = (metadata or {}).get("sample_rate_Hz")
        if given is not None and given != rate:
            raise RunFormatError(
                f"sample_rate_Hz is {rate!r} Hz but metadata gives {given!r} Hz; give one",
                where,
            )
        meta["sample_rate_Hz"] = rate
    time = signals.get(TIME)
    implicit = time is None
    origin = ""  # where the sample rate of a file without a time column comes from
    if implicit:
        time, origin = _implicit_time(signals, meta, path, stated, _rate_origin(opts, path))
    elif stated is not None:
        _check_stated_rate(time, stated, where)
    if any(signals.get(name) is not None for name in ACCELERATIONS):
        signals = _integrated(signals, time, meta, opts.window, where, file_columns)
    run = Run(
        signals.get(TIME, time),
        signals.get(DISPLACEMENT),
        signals.get(VELOCITY),
        meta,
        source=where,
    )
    del signals  # the reader's arrays: the run holds its own copies
    run = without_repeated_samples(run)  # a row written twice, read once
    run = on_one_clock(run)  # a clock that restarts within the record, continued or cut
    if opts.window is not None:
        run = _windowed(run, opts.window, where)
    run = high_pass_undone(run, where)  # a sensor's high-pass, when the metadata declare one
    run = as_angle(run, where)  # a length recorded on a pendulum, when the metadata say so
    if validate:
        try:
            validate_run(run)
        except RecordingError as exc:
            note = _rate_note(run, exc.message, origin, stated) if implicit else None
            if note is None:
                raise
            raise RecordingError(f"{exc.message}; {note}", exc.where) from None
    return run


def _rate_note(run: Run, message: str, origin: str, stated: StatedRate | None) -> str | None:
    """What a refusal of a run without a time column says of its sample rate, or None
    where the refusal is not one a wrong rate makes: an implausible frequency (a rate
    wrong by a factor makes the frequency wrong by it) or channels that disagree (the
    integral of the velocity wrong by it: the rate that makes them agree is named).
    Where the rate is a preamble's, the fix of a wrong one is named as well (the
    samples' rate given and the preamble's line left out)."""
    rate = float(run.metadata["sample_rate_Hz"])
    if "plausibility" in message:
        note = (
            f"the time stamps here are i / {rate:g} Hz, from {origin}: a rate wrong by a "
            "factor gives a frequency wrong by the same factor"
        )
    elif " disagree: the displacement is " in message:
        from bayestribo.signal.channels import channel_consistency

        found = channel_consistency(run)
        if found is None or not (math.isfinite(found.gain) and found.gain > 0):
            return None
        note = (
            f"the time stamps here are i / {rate:g} Hz, from {origin}: a rate wrong by a "
            "factor makes the integral of the velocity wrong by the same factor, and at "
            f"{rate / found.gain:.4g} Hz the channels agree"
        )
    else:
        return None
    if stated is not None and origin == str(stated):
        note += (
            "; if the preamble's is not the samples' rate, give theirs, sample_rate_Hz=HZ "
            f"(--sample-rate HZ), and leave the preamble's line out with skip_rows={stated.skip}"
        )
    return note


def _integrated(
    signals: Mapping[str, Any],
    time: NDArray,
    meta: dict[str, Any],
    window: tuple[float, float] | None,
    where: str,
    file_columns: list[str] | None = None,
) -> dict[str, Any]:
    """The columns with an acceleration integrated into the velocity
    (:func:`bayestribo.io.acceleration.integrated_signals`), over the ``window`` only
    when one is given (the part of the record that holds the free decay); an angular
    velocity so made is read as a rotation's."""
    signals = {**signals, TIME: time}
    if window is not None:
        keep = (time >= window[0]) & (time <= window[1])
        if int(keep.sum()) >= 2:
            signals = {
                name: (value[keep] if isinstance(value, np.ndarray) else value)
                for name, value in signals.items()
            }
    out = integrated_signals(signals, meta, where, file_columns)
    angular = [name for name in ANGULAR if out.get(name) is not None]
    if angular:
        out = _as_rotation(out, angular, meta, where)
    return out


def _as_rotation(
    signals: Mapping[str, Any], angular: list[str], meta: dict[str, Any], where: str
) -> dict[str, Any]:
    """A rotational rig's columns (angle [rad], angular velocity [rad/s]) as the run's
    displacement and velocity, with ``length_unit`` ``"rad"`` in ``meta``.

    Raises
    ------
    RunFormatError
        When the file holds a linear column beside an angular one, or the metadata
        state another length unit.
    """
    linear = [name for name in (DISPLACEMENT, VELOCITY) if signals.get(name) is not None]
    if linear:
        raise RunFormatError(
            f"columns {angular} are angles and {linear} lengths: one run is a rotation or a "
            "translation; name the columns of one (columns=[...], 'ignore' for the other)",
            where,
        )
    stated = meta.get("length_unit")
    if stated not in (None, "rad"):
        raise RunFormatError(
            f"the columns {angular} are angles but the metadata give length_unit "
            f"{stated!r}; expected 'rad' (or none) for a rotation",
            where,
        )
    meta["length_unit"] = "rad"
    out = {name: value for name, value in signals.items() if name not in ANGULAR}
    for name in angular:
        out[ANGULAR[name]] = signals[name]
    return out


def _windowed(run: Run, window: tuple[float, float], where: str) -> Run:
    """The samples of ``run`` with ``t0 <= t <= t1``, the window in its metadata."""
    keep = (run.time >= window[0]) & (run.time <= window[1])
    t0, t1 = window
    if keep.any():  # an open end is the record's own
        t0, t1 = max(t0, float(run.time[keep][0])), min(t1, float(run.time[keep][-1]))
    if int(keep.sum()) < 2:
        raise RunFormatError(
            f"window ({t0:g} s, {t1:g} s) holds {int(keep.sum())} sample(s); the record "
            f"spans {run.time[0]:g} s to {run.time[-1]:g} s",
            where,
        )
    return Run(
        run.time[keep],
        None if run.displacement is None else run.displacement[keep],
        None if run.velocity is None else run.velocity[keep],
        {**run.metadata, "window_s": [t0, t1]},
        source=run.source,
    )


def _rate(value: Any, name: str, where: str) -> float:
    """A sample rate [Hz]: a finite number > 0."""
    try:
        rate = float(value)
    except (TypeError, ValueError, OverflowError):
        rate = math.nan
    if isinstance(value, bool) or not math.isfinite(rate) or rate <= 0.0:
        raise RunFormatError(f"{name}: expected a sample rate in Hz > 0, got {value!r}", where)
    return rate


#: A sample rate given and the one the preamble states agree within this (relative): a
#: preamble rounds its rate (``Sample rate: 3.333 kHz``), a wrong rate is off by far more.
_GIVEN_AGREES = 1e-3
#: A preamble's rate and the time stamps' agree within this (relative).
_STAMPS_AGREE = 0.01


def _rate_origin(opts: ReadOptions, path: Path) -> str:
    """Where a sample rate given for a file comes from, in words for messages."""
    if opts.sample_rate_Hz is not None:
        return "the sample rate given (sample_rate_Hz, --sample-rate)"
    if (opts.metadata or {}).get("sample_rate_Hz") is not None:
        return "the metadata's sample_rate_Hz"
    sidecar = opts.sidecar
    if sidecar is False:
        return "the sample_rate_Hz given"
    side = sidecar_path(path) if sidecar is True else Path(str(sidecar))
    return f"the sample_rate_Hz of the sidecar {side.name}"


def _implicit_time(
    signals: Mapping[str, NDArray],
    meta: dict[str, Any],
    path: Path,
    stated: StatedRate | None = None,
    origin: str = "the sample rate given (sample_rate_Hz, --sample-rate)",
) -> tuple[NDArray, str]:
    """The time stamps i / rate [s] of a file without a time column, and where the rate
    comes from (for messages).

    The rate is the one given (``sample_rate_Hz``: the option, the metadata or the
    sidecar, already in ``meta``), else the one the file's preamble states (``stated``:
    the :class:`~bayestribo.io.text.StatedRate` a text reader returns under
    :data:`~bayestribo.io.text.PREAMBLE_RATE`), which is then set in ``meta`` and said
    with a :class:`~bayestribo.errors.ReadingWarning`.

    Parameters
    ----------
    signals : mapping
        The reader's columns, by canonical name (no time).
    meta : dict
        The run's metadata, updated with the preamble's rate when it is the one used.
    path : Path
        The file, for messages.
    stated : StatedRate, optional
        The sample rate the file's preamble states.
    origin : str
        Where a rate in ``meta`` comes from, in words.

    Returns
    -------
    time : ndarray
        i / rate [s].
    origin : str
        Where the rate comes from, in words.

    Raises
    ------
    RunFormatError
        When no sample rate is known, saying how to give one; when the rate given and
        the preamble's differ by more than 0.1 %, naming both.
    """
    where = str(path)
    rate = meta.get("sample_rate_Hz")
    n = max(np.size(v) for name, v in signals.items() if name != TIME)
    if rate is None and stated is not None:
        rate = meta["sample_rate_Hz"] = stated.rate_Hz
        origin = str(stated)
        warn(
            f"{where}: no time column: t = i / {rate:g} Hz, the sample rate from {origin}; "
            f"if it is not the samples' rate, give theirs with sample_rate_Hz=HZ and leave "
            f"the preamble's line out with skip_rows={stated.skip}",
            ReadingWarning,
        )
        return np.arange(n, dtype=np.float64) / rate, origin
    if rate is None:
        raise RunFormatError(
            f"the file has no time column: give its sample rate, sample_rate_Hz=HZ "
            f'(--sample-rate HZ), or "sample_rate_Hz" in the sidecar '
            f"{sidecar_path(path).name}; sample i is then at t = i / rate [s] "
            f"({n} samples read)",
            where,
        )
    rate = _rate(rate, "sample_rate_Hz", where)
    if stated is not None and abs(rate - stated.rate_Hz) > _GIVEN_AGREES * stated.rate_Hz:
        raise RunFormatError(
            f"the file has no time column and {origin} is {rate:g} Hz but {stated} states "
            f"{stated.rate_Hz:g} Hz; correct the one that is wrong (skip_rows={stated.skip}, "
            "--skip-rows, leaves the preamble's line out)",
            where,
        )
    return np.arange(n, dtype=np.float64) / rate, origin


def _check_stated_rate(time: NDArray, stated: StatedRate, where: str) -> None:
    """Refuse a time column whose median step disagrees by more than 1 % with the
    sample rate the preamble states.

    Raises
    ------
    RunFormatError
        Naming the preamble's line and both rates.
    """
    steps = np.diff(np.asarray(time, dtype=np.float64))
    steps = steps[np.isfinite(steps) & (steps > 0.0)]
    if steps.size == 0:
        return  # no time step to compare: the run's checks name the time column
    rate = 1.0 / float(np.median(steps))
    if abs(rate - stated.rate_Hz) > _STAMPS_AGREE * stated.rate_Hz:
        raise RunFormatError(
            f"{stated} states a sample rate of {stated.rate_Hz:g} Hz but the time column's "
            f"stamps are {rate:g} Hz apart (median step {1.0 / rate:g} s); the time column or "
            "its unit is wrong, or the preamble: name the columns with columns=[...] "
            f"(the time column's unit, or 'ignore' to take t = i / rate), or leave the "
            f"preamble's line out with skip_rows={stated.skip} (--skip-rows)",
            where,
        )


def _checked_signals(
    fmt: FileFormat,
    path: Path,
    opts: ReadOptions,
    record: Mapping[str, Any] | None,
    side: Path | None,
) -> dict[str, Any]:
    """The reader's signals, the file checked against its sidecar's ``data_file`` record
    (:func:`~bayestribo.io.sidecar.check_data_file`) when there is one.

    Raises
    ------
    DataFileMismatchError
        When the file is not the one the record describes (a file that the reader
        cannot read either is named by this error, not the reader's).
    """
    if record is None:
        return dict(_call_reader(fmt, path, opts))
    digest = file_sha256(path) if "sha256" in record else None
    intact = digest is not None and digest == record["sha256"]
    try:
        signals = dict(_call_reader(fmt, path, opts))
    except BayestriboError:
        if not intact:
            check_data_file(path, record, None, sidecar=side, sha256=digest)
        raise
    if not intact:
        check_data_file(path, record, _sample_count(signals), sidecar=side, sha256=digest)
    return signals


def _sample_count(signals: Mapping[str, Any]) -> int:
    """The number of samples a reader returned: its longest column."""
    sizes = [
        np.size(v)
        for k, v in signals.items()
        if k not in (PREAMBLE_RATE, FILE_COLUMNS, START_TIME) and v is not None
    ]
    return int(max(sizes, default=0))


def _call_reader(fmt: FileFormat, path: Path, opts: ReadOptions) -> Mapping[str, Any]:
    """``fmt.read``, with any failure of a library it uses made the package's error.

    A reader names what is wrong where it can (a line, a channel, a unit); what a
    third-party library raises on a damaged file (h5py's ``RuntimeError``, scipy's
    ``MatReadError``, an XML parser's error) becomes a
    :class:`~bayestribo.errors.RunFormatError` naming the file, the format and the
    library's message, the original exception chained for a bug report. A claim of
    more memory than there is (a header with a huge size) is refused the same way.
    """
    try:
        return fmt.read(path, opts)
    except BayestriboError:
        raise
    except MemoryError:
        raise RunFormatError(
            f"the file is not a readable {fmt.title} file: it claims more data than fits in memory",
            str(path),
        ) from None
    except RecursionError:
        raise RunFormatError(
            f"the file is not a readable {fmt.title} file: its structure nests too deep",
            str(path),
        ) from None
    except Exception as exc:  # the reader's libraries on a damaged file
        raise RunFormatError(
            f"the file is not a readable {fmt.title} file ({type(exc).__name__}: {str(exc)[:200]})",
            str(path),
        ) from exc


def as_run(
    run: Run | str | os.PathLike[str],
    options: ReadOptions | Mapping[str, Any] | None = None,
    **read_options: Any,
) -> Run:
    """The one conversion of "a run or a file" into a :class:`~bayestribo.io.run.Run`.

    Parameters
    ----------
    run : Run, str or path-like
        A run, returned as it is, or a file read with :func:`read_run`.
    options : ReadOptions or mapping, optional
        How to read a file (:class:`~bayestribo.io.options.ReadOptions`, or a mapping of
        its option names).
    **read_options
        Options of :func:`read_run` (:data:`READ_OPTIONS`) overriding ``options``.

    Returns
    -------
    Run

    Raises
    ------
    BayestriboError
        If ``run`` is neither a Run nor a path, if reading options are given with a
        Run (they would be ignored), or if an option is unknown.
    """
    opts = ReadOptions.of(options, **read_options)
    if isinstance(run, Run):
        given = opts.as_kwargs()
        if given:
            raise BayestriboError(
                f"reading options {sorted(given)} apply to a file, but run is "
                "already a Run; read the file with these options, or drop them"
            )
        return as_angle(high_pass_undone(on_one_clock(without_repeated_samples(run))))
    if isinstance(run, str | os.PathLike):
        return _read(Path(run), opts)
    raise BayestriboError(
        f"run: expected a bayestribo Run or the path of a run file, got {type(run).__name__}"
    )


def write_run(run: Run, path: str | Path) -> Path:
    """Write a run in the canonical format: ``path`` (CSV) and its JSON sidecar.

    Parameters
    ----------
    run : Run
        The run to write (its ``source`` is not written).
    path : str or Path
        The ``.csv`` file; the sidecar is the same path with suffix ``.json``.

    Returns
    -------
    Path
        The CSV path. ``read_run(path)`` gives a run equal to ``run``. The sidecar
        records the CSV's sample count and SHA-256 (``data_file``), which
        :func:`read_run` checks. Both files are whole: a failure (a full disk) leaves
        the previous pair, or none.

    Raises
    ------
    RunFormatError
        If the path does not end in ``.csv``.
    """
    path = Path(path)
    if path.suffix.lower() != ".csv":
        raise RunFormatError(
            f"the canonical run file is a .csv file; got suffix {path.suffix!r}", str(path)
        )
    # both written in full under temporary names before either is renamed into place
    # (the CSV first): a failure leaves the previous pair, or none
    with atomic_path(sidecar_path(path)) as side, atomic_path(path) as csv:
        write_csv(run.signals, csv)
        write_sidecar(run.metadata, side, data=data_record(csv, run.n_samples))
    return path
