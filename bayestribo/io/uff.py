"""Universal File Format data-set 58 (ASCII) and 58b (binary), through pyuff.

Vibrometer software exports each channel as one data-set 58: a time response
(function type 1) with an evenly spaced abscissa. The channel is recognised by its
ordinate specific data type (8 displacement, 11 velocity) or, when that is 0
(unknown), by its unit label; the unit label (``m``, ``mm``, ``um``/``µm``, ``nm``,
each optionally ``/s``) gives the factor to SI units. Time comes from the abscissa
minimum and increment (label ``s`` or ``ms``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo.errors import RunFormatError
from bayestribo.io.run import COLUMNS, DISPLACEMENT, TIME, VELOCITY
from bayestribo.io.text import check_scale
from bayestribo.io.units import LENGTHS, TIMES, length_unit

__all__ = ["LENGTH_UNIT_FACTORS", "read_uff"]

#: Length unit labels and their factor to metres (the package's one table).
LENGTH_UNIT_FACTORS: Mapping[str, float] = LENGTHS
#: Abscissa labels and their factor to seconds; a record of no abscissa unit is in
#: seconds, as UFF 58 defines its time records.
_TIME_UNIT_FACTORS = {**TIMES, "none": 1.0, "": 1.0}
_SPEC_TYPES = {8: DISPLACEMENT, 11: VELOCITY}
_TIME_RESPONSE = 1


def _channel_and_factor(record: dict, index: int, where: str) -> tuple[str | None, float | None]:
    """Canonical channel of a record from its data type / unit label, and the unit factor."""
    label = str(record.get("ordinate_axis_units_lab", "")).strip()
    parsed = length_unit(label)
    factor, per_second = (None, False) if parsed is None else parsed
    name = _SPEC_TYPES.get(int(record.get("ordinate_spec_data_type", 0) or 0))
    if name is None and factor is not None:
        name = VELOCITY if per_second else DISPLACEMENT
    if name is not None and factor is not None and per_second != (name == VELOCITY):
        expected = "a velocity unit such as m/s" if name == VELOCITY else "a length unit such as m"
        raise RunFormatError(
            f"UFF record {index} ({record.get('id1', '')!r}): unit label {label!r} does not fit a "
            f"{name} record; expected {expected}",
            where,
        )
    return name, factor


def read_uff(
    path: str | Path,
    *,
    channels: Mapping[str, int] | None = None,
    scale: Mapping[str, float] | None = None,
) -> dict[str, NDArray]:
    """Read displacement and velocity time records from a UFF 58/58b file.

    Parameters
    ----------
    path : str or Path
        The ``.uff``/``.unv`` file.
    channels : mapping, optional
        Record index (counting data-sets 58 in the file from 0) per canonical name,
        e.g. ``{"displacement_m": 0, "velocity_m_per_s": 3}``, when the file holds
        several records of a kind or records without a recognisable type.
    scale : mapping, optional
        Factor to SI per canonical name; replaces the factor from the unit label (use
        it when the label is missing or unknown).

    Returns
    -------
    dict
        Arrays by canonical name (time first).

    Raises
    ------
    RunFormatError
        For a file pyuff cannot read, no or ambiguous records, an unknown unit label
        without a scale factor, or records with different time axes.
    """
    pyuff = require("pyuff", "reading UFF files")

    path = Path(path)
    where = str(path)
    try:
        uff = pyuff.UFF(str(path))
        found: Any = uff.read_sets() if uff.get_n_sets() else []
    except Exception as exc:  # third-party parser, untrusted file: any failure is a format error
        raise RunFormatError(f"could not read the file as UFF: {exc!r}", where) from None
    if isinstance(found, dict):
        found = [found]
    records = [r for r in found if isinstance(r, dict) and r.get("type") == 58]
    if not records:
        raise RunFormatError("no data-set 58 (function at a nodal DOF) in the file", where)

    chosen: dict[str, int] = {}
    factors: dict[str, float | None] = {}
    if channels is not None:
        for name, index in channels.items():
            if name not in (DISPLACEMENT, VELOCITY):
                raise RunFormatError(
                    f"channels: {name!r} is not a signal; expected {DISPLACEMENT!r} or "
                    f"{VELOCITY!r}",
                    where,
                )
            if not isinstance(index, int) or not 0 <= index < len(records):
                raise RunFormatError(
                    f"channels[{name!r}]: expected a record index from 0 to {len(records) - 1}, "
                    f"got {index!r}",
                    where,
                )
            chosen[name] = index
            factors[name] = _channel_and_factor(records[index], index, where)[1]
    else:
        for index, record in enumerate(records):
            if int(record.get("func_type", 0) or 0) != _TIME_RESPONSE:
                continue
            name, factor = _channel_and_factor(record, index, where)
            if name is None:
                continue
            if name in chosen:
                raise RunFormatError(
                    f"records {chosen[name]} and {index} are both {name}; choose one with "
                    f"channels={{{name!r}: index}}",
                    where,
                )
            chosen[name] = index
            factors[name] = factor
    if not chosen:
        raise RunFormatError(
            "no displacement (data type 8) or velocity (data type 11) time record; choose "
            "records with channels={'displacement_m': index}",
            where,
        )
    scale = check_scale(scale, list(chosen), where)

    out: dict[str, NDArray] = {}
    time: NDArray | None = None
    for name in (DISPLACEMENT, VELOCITY):
        if name not in chosen:
            continue
        index = chosen[name]
        record = records[index]
        factor = scale.get(name, factors[name])
        if factor is None:
            raise RunFormatError(
                f"UFF record {index}: unit label {record.get('ordinate_axis_units_lab')!r} is "
                f"not a known length unit {sorted(LENGTH_UNIT_FACTORS)}; give the factor to SI "
                f"units with scale={{{name!r}: factor}}",
                where,
            )
        data = np.asarray(record.get("data"))
        if np.iscomplexobj(data) or data.ndim != 1:
            raise RunFormatError(
                f"UFF record {index}: expected real 1-D time data, got {data.dtype} {data.shape}",
                where,
            )
        t_label = str(record.get("abscissa_axis_units_lab", "")).strip().lower()
        t_label = t_label.replace("\u03bc", "\u00b5")
        if t_label not in _TIME_UNIT_FACTORS:
            raise RunFormatError(
                f"UFF record {index}: abscissa unit {t_label!r}; expected a unit of time, one "
                f"of {sorted(TIMES)}",
                where,
            )
        t = np.asarray(record.get("x"), dtype=np.float64) * _TIME_UNIT_FACTORS[t_label]
        if t.shape != data.shape:
            raise RunFormatError(
                f"UFF record {index}: {t.size} abscissa values for {data.size} data values", where
            )
        if time is None:
            time = t
        elif time.shape != t.shape or not np.array_equal(time, t):
            raise RunFormatError(
                f"UFF records {chosen[DISPLACEMENT]} and {index} have different time axes; "
                "expected displacement and velocity sampled together",
                where,
            )
        out[name] = data.astype(np.float64) * factor
    out[TIME] = time
    return {name: out[name] for name in COLUMNS if name in out}
