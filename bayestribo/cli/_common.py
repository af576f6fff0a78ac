"""Arguments shared by the commands that read one run."""

from __future__ import annotations

import argparse
import math
import re
from typing import Any

from bayestribo.errors import BayestriboError


class CommandLineError(BayestriboError):
    """A command's input is wrong; the message gives the fix as command-line options."""


__all__ = [
    "COLUMN_ALIASES",
    "CommandLineError",
    "add_notch_option",
    "add_reading_options",
    "add_run_arguments",
    "cli_message",
    "read_run_from_args",
    "reading_kwargs",
    "reading_options",
]

#: Short names accepted by ``--columns``.
COLUMN_ALIASES = {"t": "time_s", "x": "displacement_m", "v": "velocity_m_per_s", "-": "ignore"}


def add_run_arguments(parser: argparse.ArgumentParser, *, optional: bool = False) -> None:
    """Add RUN (optional if ``optional``) and the options that describe a file."""
    parser.add_argument(
        "run",
        metavar="RUN",
        nargs="?" if optional else None,
        help="run file: canonical CSV, other text, an oscilloscope or DAQ export (Tektronix, "
        "Keysight/Agilent, Rigol, PicoScope CSV, LabVIEW .lvm), Excel .xlsx, UFF, TDMS, .mat, "
        "HDF5, WAV or NumPy .npz/.npy (bayestribo inspect --formats lists them)",
    )
    add_reading_options(parser)


def add_reading_options(parser: argparse.ArgumentParser) -> None:
    """Add the options that describe a run file, each said to apply to the registered
    formats that take it (:func:`bayestribo.io.registry.format_table`: no reader is
    imported to build them)."""
    from bayestribo.io.registry import format_table

    formats = format_table()

    def only(option: str, text: str) -> str:
        takes = [f.name for f in formats.values() if option in f.options]
        return f"{', '.join(takes)} files: {text}"

    parser.add_argument(
        "--columns",
        nargs="+",
        metavar="NAME",
        help=only(
            "columns",
            "the role of each column in file order, comma or space separated: "
            "time_s, displacement_m, velocity_m_per_s or ignore (short: t, x, v, -), or a "
            "quantity with its unit (time_ms, displacement_um, velocity_mm_per_s, ...)",
        ),
    )
    parser.add_argument(
        "--length-unit",
        choices=("m", "arbitrary", "rad"),
        help="length unit of the signals (arbitrary: friction as a displacement only; rad: "
        "angles in radians, friction as an angle, and as a torque with the sidecar's "
        "inertia_kg_m2; columns named angle_deg, angular_velocity_rad_per_s, ... say so "
        "themselves)",
    )
    parser.add_argument(
        "--skip-rows",
        type=int,
        default=0,
        metavar="N",
        help=only("skip_rows", "lines (rows) to skip at the top (an instrument's preamble)"),
    )
    parser.add_argument(
        "--delimiter",
        metavar="D",
        help=only("delimiter", "column separator (',', ';', 'tab' or 'space'; default: guessed)"),
    )
    parser.add_argument(
        "--decimal",
        choices=(".", ","),
        default=".",
        help=only("decimal", "decimal mark (',' for European exports)"),
    )
    parser.add_argument(
        "--encoding",
        metavar="NAME",
        help=only(
            "encoding",
            "the text encoding (cp1252, latin-1, ...); default UTF-8, and Windows-1252, "
            "said, for a file that is not UTF-8",
        ),
    )
    parser.add_argument(
        "--scale",
        action="append",
        metavar="NAME=FACTOR",
        help="multiply a column by FACTOR to convert it to s, m or m/s, e.g. x=1e-3 for "
        "millimetres (repeatable; NAME as in --columns)",
    )
    parser.add_argument(
        "--sample-rate",
        type=_positive_rate,
        metavar="HZ",
        help="sample rate [Hz] of a file without a time column (sample i at t = i/HZ); "
        "with a time column it must agree with the time stamps",
    )
    parser.add_argument(
        "--window",
        type=_window,
        metavar="T0:T1",
        help="analyse only the samples from T0 to T1 [s] (either may be left out: "
        "'12:' from 12 s on), e.g. to leave out a disturbance or a second release",
    )
    parser.add_argument(
        "--channel",
        action="append",
        metavar="NAME=SOURCE",
        help=only(
            "channels",
            "the channel, variable or dataset holding a column, e.g. x=Disp or "
            "displacement_um=data.x (repeatable; NAME as in --columns); UFF: the record index",
        ),
    )
    parser.add_argument(
        "--group",
        metavar="GROUP",
        help=only("group", "the group holding the channels"),
    )
    parser.add_argument(
        "--sheet",
        metavar="NAME|N",
        help=only(
            "sheet",
            "the worksheet holding the run, by name or position from 0 (needed when "
            "several hold numbers)",
        ),
    )
    parser.add_argument(
        "--format",
        choices=tuple(formats),
        help="file format, when the suffix does not say it: "
        + "; ".join(f"{f.name}: {f.hint or f.title}" for f in formats.values()),
    )
    parser.add_argument("--frequency", type=float, help="nominal natural frequency f [Hz]")
    parser.add_argument("--load", type=float, help="normal load N [N]")
    parser.add_argument("--mass", type=float, help="oscillating mass m [kg]")
    from bayestribo.model.restoring import AUTO, restoring_table

    restoring = restoring_table()
    parser.add_argument(
        "--restoring",
        choices=(*restoring, AUTO),
        help="the oscillator's restoring force (sidecar 'restoring'): "
        + "; ".join(f"{name}: {description}" for name, description in restoring.items())
        + f"; {AUTO}: chosen by the fit from how the half period changes with the swing "
        "(constant: linear; as a pendulum's, in radians: pendulum; else duffing). The "
        "energy lost per cycle from the turning points takes its potential",
    )
    parser.add_argument(
        "--pendulum-radius",
        type=_pendulum_radius,
        metavar="R|simple",
        help="the displacement is x = R sin θ of a pendulum's angle θ, recorded at R [m] "
        "from the pivot (a video-tracked bob, a laser on its arm; sidecar "
        "'pendulum_radius_m'): read as the angle θ = arcsin(x/R) in radians, friction "
        "as an angle, fitted with --restoring pendulum unless another is named; 'simple' "
        "for a simple pendulum's bob, R = g/ω₀² from the record's period (an assumption, "
        "said in the output)",
    )
    from bayestribo.signal.sensor_kinds import sensor_kind_table

    kinds = sensor_kind_table()
    parser.add_argument(
        "--sensor-kind",
        choices=tuple(kinds),
        help="the kind of sensor (sidecar 'sensor_kind'), whose typical gain uncertainty "
        "the fit draws into every length where the sidecar states no 'gain_uncertainty': "
        + "; ".join(f"{k.name}: {100 * k.gain_uncertainty:.1f} %%" for k in kinds.values())
        + " (default: 1.0 %%; the output says which it took)",
    )

    parser.add_argument(
        "--sensor-high-pass",
        type=_high_pass,
        metavar="HZ[:ORDER[:DAMPING]]",
        help="the sensor passes no DC (an AC-coupled channel, a geophone, a piezoelectric "
        "sensor; sidecar 'sensor_high_pass'): its analog high-pass, corner HZ, ORDER 1 (an "
        "RC coupling, the default) or 2 (a geophone, with its DAMPING, default 0.707), is "
        "undone on every channel when the run is read, its drift measured at rest; "
        "said in the output",
    )


