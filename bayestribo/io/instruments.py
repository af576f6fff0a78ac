"""Text exports of oscilloscopes and DAQ software, recognised by their preamble.

An oscilloscope or a DAQ program writes its own lines before the samples: the model,
the sample interval, the units of each column. :func:`detect_export` recognises these
exports from their first lines and returns an :class:`InstrumentExport`: where the
column labels and the samples are, the unit of each column as the instrument wrote
it, the separator and decimal mark, and how time is given (a column of times, or a
sample index with a start and an increment). The text reader then reads the samples
and converts the time column to seconds; the channel columns are in volts, so the
sensors' sensitivities [m/V], [(m/s)/V] must be given as scale factors
(:func:`bayestribo.io.text.read_text`).

Recognised exports (the layouts documented by the vendors' manuals):

=====================  =============================================================
Tektronix              MSO/MDO/DPO 2000-6 series CSV: ``Model,…`` … ``Horizontal
                       Units,s`` … ``Vertical Units,V`` … then ``TIME,CH1,CH2``;
                       and the older TDS/TBS CSV, whose first three fields of each
                       row are the settings (``Record Length,2500,,-0.0012,0.04``)
Keysight / Agilent     InfiniiVision CSV: ``x-axis,1,2`` then ``second,Volt,Volt``
Rigol                  DS1000Z: ``X,CH1,CH2,Start,Increment,`` then
                       ``Sequence,Volt,Volt,-6e-03,2e-06`` (sample index, time =
                       Start + index × Increment); DS1000E/DS2000: ``X,CH1,`` then
                       ``Second,Volt,``
PicoScope              CSV: ``Time,Channel A,Channel B`` then ``(ms),(V),(mV)``
LabVIEW                ``.lvm`` measurement files: ``LabVIEW Measurement`` header,
                       ``Separator``, ``Decimal_Separator``, ``X_Columns`` (No, One,
                       Multi), ``X0``/``Delta_X`` per channel, one data segment
=====================  =============================================================
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.columns import IGNORE, UNITS, check_scale, parse_column
from bayestribo.io.run import COLUMNS, DISPLACEMENT, TIME, VELOCITY
from bayestribo.io.units import TIMES

__all__ = ["TIME_UNITS", "VOLT_UNITS", "InstrumentExport", "detect_export", "read_export"]

#: Time units written by instruments and their factor to seconds (lower case): the
#: package's one table.
TIME_UNITS = TIMES

#: Voltage units written by instruments and their factor to volts (lower case).
VOLT_UNITS = {"v": 1.0, "volt": 1.0, "volts": 1.0, "mv": 1e-3, "uv": 1e-6, "µv": 1e-6, "kv": 1e3}

#: How many first lines are read to recognise an export.
PREAMBLE_LINES = 200


@dataclass(frozen=True)
class InstrumentExport:
    """Layout of an instrument's text export.

    Attributes
    ----------
    vendor : str
        The recognised export, e.g. ``"Tektronix CSV"``.
    labels : list of str
        Column labels in file order, as the instrument wrote them (``TIME``, ``CH1``).
    units : list of str
        Unit of each column as written (``s``, ``ms``, ``V``, ``mV``; ``""`` when the
        export gives none; ``"index"`` for a sample-index column).
    data_line : int
        0-based index, among all lines of the file, of the first sample row.
    delimiter : str or None
        Column separator (None: white space).
    decimal : str
        Decimal mark.
    first_field : int
        Fields of each row before the first column (3 for the Tektronix TDS layout,
        whose first fields hold the settings).
    time_start, time_increment : float or None
        For a sample-index column or a file without a time column: time of sample 0
        [s] and the sample interval [s].
    implicit_time : bool
        True when the file has no time column and time is ``time_start + i ×
        time_increment`` (LabVIEW ``X_Columns No``).
    ignore : frozenset of int
        Columns that hold no signal (the extra X columns of an LVM ``X_Columns
        Multi`` file, an empty ``Comment`` column).
    """

    vendor: str
    labels: list[str]
    units: list[str]
    data_line: int
    delimiter: str | None = ","
    decimal: str = "."
    first_field: int = 0
    time_start: float | None = None
    time_increment: float | None = None
    implicit_time: bool = False
    ignore: frozenset[int] = field(default_factory=frozenset)

    @property
    def time_column(self) -> int | None:
        """Index of the time (or sample-index) column, None when time is implicit."""
        return None if self.implicit_time else 0

    def describe(self) -> str:
        """The columns as ``label [unit]``, for messages."""
        parts = [
            f"{label} [{unit}]" if unit else label
            for i, (label, unit) in enumerate(zip(self.labels, self.units, strict=True))
            if i not in self.ignore
        ]
        return ", ".join(parts)


def _separator(line: str) -> str:
    """The separator of a preamble or label line: tab, semicolon or comma."""
    if "\t" in line:
        return "\t"
    return ";" if ";" in line else ","


def _fields(line: str, delimiter: str | None = "") -> list[str]:
    """Fields of a line, unquoted; ``delimiter=""`` guesses it, None splits on spaces."""
    if delimiter == "":
        delimiter = _separator(line)
    parts = line.split() if delimiter is None else line.split(delimiter)
    return [p.strip().strip('"').strip("'").strip() for p in parts]


def _decimal(lines: Sequence[str], first: int, delimiter: str | None) -> str:
    """Decimal mark of the sample rows: ',' when the separator is not a comma and a
    sample holds one."""
    if delimiter == ",":
        return "."
    for line in lines[first : first + 5]:
        if "," in line:
            return ","
    return "."


def _number(text: str, decimal: str = ".") -> float | None:
    try:
        return float(text.replace(",", ".") if decimal == "," else text)
    except ValueError:
        return None


def _trim(fields: list[str]) -> list[str]:
    """Fields without the empty ones a trailing separator leaves."""
    while fields and fields[-1] == "":
        fields = fields[:-1]
    return fields


#: Preamble keys that mark a Tektronix CSV export after its ``Model`` line.
_TEKTRONIX_KEYS = {
    "firmware version",
    "sample interval",
    "record length",
    "horizontal units",
    "vertical units",
}


def _tektronix(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """Tektronix MSO/MDO/DPO CSV: key,value preamble then a ``TIME,CH…`` label row."""
    if not lines or _fields(lines[0])[0].lower() != "model":
        return None
    keys = {_fields(line)[0].lower() for line in lines[1:30]}
    if not keys & _TEKTRONIX_KEYS:
        return None
    settings: dict[str, list[str]] = {}
    for index, line in enumerate(lines):
        fields = _trim(_fields(line))
        if not fields:
            continue
        if fields[0].upper() == "TIME" and len(fields) >= 2:
            count = len(fields) - 1
            vertical = settings.get("vertical units", [])
            if len(vertical) == 1:
                vertical = vertical * count
            channel_units = vertical if len(vertical) == count else [""] * count
            horizontal = (settings.get("horizontal units") or ["s"])[0]
            delimiter = _separator(line)
            return InstrumentExport(
                "Tektronix CSV",
                fields,
                [horizontal, *channel_units],
                index + 1,
                delimiter=delimiter,
                decimal=_decimal(lines, index + 1, delimiter),
            )
        settings[fields[0].lower()] = fields[1:]
    raise RunFormatError(
        f"Tektronix CSV export: no 'TIME,CH…' label row within the first {len(lines)} lines",
        where,
    )


def _tektronix_tds(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """Tektronix TDS/TBS CSV: settings in the first three fields of every row."""
    if not lines:
        return None
    first = _fields(lines[0])
    if first[0].lower() != "record length" or len(first) < 5:
        return None
    settings = {}
    for line in lines:
        fields = _fields(line)
        if len(fields) >= 2 and fields[0]:
            settings[fields[0].lower()] = fields[1]
    units = [settings.get("horizontal units", "s"), settings.get("vertical units", "")]
    source = settings.get("source", "CH")
    delimiter = _separator(lines[0])
    return InstrumentExport(
        "Tektronix TDS CSV",
        ["TIME", source],
        units,
        0,
        delimiter=delimiter,
        decimal=_decimal(lines, 0, delimiter) if delimiter != "," else ".",
        first_field=3,
    )


def _keysight(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """Keysight/Agilent InfiniiVision CSV: ``x-axis,1,2`` then ``second,Volt,Volt``."""
    if len(lines) < 2:
        return None
    labels = _trim(_fields(lines[0]))
    if not labels or labels[0].lower() != "x-axis" or len(labels) < 2:
        return None
    units = _trim(_fields(lines[1]))
    if not units or units[0].lower() not in ("second", "s"):
        return None  # a header that merely starts with x-axis
    if len(units) != len(labels):
        raise RunFormatError(
            f"Keysight/Agilent CSV export: line 2 gives {len(units)} unit(s) for "
            f"{len(labels)} column(s) ({', '.join(labels)}); expected one unit per column",
            where,
        )
    delimiter = _separator(lines[0])
    return InstrumentExport(
        "Keysight/Agilent CSV",
        labels,
        units,
        2,
        delimiter=delimiter,
        decimal=_decimal(lines, 2, delimiter),
    )


def _rigol(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """Rigol CSV: ``X,CH1,…[,Start,Increment]`` then ``Sequence|Second,Volt,…``."""
    if len(lines) < 2:
        return None
    labels = _trim(_fields(lines[0]))
    if not labels or labels[0] != "X" or len(labels) < 2:
        return None
    units = _trim(_fields(lines[1]))
    if not units or units[0].lower() not in ("sequence", "second", "s"):
        return None  # a header that merely starts with X, not a Rigol export
    if labels[-2:] == ["Start", "Increment"]:
        labels = labels[:-2]
        try:
            start, increment = float(units[len(labels)]), float(units[len(labels) + 1])
        except (IndexError, ValueError):
            raise RunFormatError(
                "Rigol CSV export: line 2 does not give the Start and Increment values after "
                "the units; expected e.g. 'Sequence,Volt,-6.0e-03,2.0e-06'",
                where,
            ) from None
        units = units[: len(labels)]
        if not increment > 0:
            raise RunFormatError(
                f"Rigol CSV export: Increment must be a positive sample interval [s], got "
                f"{increment}",
                where,
            )
        if units and units[0].lower() == "sequence":
            units = ["index", *units[1:]]
        delimiter = _separator(lines[0])
        return InstrumentExport(
            "Rigol CSV",
            labels,
            units,
            2,
            delimiter=delimiter,
            decimal=_decimal(lines, 2, delimiter),
            time_start=start,
            time_increment=increment,
        )
    if len(units) != len(labels):
        raise RunFormatError(
            f"Rigol CSV export: line 2 gives {len(units)} unit(s) for {len(labels)} column(s); "
            "expected one unit per column",
            where,
        )
    delimiter = _separator(lines[0])
    return InstrumentExport(
        "Rigol CSV", labels, units, 2, delimiter=delimiter, decimal=_decimal(lines, 2, delimiter)
    )


def _picoscope(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """PicoScope CSV: ``Time,Channel A,…`` then units in parentheses ``(ms),(V),…``."""
    if len(lines) < 2:
        return None
    delimiter = _separator(lines[0])
    labels = _trim(_fields(lines[0], delimiter))
    if (
        not labels
        or labels[0].lower() != "time"
        or not any(label.lower().startswith("channel") for label in labels[1:])
    ):
        return None
    raw = _trim(_fields(lines[1], delimiter))
    if len(raw) != len(labels) or not all(u.startswith("(") and u.endswith(")") for u in raw):
        raise RunFormatError(
            "PicoScope CSV export: line 2 should give each column's unit in parentheses, e.g. "
            f"'(ms),(V),(V)'; got {lines[1][:80]!r}",
            where,
        )
    units = [u[1:-1].strip() for u in raw]
    first = 2
    while first < len(lines) and not lines[first].strip(" \t,;"):
        first += 1
    return InstrumentExport(
        "PicoScope CSV",
        labels,
        units,
        first,
        delimiter=delimiter,
        decimal=_decimal(lines, first, delimiter),
    )


_LVM_SEPARATORS = {"tab": "\t", "comma": ",", "semicolon": ";", "space": None}
#: A unit at the end of a channel's label, in parentheses or brackets: "Displacement (mm)".
_LABEL_UNIT = re.compile(r"[(\[]\s*([^()\[\]]+?)\s*[)\]]\s*$")


def _label_unit(label: str) -> str:
    """The unit a channel's label ends with ("Displacement (mm)": "mm"), where the
    export's header gives none (a LabVIEW file without Y_Unit_Label); "" if none."""
    found = _LABEL_UNIT.search(label)
    return found.group(1) if found else ""


