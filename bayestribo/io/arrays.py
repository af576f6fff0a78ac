"""Named arrays (MATLAB variables, HDF5 datasets) to the signals of a run.

A ``.mat`` or HDF5 file holds arrays by name. The signals are picked either by the
user (``channels={"time_s": "t", "displacement_m": "x"}``, where a key may carry a
unit, ``"displacement_um": "x"``) or, without ``channels``, by the names themselves
when they are canonical or carry a unit (``time_s``, ``displacement_um``,
``velocity_mm_per_s``; an HDF5 dataset may state its unit in a ``units`` attribute
instead). A name that is a quantity without a unit is never read as SI: the error asks
for the unit.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RunFormatError
from bayestribo.io.columns import check_scale, parse_column
from bayestribo.io.run import ACCELERATIONS, ANGULAR, COLUMNS, DISPLACEMENT, TIME, VELOCITY

__all__ = ["MAX_SAMPLES", "NamedArray", "signals_from_arrays"]

#: Most samples a channel of a binary file may claim [-] (20 million: 20 s at 1 MHz,
#: 160 MB as float64). Checked from the file's own description (a dataset's shape, a
#: MATLAB variable's header) before any data is read, so that a damaged header that
#: claims billions of samples is refused in bounded memory.
MAX_SAMPLES = 20_000_000

#: The columns that carry the motion, any one of which makes a run (with the time, or
#: the sample rate): a displacement, a velocity, an angle or angular velocity (a
#: rotation), an acceleration (integrated into the velocity by read_run).
_MOTION: tuple[str, ...] = (DISPLACEMENT, VELOCITY, *ANGULAR, *ACCELERATIONS)


@dataclass(frozen=True)
class NamedArray:
    """One array of a file: its name (a variable or dataset path), values and unit.

    Attributes
    ----------
    name : str
        Variable name or dataset path (``group/name``).
    values : ndarray
        The values as stored.
    unit : str or None
        The unit the file states for it (HDF5 ``units`` attribute), if any.
    """

    name: str
    values: NDArray
    unit: str | None = None

    def describe(self) -> str:
        """``name (shape, unit)`` for messages."""
        shape = "x".join(str(n) for n in np.shape(self.values)) or "scalar"
        unit = f", {self.unit}" if self.unit else ""
        return f"{self.name} ({shape}{unit})"


def _as_vector(item: NamedArray, role: str, where: str, kind: str) -> NDArray:
    values = np.asarray(item.values)
    if values.dtype.kind not in "iuf" or values.size < 2:
        raise RunFormatError(
            f"{kind} {item.describe()} for {role}: expected a real numeric array of samples",
            where,
        )
    squeezed = np.squeeze(values)
    if squeezed.ndim != 1:
        raise RunFormatError(
            f"{kind} {item.describe()} for {role}: expected a vector (one dimension), got "
            f"shape {values.shape}",
            where,
        )
    return squeezed.astype(np.float64)


def _parse(name: str, where: str, what: str) -> tuple[str, float] | None:
    try:
        return parse_column(name)
    except ValueError as exc:
        raise RunFormatError(f"{what}: {exc}", where) from None


def _known(role: str, unit: str) -> bool:
    """Whether ``unit`` is a unit of ``role`` that :func:`parse_column` converts."""
    try:
        parsed = parse_column(f"{role.split('_')[0]} [{unit}]")
    except ValueError:
        return False
    return parsed is not None and parsed[0] == role


def _basename(name: str) -> str:
    return name.rsplit("/", 1)[-1].rsplit(".", 1)[-1]


def _named_factor(item: NamedArray, role: str, factor: float) -> float:
    """The factor to SI that the array's own name states for ``role`` (``x_mm`` picked
    as the displacement: 1e-3), else ``factor``: a channel picked by its role alone
    (``channels={'displacement_m': 'rec.x_mm'}``, ``--channel x=rec.x_mm``) is read in
    the unit its name carries, as it is when picked by that name."""
    try:
        named = parse_column(_basename(item.name))
    except ValueError:
        return factor
    return named[1] if named is not None and named[0] == role else factor


def _example(arrays: list[NamedArray]) -> str:
    """``channels={...}`` naming the file's first two vectors (one vector: it, and the
    sample rate for its time), for messages."""
    vectors = [a.name for a in arrays if np.size(a.values) >= 2][:2]
    if len(vectors) == 1:
        return (
            f"channels={{'displacement_m': {vectors[0]!r}}} with "
            "sample_rate_Hz=HZ (--sample-rate HZ)"
        )
    t, x = vectors if len(vectors) == 2 else ("t", "x")
    return f"channels={{'time_s': {t!r}, 'displacement_m': {x!r}}}"


def _automatic(
    arrays: list[NamedArray], where: str, kind: str
) -> dict[str, tuple[NamedArray, float]]:
    picked: dict[str, tuple[NamedArray, float]] = {}
    unitless = []
    for item in arrays:
        base = _basename(item.name)
        label = f"{base} [{item.unit}]" if item.unit else base
        try:
            parsed = parse_column(label)
        except ValueError:
            unitless.append(item.name)
            continue
        if parsed is None:
            continue
        role, factor = parsed
        if role in picked:
            raise RunFormatError(
                f"{kind}s {picked[role][0].name!r} and {item.name!r} both name {role}; choose "
                f"one with channels={{{role!r}: ...}}",
                where,
            )
        picked[role] = (item, factor)
    if TIME in picked and set(_MOTION) & set(picked):
        return picked  # an acceleration is integrated by read_run
    listing = ", ".join(a.describe() for a in arrays) or "none"
    hint = f"; {', '.join(map(repr, unitless))} name a quantity without a unit" if unitless else ""
    raise RunFormatError(
        f"no time and displacement or velocity {kind}s found by name (time_s, "
        f"displacement_m, velocity_m_per_s, or with a unit such as displacement_um){hint}; "
        f"the {kind}s are: {listing}; name them with channels={{...}}, e.g. "
        f"{_example(arrays)}",
        where,
    )


def _chosen(
    arrays: list[NamedArray], channels: Mapping[str, str], where: str, kind: str
) -> dict[str, tuple[NamedArray, float]]:
    if not isinstance(channels, Mapping):
        raise RunFormatError(
            f"channels: expected a mapping of column name to {kind} name, e.g. "
            f"{{'time_s': 't'}}; got {type(channels).__name__}",
            where,
        )
    by_name = {a.name: a for a in arrays}
    by_base: dict[str, list[NamedArray]] = {}
    for a in arrays:
        by_base.setdefault(_basename(a.name), []).append(a)
    picked: dict[str, tuple[NamedArray, float]] = {}
    for key, source in channels.items():
        parsed = _parse(str(key), where, "channels")
        if parsed is None:
            raise RunFormatError(
                f"channels: unknown column {key!r}; expected {list(COLUMNS)} or a quantity "
                "with its unit (time_ms, displacement_um, ...)",
                where,
            )
        role, factor = parsed
        if role in picked:
            raise RunFormatError(f"channels: {role} is given twice", where)
        item = by_name.get(str(source))
        if item is None:
            matches = by_base.get(str(source), [])
            if len(matches) > 1:
                raise RunFormatError(
                    f"channels[{key!r}]: {source!r} names {len(matches)} {kind}s "
                    f"({', '.join(m.name for m in matches)}); give the full path",
                    where,
                )
            item = matches[0] if matches else None
        if item is None:
            listing = ", ".join(a.describe() for a in arrays) or "none"
            raise RunFormatError(
                f"channels[{key!r}]: no {kind} {source!r}; the {kind}s are: {listing}", where
            )
        if item.unit:
            stated = (
                parse_column(f"{role.split('_')[0]} [{item.unit}]")
                if _known(role, item.unit)
                else None
            )
            if stated is None:
                raise RunFormatError(
                    f"channels[{key!r}]: {kind} {item.describe()} states unit "
                    f"{item.unit!r}, which is not a unit of {role}",
                    where,
                )
            if str(key) == role:
                factor = stated[1]
            elif abs(stated[1] - factor) > 1e-12 * factor:
                raise RunFormatError(
                    f"channels[{key!r}]: {kind} {item.describe()} states unit "
                    f"{item.unit!r}, which contradicts the unit in {key!r}; name it {role!r}",
                    where,
                )
        elif str(key) == role:
            factor = _named_factor(item, role, factor)
        picked[role] = (item, factor)
    if not set(_MOTION) & set(picked):
        # without a time channel the run's time comes from its sample rate (read_run)
        raise RunFormatError(
            f"channels: expected {DISPLACEMENT!r} or {VELOCITY!r} (or an angle, an "
            f"acceleration: {', '.join(map(repr, _MOTION[2:]))}; and {TIME!r}, or the "
            f"sample rate); got {sorted(channels)}",
            where,
        )
    return picked


def signals_from_arrays(
    arrays: list[NamedArray],
    *,
    channels: Mapping[str, str] | None = None,
    scale: Mapping[str, float] | None = None,
    where: str = "",
    kind: str = "variable",
    load: Callable[[NamedArray], NDArray] | None = None,
) -> dict[str, NDArray]:
    """Pick and convert the signals of a run from a file's named arrays.

    Parameters
    ----------
    arrays : list of NamedArray
        The arrays of the file.
    channels : mapping, optional
        Column name (canonical, or with a unit such as ``displacement_um``) -> array
        name. Without it the arrays are picked by their own names and units (a time
        among them). Given without ``time_s``, the run's time comes from its sample
        rate (:func:`bayestribo.read_run`'s ``sample_rate_Hz``).
    scale : mapping, optional
        Extra factor per canonical column, applied after the unit conversion.
    where : str
        The file, for messages.
    kind : str
        What the arrays are called in messages ("variable", "dataset").
    load : callable, optional
        Reads the values of a picked array (an HDF5 dataset read only once picked);
        without it, ``values`` are used as given.

    Returns
    -------
    dict
        Arrays by canonical column name (time first), in s, m and m/s.

    Raises
    ------
    RunFormatError
        For no usable arrays, an unknown name, a unit missing, or arrays that are not
        vectors of the same length, naming them.
    """
    picked = (
        _automatic(arrays, where, kind)
        if channels is None
        else _chosen(arrays, channels, where, kind)
    )
    factors = check_scale(scale, list(picked), where)
    out = {}
    for role, (item, factor) in picked.items():
        if load is not None:
            item = NamedArray(item.name, load(item), item.unit)
        values = _as_vector(item, role, where, kind)  # a new float64 array: scaled in place
        values *= factor
        values *= factors.get(role, 1.0)
        out[role] = values
    sizes = {role: values.size for role, values in out.items()}
    if len(set(sizes.values())) > 1:
        detail = ", ".join(f"{picked[r][0].name} ({n})" for r, n in sizes.items())
        raise RunFormatError(f"the signals have different lengths: {detail}", where)
    return {name: out[name] for name in (TIME, *_MOTION) if name in out}