def _positive(text: str, expected: str, keyword: str | None = None) -> float | str:
    """A finite number > 0 from ``text``, or ``keyword`` itself; else an
    :class:`argparse.ArgumentTypeError` saying what was ``expected``."""
    if keyword is not None and text == keyword:
        return text
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0.0:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return value


def _positive_rate(text: str) -> float:
    """``--sample-rate`` value: a sample rate [Hz] > 0."""
    return float(_positive(text, "a sample rate in Hz > 0"))


def _pendulum_radius(text: str) -> float | str:
    """``--pendulum-radius`` value: a radius [m] > 0, or ``simple``."""
    return _positive(
        text, "the pendulum's radius at the sensor in metres (> 0), or simple", "simple"
    )


def _high_pass(text: str) -> dict[str, Any]:
    """``--sensor-high-pass`` value ``HZ[:ORDER[:DAMPING]]`` as a declaration
    (:func:`bayestribo.signal.high_pass.check_high_pass`)."""
    from bayestribo.signal.high_pass import check_high_pass

    parts = [p.strip() for p in re.split("[:,]", text)]
    try:
        if not 1 <= len(parts) <= 3:
            raise ValueError("expected HZ, HZ:ORDER or HZ:2:DAMPING")
        spec: dict[str, Any] = {"cutoff_Hz": float(parts[0])}
        if len(parts) > 1:
            spec["order"] = int(parts[1])
        if len(parts) > 2:
            spec["damping"] = float(parts[2])
        return check_high_pass(spec)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(
            f"expected HZ[:ORDER[:DAMPING]] (e.g. 0.5 for one pole at 0.5 Hz, 4.5:2:0.7 for a "
            f"geophone), got {text!r}: {exc}"
        ) from None