def _lvm(lines: Sequence[str], where: str) -> InstrumentExport | None:
    """LabVIEW measurement file (``.lvm``), one data segment."""
    if not lines or not lines[0].startswith("LabVIEW Measurement"):
        return None
    settings: dict[str, list[str]] = {}
    ends = []
    delimiter: str | None = "\t"
    for index, line in enumerate(lines):
        fields = [f.strip() for f in line.split(delimiter)] if line.strip() else []
        if not fields:
            continue
        if fields[0] == "***End_of_Header***":
            ends.append(index)
            if len(ends) == 2:
                break
            continue
        key = fields[0].lower()
        settings[key] = [f for f in fields[1:] if f != ""]
        if key == "separator" and settings[key]:
            name = settings[key][0].lower()
            if name not in _LVM_SEPARATORS:
                raise RunFormatError(
                    f"LabVIEW .lvm header: unknown Separator {settings[key][0]!r}; expected Tab "
                    "or Comma",
                    where,
                )
            delimiter = _LVM_SEPARATORS[name]
    if len(ends) < 2:
        raise RunFormatError(
            "LabVIEW .lvm file: expected a file header and a segment header, each ending with "
            f"'***End_of_Header***', within the first {len(lines)} lines",
            where,
        )
    decimal = (settings.get("decimal_separator") or ["."])[0]
    if decimal not in (".", ","):
        raise RunFormatError(
            f"LabVIEW .lvm header: Decimal_Separator {decimal!r}; expected '.' or ','", where
        )
    x_columns = (settings.get("x_columns") or ["One"])[0].lower()
    if x_columns not in ("no", "one", "multi"):
        raise RunFormatError(
            f"LabVIEW .lvm header: X_Columns {x_columns!r}; expected No, One or Multi", where
        )
    label_line = ends[1] + 1
    while label_line < len(lines) and not lines[label_line].strip():
        label_line += 1
    if label_line >= len(lines):
        raise RunFormatError("LabVIEW .lvm file: no column label row after the headers", where)
    labels = [f.strip() for f in lines[label_line].split(delimiter)]
    ignore = {i for i, label in enumerate(labels) if label.lower() == "comment"}
    y_units = settings.get("y_unit_label", [])
    x_dimension = (settings.get("x_dimension") or ["Time"])[0]
    if x_dimension.lower() != "time":
        raise RunFormatError(
            f"LabVIEW .lvm file: X_Dimension is {x_dimension!r}; expected Time", where
        )
    channel_columns = [i for i in range(len(labels)) if i not in ignore]
    if x_columns == "multi":
        xs = channel_columns[0::2]
        ys = channel_columns[1::2]
        ignore |= set(xs[1:])
        channel_columns = [xs[0], *ys]
    units = [""] * len(labels)
    if x_columns == "no":
        try:
            start = _number((settings.get("x0") or ["0"])[0], decimal)
            increment = _number(settings["delta_x"][0], decimal)
        except (KeyError, IndexError):
            increment = None
        if increment is None or start is None or not increment > 0:
            raise RunFormatError(
                "LabVIEW .lvm file with X_Columns No: expected X0 and a positive Delta_X [s] "
                "in the segment header",
                where,
            )
        for j, column in enumerate(channel_columns):
            units[column] = (y_units[j] if j < len(y_units) else "") or _label_unit(labels[column])
        return InstrumentExport(
            "LabVIEW LVM",
            labels,
            units,
            label_line + 1,
            delimiter=delimiter,
            decimal=decimal,
            time_start=start,
            time_increment=increment,
            implicit_time=True,
            ignore=frozenset(ignore),
        )
    units[channel_columns[0]] = "s"
    for j, column in enumerate(channel_columns[1:]):
        units[column] = (y_units[j] if j < len(y_units) else "") or _label_unit(labels[column])
    return InstrumentExport(
        "LabVIEW LVM",
        labels,
        units,
        label_line + 1,
        delimiter=delimiter,
        decimal=decimal,
        ignore=frozenset(ignore),
    )


