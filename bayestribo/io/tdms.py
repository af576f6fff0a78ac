"""LabVIEW TDMS files, through npTDMS.

The user names the group and the channel of each signal
(``channels={"displacement_m": "Disp", "velocity_m_per_s": "Vel"}``); a file with a
single group needs no group name. Time comes from the waveform properties of the
channels (``wf_start_offset``, default 0, and ``wf_increment`` [s]) or from a
channel mapped to ``"time_s"``. The unit comes from the channel property
``unit_string`` (``m``, ``mm``, ``um``, ``m/s``, ``mm/s``...), or ``NI_UnitDescription``,
when present; a ``scale`` factor replaces it. Without channels named, a group whose
units name one length (the displacement) and/or one length per second (the velocity)
is read by them, and said.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._optional import require
from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.budget import FLOAT_BYTES, read_budget
from bayestribo.io.run import COLUMNS, DISPLACEMENT, TIME, VELOCITY
from bayestribo.io.text import check_scale
from bayestribo.io.units import TIMES, length_unit

__all__ = ["read_tdms"]


def _unit_factor(name: str, unit: Any, where: str, label: str) -> float:
    """Factor from a TDMS ``unit_string`` to the canonical unit of ``name``."""
    text = str(unit).strip()
    if name == TIME:
        factor = TIMES.get(text.lower().replace("\u03bc", "\u00b5"))
    else:
        parsed = length_unit(text)
        factor = None if parsed is None or parsed[1] != (name == VELOCITY) else parsed[0]
    if factor is None:
        raise RunFormatError(
            f"TDMS channel {label}: unit_string {text!r} is not a unit of {name}; give the "
            f"factor to SI units with scale={{{name!r}: factor}}",
            where,
        )
    return factor


def _unit_of(channel: Any) -> str:
    """A channel's unit as a DAQ writes it: ``unit_string``, else ``NI_UnitDescription``."""
    props = getattr(channel, "properties", {}) or {}
    for key in ("unit_string", "NI_UnitDescription"):
        text = str(props.get(key, "")).strip()
        if text:
            return text
    return ""


def _by_unit(available: Mapping[str, Any]) -> dict[str, str] | None:
    """The channels a group's units name, where they name at most one displacement
    (a length) and one velocity (a length per second), and at least one of them; None
    otherwise."""
    found: dict[str, list[str]] = {DISPLACEMENT: [], VELOCITY: []}
    for name, channel in available.items():
        parsed = length_unit(_unit_of(channel)) if _unit_of(channel) else None
        if parsed is not None:
            found[VELOCITY if parsed[1] else DISPLACEMENT].append(name)
    if any(len(v) > 1 for v in found.values()) or not any(found.values()):
        return None
    return {role: names[0] for role, names in found.items() if names}


def read_tdms(
    path: str | Path,
    *,
    channels: Mapping[str, str] | None = None,
    group: str | None = None,
    scale: Mapping[str, float] | None = None,
) -> dict[str, NDArray]:
    """Read the chosen channels of a TDMS file.

    Parameters
    ----------
    path : str or Path
        The ``.tdms`` file.
    channels : mapping, optional
        TDMS channel name per canonical name (``"displacement_m"``,
        ``"velocity_m_per_s"`` and optionally ``"time_s"``); default: the channels whose
        units name one length and/or one length per second (said with a
        :class:`~bayestribo.errors.ReadingWarning`).
    group : str, optional
        TDMS group; needed when the file has more than one group.
    scale : mapping, optional
        Factor to SI per canonical name; replaces the factor from ``unit_string``.

    Returns
    -------
    dict
        Arrays by canonical name (time first).

    Raises
    ------
    RunFormatError
        For a file npTDMS cannot read, an unknown group or channel (the message lists
        those in the file), channels of different lengths or time steps, no time
        information, or an unknown unit without a scale factor.
    """
    TdmsFile = require("nptdms", "reading TDMS files").TdmsFile

    path = Path(path)
    where = str(path)
    try:
        # opened, not read: only the chosen channels' data are read, once counted
        tdms = TdmsFile.open(str(path))
    except Exception as exc:  # third-party parser, untrusted file: any failure is a format error
        raise RunFormatError(f"could not read the file as TDMS: {exc!r}", where) from None
    with tdms:
        return _read_channels(tdms, path, where, channels, group, scale)