def _window(text: str) -> tuple[float, float]:
    """``--window`` value ``T0:T1`` [s]; an end left out is open (``12:``, ``:40``)."""
    start, sep, stop = text.partition(":")
    try:
        if not sep:
            raise ValueError
        t0 = float(start) if start.strip() else -math.inf
        t1 = float(stop) if stop.strip() else math.inf
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected T0:T1 in seconds (e.g. 2.5:40, or 12: from 12 s on), got {text!r} "
            "(the length of bayestribo check's windows is --window-length N)"
        ) from None
    if math.isnan(t0) or math.isnan(t1) or not t0 < t1:
        raise argparse.ArgumentTypeError(f"expected T0 < T1, got {text!r}")
    return t0, t1


def notch_value(text: str) -> float | str:
    """``--notch`` value: a frequency [Hz] or ``auto``."""
    return _positive(text, "a frequency in Hz (50, 60) or auto", "auto")


def add_notch_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--notch``: remove a mains line measured at rest before the analysis."""
    parser.add_argument(
        "--notch",
        type=notch_value,
        metavar="HZ|auto",
        help="subtract the mains line (50, 60) measured at rest from both channels, or the "
        "line found in the rest spectrum (auto); zero-phase, no delay",
    )


def columns_from_args(values: list[str] | None) -> list[str] | None:
    """Expand ``--columns`` values (aliases, comma lists) to canonical names."""
    if values is None:
        return None
    names = [c for v in values for c in v.split(",") if c]
    return [COLUMN_ALIASES.get(c, c) for c in names]


_DELIMITER_NAMES = {"tab": "\t", "\\t": "\t", "space": None, "whitespace": None}


def _scale_from_args(values: list[str] | None) -> dict[str, float] | None:
    """``--scale NAME=FACTOR`` options as a mapping of canonical names to factors."""
    if not values:
        return None
    out: dict[str, float] = {}
    for item in values:
        name, sep, factor = item.partition("=")
        try:
            value = float(factor)
        except ValueError:
            value = None
        if not sep or not name or value is None:
            raise CommandLineError(
                f"--scale: expected NAME=FACTOR (e.g. x=1e-3 for millimetres), got {item!r}"
            )
        out[COLUMN_ALIASES.get(name, name)] = value
    return out


def _channels_from_args(values: list[str] | None) -> dict[str, Any] | None:
    """``--channel NAME=SOURCE`` options as a mapping of column names to sources."""
    if not values:
        return None
    out: dict[str, Any] = {}
    for item in values:
        name, sep, source = item.partition("=")
        if not sep or not name or not source:
            raise CommandLineError(f"--channel: expected NAME=SOURCE (e.g. x=Disp), got {item!r}")
        name = COLUMN_ALIASES.get(name, name)
        out[name] = int(source) if source.isdigit() else source
    return out


def reading_options(args: argparse.Namespace) -> Any:
    """The :class:`~bayestribo.io.options.ReadOptions` of :func:`add_reading_options`.

    Raises
    ------
    CommandLineError
        For an option value that is not valid, naming the option.
    """
    from bayestribo.io.options import ReadOptions

    kwargs: dict[str, Any] = {}
    columns = columns_from_args(args.columns)
    if columns is not None:
        kwargs["columns"] = columns
    if args.skip_rows:
        kwargs["skip_rows"] = args.skip_rows
    if args.delimiter is not None:
        kwargs["delimiter"] = _DELIMITER_NAMES.get(args.delimiter, args.delimiter)
    if args.decimal != ".":
        kwargs["decimal"] = args.decimal
    if getattr(args, "encoding", None):
        kwargs["encoding"] = args.encoding
    scale = _scale_from_args(args.scale)
    if scale is not None:
        kwargs["scale"] = scale
    if getattr(args, "sample_rate", None) is not None:
        kwargs["sample_rate_Hz"] = args.sample_rate
    if getattr(args, "window", None) is not None:
        kwargs["window"] = args.window
    channels = _channels_from_args(getattr(args, "channel", None))
    if channels is not None:
        kwargs["channels"] = channels
    if getattr(args, "group", None) is not None:
        kwargs["group"] = args.group
    sheet = getattr(args, "sheet", None)
    if sheet is not None:
        kwargs["sheet"] = int(sheet) if sheet.isdigit() else sheet
    if args.format is not None:
        kwargs["file_format"] = args.format
    metadata = {
        key: value
        for key, value in (
            ("length_unit", args.length_unit),
            ("natural_frequency_Hz", args.frequency),
            ("load_N", args.load),
            ("mass_kg", args.mass),
            ("restoring", getattr(args, "restoring", None)),
            ("pendulum_radius_m", getattr(args, "pendulum_radius", None)),
            ("sensor_kind", getattr(args, "sensor_kind", None)),
            ("sensor_high_pass", getattr(args, "sensor_high_pass", None)),
        )
        if value is not None
    }
    if metadata:
        kwargs["metadata"] = metadata
    return ReadOptions(**kwargs)


def reading_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """The options of :func:`reading_options` as keyword arguments (JSON-ready)."""
    return reading_options(args).as_kwargs()


#: Python spellings in reading errors and the command-line options that do the same.
_CLI_SPELLINGS = (
    (
        "read_run(path, columns=['time_s', 'displacement_mm'])",
        "--columns time_s displacement_mm",
    ),
    ("length_unit='arbitrary'", "--length-unit arbitrary"),
    ("sample_rate_Hz=HZ (--sample-rate HZ)", "--sample-rate HZ"),
    ("columns=[...]", "--columns"),
    ("columns=", "--columns "),
    ("give file_format=", "give --format"),
    ("give sheet= (--sheet)", "give --sheet"),
    ("scale={...}", "--scale NAME=FACTOR"),
    ("scale=", "--scale "),
    ("channels={'time_s': 't', 'displacement_m': 'x'}", "--channel t=t --channel x=x"),
    ("channels={...}", "--channel NAME=SOURCE"),
    ("channels=", "--channel "),
    ("group=...", "--group GROUP"),
    ("group=", "--group "),
    ("skip_rows", "--skip-rows"),
)


def cli_message(message: str) -> str:
    """A reading error's message with its fixes spelled as command-line options."""
    message = _ONE_CHANNEL.sub(
        lambda m: f"--channel {_SHORT.get(m[1], m[1])}={m[2].strip()}", message
    )
    message = _CHANNEL_MAP.sub(_channel_options, message)
    message = _SKIP_ROWS.sub(r"--skip-rows \1", message)
    for python, option in _CLI_SPELLINGS:
        if python == "columns=[...]":
            # a list of column names given in full: the option with its values
            message = _COLUMN_LIST.sub(_columns_option, message)
        if python == "scale={...}":
            message = _SCALE_MAP.sub(_scale_options, message)
        message = message.replace(python, option)
    return message