_DETECTORS = (_lvm, _tektronix, _tektronix_tds, _keysight, _rigol, _picoscope)


def detect_export(lines: Sequence[str], where: str = "") -> InstrumentExport | None:
    """Recognise an instrument's text export from the first lines of a file.

    Parameters
    ----------
    lines : sequence of str
        The file's first lines (:data:`PREAMBLE_LINES` or more), without line ends.
    where : str
        The file, for error messages.

    Returns
    -------
    InstrumentExport or None
        None when the lines are no recognised export (a plain CSV, the canonical file).

    Raises
    ------
    RunFormatError
        For a recognised export whose preamble is inconsistent, naming what is wrong.
    """
    for detect in _DETECTORS:
        found = detect(lines, where)
        if found is not None:
            return found
    return None


def _role(name: str, where: str) -> tuple[str, float | None]:
    """Canonical role of a ``columns`` entry and the unit its name states (None: none)."""
    if name in (*COLUMNS, IGNORE):
        return name, None
    try:
        parsed = parse_column(name)
    except ValueError as exc:
        raise RunFormatError(f"columns: {exc}", where) from None
    if parsed is None:
        raise RunFormatError(
            f"columns: unknown column {name!r}; expected per column one of {[*COLUMNS, IGNORE]}",
            where,
        )
    return parsed