def _read_channels(
    tdms: Any,
    path: Path,
    where: str,
    channels: Mapping[str, str] | None,
    group: str | None,
    scale: Mapping[str, float] | None,
) -> dict[str, NDArray]:
    try:
        groups = {g.name: g for g in tdms.groups()}
    except Exception as exc:  # third-party parser, untrusted file: any failure is a format error
        raise RunFormatError(f"could not read the file as TDMS: {exc!r}", where) from None
    if not groups:
        raise RunFormatError("the file holds no TDMS group (empty, or not a TDMS file)", where)
    if group is None:
        if len(groups) != 1:
            raise RunFormatError(
                f"the file has {len(groups)} groups {sorted(groups)}; choose one with group=...",
                where,
            )
        group = next(iter(groups))
    if group not in groups:
        raise RunFormatError(
            f"group {group!r} is not in the file; its groups are {sorted(groups)}", where
        )
    available = {c.name: c for c in groups[group].channels()}
    if not channels:
        channels = _by_unit(available)
        if channels is None:
            example = next(iter(sorted(available)), "Disp")
            raise RunFormatError(
                f"name the channels, e.g. channels={{'displacement_m': {example!r}}}; "
                f"group {group!r} has channels {sorted(available)}",
                where,
            )
        named = ", ".join(f"{channel!r} as {name}" for name, channel in channels.items())
        warn(
            f"{where}: channels read by their unit_string: {named}; name others with "
            "channels={...}",
            ReadingWarning,
        )
    for name, channel in channels.items():
        if name not in COLUMNS:
            raise RunFormatError(
                f"channels: {name!r} is not a canonical name; expected some of {list(COLUMNS)}",
                where,
            )
        if channel not in available:
            raise RunFormatError(
                f"channel {channel!r} (for {name!r}) is not in group {group!r}; its channels "
                f"are {sorted(available)}",
                where,
            )
    if DISPLACEMENT not in channels and VELOCITY not in channels:
        raise RunFormatError(
            f"channels: a {DISPLACEMENT!r} or {VELOCITY!r} channel is needed", where
        )
    factors = check_scale(scale, list(channels), where)
    budget = read_budget(path.stat().st_size, where)

    out: dict[str, NDArray] = {}
    steps: dict[str, tuple[float, float]] = {}
    for name, channel_name in channels.items():
        channel = available[channel_name]
        label = f"{group}/{channel_name}"
        try:
            declared = len(channel)
            stated = getattr(channel, "dtype", None)
            dtype = np.dtype(np.float64 if stated is None else stated)
        except Exception as exc:  # npTDMS failure while reading the channel's description
            raise RunFormatError(
                f"TDMS channel {label}: cannot read its description: {exc!r}", where
            ) from None
        budget.claim(
            f"TDMS channel {label!r}",
            declared * max(FLOAT_BYTES, dtype.itemsize),
            f"{declared} values of {dtype}",
        )
        try:
            data = np.asarray(channel[:])
        except Exception as exc:  # npTDMS failure while reading data
            raise RunFormatError(
                f"TDMS channel {label}: cannot read data: {exc!r}", where
            ) from None
        if data.ndim != 1 or not (np.issubdtype(data.dtype, np.number)) or np.iscomplexobj(data):
            raise RunFormatError(
                f"TDMS channel {label}: expected real numbers, got {data.dtype}", where
            )
        props = channel.properties
        if name in factors:
            factor = factors[name]
        elif _unit_of(channel):
            factor = _unit_factor(name, _unit_of(channel), where, label)
        else:
            factor = 1.0  # no unit given: the canonical unit is assumed (documented)
        out[name] = data.astype(np.float64) * factor
        if "wf_increment" in props:
            try:
                inc = float(props["wf_increment"])
                start = float(props.get("wf_start_offset", 0.0))
            except (TypeError, ValueError):
                inc = start = math.nan
            if not (math.isfinite(inc) and inc > 0 and math.isfinite(start)):
                raise RunFormatError(
                    f"TDMS channel {label}: wf_increment {props['wf_increment']!r} / "
                    f"wf_start_offset {props.get('wf_start_offset')!r}; expected a positive "
                    "finite time step [s] and a finite start",
                    where,
                )
            steps[label] = (start, inc)
    lengths = {name: a.size for name, a in out.items()}
    if len(set(lengths.values())) > 1:
        raise RunFormatError(
            f"channels have different lengths {lengths}; expected signals sampled together",
            where,
        )
    if TIME not in out:
        if not steps:
            raise RunFormatError(
                "no time information: the channels have no wf_increment property; map a time "
                "channel with channels={'time_s': ...}",
                where,
            )
        if len(set(steps.values())) > 1:
            raise RunFormatError(
                f"channels have different time axes {steps}; expected signals sampled together",
                where,
            )
        start, inc = next(iter(steps.values()))
        n = next(iter(lengths.values()))
        out[TIME] = start + inc * np.arange(n, dtype=np.float64)
    return {name: out[name] for name in COLUMNS if name in out}