#: ``skip_rows=N`` with the option named beside it (``skip_rows=2, --skip-rows,`` and
#: ``skip_rows=2 (--skip-rows)``), spelled as the option with its value once.
_SKIP_ROWS = re.compile(r"skip_rows=(\d+)(?:, --skip-rows,| \(--skip-rows\))?")

#: ``columns=['time_s', 'ignore', ...]``, spelled as a ``--columns`` option.
_COLUMN_LIST = re.compile(r"columns=\[('[^'\]]*'(?:, '[^'\]]*')*)\]")
_SHORT = {name: short for short, name in COLUMN_ALIASES.items()}


def _columns_option(match: re.Match[str]) -> str:
    names = re.findall(r"'([^']*)'", match[1])
    return "--columns " + " ".join(_SHORT.get(n, n) for n in names)


#: ``scale={'time_s': 0.001, ...}``, spelled as ``--scale`` options.
_SCALE_MAP = re.compile(r"scale=\{('\w+': [-+.\deE]+(?:, '\w+': [-+.\deE]+)*)\}")


def _scale_options(match: re.Match[str]) -> str:
    pairs = re.findall(r"'(\w+)': ([-+.\deE]+)", match[1])
    return " ".join(f"--scale {_SHORT.get(name, name)}={value}" for name, value in pairs)


#: ``channels={'name': source}`` with one entry, spelled as a ``--channel`` option.
_ONE_CHANNEL = re.compile(r"channels=\{'(\w+)': '?([^,}']+)'?\}")

#: ``channels={'time_s': 'rec.t', 'displacement_m': 'rec.x_mm'}``, spelled as
#: ``--channel`` options.
_CHANNEL_MAP = re.compile(r"channels=\{('\w+': '[^',}]+'(?:, '\w+': '[^',}]+')+)\}")


def _channel_options(match: re.Match[str]) -> str:
    pairs = re.findall(r"'(\w+)': '([^',}]+)'", match[1])
    return " ".join(f"--channel {_SHORT.get(name, name)}={source}" for name, source in pairs)


def read_run_from_args(args: argparse.Namespace, options: Any = None) -> Any:
    """Read the run named by :func:`add_run_arguments` options (or read as ``options``
    say, a :class:`~bayestribo.io.options.ReadOptions`: a fit specification's).

    Raises
    ------
    CommandLineError
        For a file that cannot be read as described, with the fix spelled as
        command-line options.
    """
    from bayestribo.errors import BayestriboError
    from bayestribo.io import as_run

    try:
        return as_run(args.run, reading_options(args) if options is None else options)
    except BayestriboError as exc:
        raise CommandLineError(cli_message(str(exc))) from None