def _physical_factor(role: str, unit: str) -> float | None:
    """Factor from an instrument's unit to the canonical unit of ``role``, if physical."""
    text = unit.strip()
    units = UNITS[role]
    if text in units:
        return units[text]
    return units.get(text.lower())


def _auto_roles(export: InstrumentExport, where: str, fix: str) -> list[str]:
    """Roles from the units alone, when every channel has a length or velocity unit."""
    roles = []
    for i, unit in enumerate(export.units):
        if i in export.ignore:
            roles.append(IGNORE)
        elif i == export.time_column:
            roles.append(TIME)
        elif _physical_factor(DISPLACEMENT, unit) is not None:
            roles.append(DISPLACEMENT)
        elif _physical_factor(VELOCITY, unit) is not None:
            roles.append(VELOCITY)
        else:
            raise RunFormatError(
                f"{export.vendor} export with columns {export.describe()}: {fix}", where
            )
    if roles.count(DISPLACEMENT) > 1 or roles.count(VELOCITY) > 1:
        raise RunFormatError(
            f"{export.vendor} export with columns {export.describe()}: more than one channel "
            f"of the same quantity; {fix}",
            where,
        )
    return roles


def _check_stated(
    export: InstrumentExport, i: int, stated: float | None, factor: float, name: str, where: str
) -> None:
    """A unit in a ``columns`` name must agree with the unit the export states."""
    if stated is not None and abs(stated - factor) > 1e-12 * factor:
        raise RunFormatError(
            f"columns: {export.labels[i]} is exported in {export.units[i]}; the unit in its "
            f"name contradicts it; name it {name!r} and it is converted from "
            f"{export.units[i]}",
            where,
        )


def _column_factor(
    export: InstrumentExport,
    i: int,
    role: str,
    stated: float | None,
    factors: Mapping[str, float],
    where: str,
) -> float:
    """Factor from column ``i`` as exported to the canonical unit of ``role``.

    Time converts from its unit (a sample index is converted later); a channel in a
    length or velocity unit converts from it (a scale factor on top is refused); a
    channel in volts or without a unit needs its sensitivity in ``factors``.
    """
    unit = export.units[i]
    label = f"{export.labels[i]} [{unit}]" if unit else export.labels[i]
    if role == TIME:
        if unit == "index":
            return 1.0
        factor = TIME_UNITS.get(unit.strip().lower().replace("\u03bc", "\u00b5"))
        if factor is None:
            raise RunFormatError(
                f"{export.vendor} export: time column {label} has no known time unit; "
                f"expected one of {sorted(TIME_UNITS)}",
                where,
            )
        _check_stated(export, i, stated, factor, TIME, where)
        return factor
    physical = _physical_factor(role, unit) if unit else None
    volts = VOLT_UNITS.get(unit.strip().lower())
    if physical is not None:
        if role in factors:
            raise RunFormatError(
                f"scale: {export.labels[i]} is exported in {unit}, which is converted to "
                "SI units already; a scale factor would convert it twice",
                where,
            )
        _check_stated(export, i, stated, physical, role, where)
        return physical
    other = VELOCITY if role == DISPLACEMENT else DISPLACEMENT
    if unit and volts is None and _physical_factor(other, unit) is not None:
        raise RunFormatError(
            f"columns: {label} is exported as a {other.split('_')[0]} but is named "
            f"{role!r}; check the order of the columns",
            where,
        )
    if stated is not None:
        raise RunFormatError(
            f"columns: {label} is exported in {unit or 'an unknown unit'}, not in the unit "
            f"its name states; name it {role!r} and give its sensitivity with scale={{...}}",
            where,
        )
    if role not in factors:
        what = "volts" if volts is not None else "an unknown unit"
        per = "m/V" if role == DISPLACEMENT else "(m/s)/V"
        raise RunFormatError(
            f"{export.vendor} export: {label} ({role}) is in {what}; give the sensor's "
            f"sensitivity in {per} with scale={{...}}, e.g. {role}=1e-3",
            where,
        )
    return (volts if volts is not None else 1.0) * factors[role]


def read_export(
    lines: Sequence[str],
    export: InstrumentExport,
    *,
    columns: Sequence[str] | None = None,
    scale: Mapping[str, float] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    where: str = "",
) -> dict[str, NDArray]:
    """Read the samples of a recognised instrument export.

    Parameters
    ----------
    lines : sequence of str
        All lines of the file, without line ends.
    export : InstrumentExport
        Its layout, from :func:`detect_export`.
    columns : list of str, optional
        The role of each column in file order (the columns listed by
        :meth:`InstrumentExport.describe`): ``time_s``, ``displacement_m``,
        ``velocity_m_per_s`` or ``ignore``. Needed unless every channel's unit is a
        length or a velocity unit. Time is converted from the export's unit.
    scale : mapping, optional
        The sensitivity of each channel exported in volts: ``{"displacement_m":
        M_PER_V, "velocity_m_per_s": M_PER_S_PER_V}``, in [m/V] and [(m/s)/V]; a
        channel in mV is converted to V first. Required for every channel in volts
        or without a unit; refused for a channel whose unit is already converted.
    delimiter, decimal : str, optional
        Override the separator and decimal mark of the export.
    where : str
        The file, for error messages.

    Returns
    -------
    dict
        Arrays by canonical column name (time first), in s, m and m/s.

    Raises
    ------
    RunFormatError
        Naming the line and column, or the option that is missing, e.g. the role of
        the channels or a sensitivity.
    """
    sep = export.delimiter if delimiter is None else delimiter
    mark = export.decimal if decimal is None else decimal
    visible = [i for i in range(len(export.labels)) if i not in export.ignore]
    fix = (
        f"name the role of each column with columns=[...] ({len(visible)} names in file "
        "order: time_s, displacement_m, velocity_m_per_s or ignore) and give each "
        "channel's sensitivity in m/V or (m/s)/V with scale={...}"
    )
    if columns is None:
        roles = _auto_roles(export, where, fix)
        stated: list[float | None] = [None] * len(roles)
    else:
        if isinstance(columns, str) or len(columns) != len(visible):
            raise RunFormatError(
                f"{export.vendor} export with columns {export.describe()}: columns= names "
                f"{0 if isinstance(columns, str) else len(columns)} column(s); expected "
                f"{len(visible)}, one per column in file order",
                where,
            )
        parsed = dict(zip(visible, (_role(str(c), where) for c in columns), strict=True))
        roles = [parsed[i][0] if i in parsed else IGNORE for i in range(len(export.labels))]
        stated = [parsed[i][1] if i in parsed else None for i in range(len(export.labels))]
    used = [r for r in roles if r != IGNORE]
    for name in set(used):
        if used.count(name) > 1:
            raise RunFormatError(f"columns: {name!r} is given {used.count(name)} times", where)
    if export.implicit_time:
        if TIME in used:
            raise RunFormatError(
                f"{export.vendor} export: time is given by the header (X0, Delta_X), not by a "
                "column; name only the channels in columns=",
                where,
            )
    elif roles[export.time_column] != TIME:
        raise RunFormatError(
            f"{export.vendor} export: the first column "
            f"({export.labels[export.time_column]}) is the time axis; columns= must name it "
            f"{TIME!r}, got {roles[export.time_column]!r}",
            where,
        )
    if DISPLACEMENT not in used and VELOCITY not in used:
        raise RunFormatError(
            f"columns: a {DISPLACEMENT!r} or {VELOCITY!r} column is needed; got {list(roles)}",
            where,
        )
    factors = check_scale(scale, [r for r in used if r != TIME], where)
    conversion = {
        i: _column_factor(export, i, role, stated[i], factors, where)
        for i, role in enumerate(roles)
        if role != IGNORE
    }

    keep = [i for i, r in enumerate(roles) if r != IGNORE]
    width = len(export.labels)
    rows: list[list[float]] = []
    for number in range(export.data_line, len(lines)):
        line = lines[number]
        if not line.strip(" \t,;"):
            continue
        fields = _fields(line, sep)[export.first_field :]
        fields = _trim(fields) if len(fields) > width else fields
        if len(fields) < width:
            fields = fields + [""] * (width - len(fields))
        if len(fields) != width:
            raise RunFormatError(
                f"line {number + 1}: expected {width} field(s) ({', '.join(export.labels)}), "
                f"got {len(fields)}: {line[:80]!r}",
                where,
            )
        row = []
        for i in keep:
            value = _number(fields[i], mark)
            if value is None:
                hint = " (an over-range mark: the channel was clipped)" if "∞" in fields[i] else ""
                raise RunFormatError(
                    f"line {number + 1}, column {export.labels[i]!r}: {fields[i][:40]!r} is not "
                    f"a number{hint}",
                    where,
                )
            row.append(value)
        rows.append(row)
    if not rows:
        raise RunFormatError(f"{export.vendor} export: no sample rows after the preamble", where)
    data = np.asarray(rows, dtype=np.float64)
    out: dict[str, NDArray] = {}
    for c, i in enumerate(keep):
        column = data[:, c] * conversion[i]
        if roles[i] == TIME and export.units[i] == "index":
            column = export.time_start + column * export.time_increment
        out[roles[i]] = column
    if export.implicit_time:
        out[TIME] = export.time_start + np.arange(len(rows)) * export.time_increment
    return {name: out[name] for name in COLUMNS if name in out}
