"""ΔE(A) bands of a campaign's runs, per group of repeats, at amplitudes the runs share.

Every fit gives its law's energy loss per cycle ΔE(A) with a credible band at the swings
of its analysed motion (:attr:`bayestribo.inference.FitResult.dissipation`,
:func:`bayestribo.inference.dissipation.dissipation_band`), in any law and for the
law-free answer alike (``law="auto"`` with several laws as good: their mixture). It is
the one quantity every law has, so it compares runs of any laws side by side.

The runs of a group decay over different ranges of swing: ΔE is compared at a swing
inside the range every run shown covers (:func:`common_range`; the geometric middle by
default, :func:`chosen_amplitude`), each run's band read there by interpolation on
log-log axes (:func:`at_amplitude`), where a law's ΔE(A) is a sum of powers of A and
close to a straight line between the band's swings.

These are each run's posterior bands, not a population of repeats: a campaign's digests
keep no draws of ΔE (:mod:`bayestribo.campaign.digest`), so the spread between repeats
is seen, not inferred.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "at_amplitude",
    "chosen_amplitude",
    "common_range",
    "dissipation_rows",
    "group_runs",
    "run_bands",
    "run_metadata",
    "swing_record",
]


def run_bands(fits: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Each run's ΔE(A) band, by run id (runs without one are left out).

    Parameters
    ----------
    fits : mapping of str to fit result
        Run id -> :class:`bayestribo.inference.FitResult` (its ``dissipation``), or
        directly a band (a dict with ``amplitude``, ``mean``, ``interval``).

    Returns
    -------
    dict of str to dict
        Run id -> band with at least two finite, positive swings.
    """
    out = {}
    for name, fit in fits.items():
        band = fit if isinstance(fit, Mapping) else getattr(fit, "dissipation", None)
        if not band or "amplitude" not in band or "interval" not in band:
            continue
        amps = np.asarray(band["amplitude"], dtype=float)
        if np.count_nonzero(np.isfinite(amps) & (amps > 0)) >= 2:
            out[str(name)] = dict(band)
    return out


def group_runs(analysis: Any) -> dict[str, list[str]]:
    """The runs of each group of a campaign analysis, by group label.

    Groups with contact first (the labels of ``analysis.contact``), then the runs
    without contact (``"no contact"``, or one label per law where they have several).
    """
    out: dict[str, list[str]] = {}
    if analysis.contact is not None:
        for g in analysis.contact.groups.values():
            out[g.label] = list(g.runs)
        if not analysis.contact.groups and analysis.contact.pooled is not None:
            out[analysis.contact.pooled.label] = list(analysis.contact.pooled.runs)
    if analysis.zeta0 is not None:
        if analysis.zeta0.pooled is not None:
            out["no contact"] = list(analysis.zeta0.pooled.runs)
        for g in analysis.zeta0.groups.values():
            out[f"no contact,{g.label}"] = list(g.runs)
    return out


def _swings(band: Mapping[str, Any]) -> np.ndarray:
    amps = np.asarray(band["amplitude"], dtype=float)
    return amps[np.isfinite(amps) & (amps > 0)]


def common_range(bands: Sequence[Mapping[str, Any]]) -> tuple[float, float] | None:
    """The swings every band covers, ``(low, high)``, or None if they share none.

    Bands in different amplitude units never share a range.
    """
    if not bands:
        return None
    units = {str(b.get("amplitude_unit", "")) for b in bands}
    if len(units) > 1:
        return None
    low = max(float(_swings(b).min()) for b in bands)
    high = min(float(_swings(b).max()) for b in bands)
    return (low, high) if low < high else None


def chosen_amplitude(bands: Sequence[Mapping[str, Any]]) -> float | None:
    """The geometric middle of :func:`common_range`, or None."""
    found = common_range(bands)
    return None if found is None else math.sqrt(found[0] * found[1])


def _loglog(amplitude: float, amps: np.ndarray, values: np.ndarray) -> float:
    """``values`` at ``amplitude`` by linear interpolation in log A and log ΔE (linear in
    ΔE where a value is not positive)."""
    order = np.argsort(amps)
    a, v = amps[order], values[order]
    if np.all(v > 0):
        return float(np.exp(np.interp(math.log(amplitude), np.log(a), np.log(v))))
    return float(np.interp(math.log(amplitude), np.log(a), v))


def at_amplitude(band: Mapping[str, Any], amplitude: float) -> dict[str, float] | None:
    """A run's ΔE and its band at one swing, or None outside the band's swings.

    Parameters
    ----------
    band : mapping
        A ΔE(A) band (:func:`run_bands`).
    amplitude : float
        The swing [the band's ``amplitude_unit``].

    Returns
    -------
    dict or None
        ``mean``, ``low``, ``high`` [the band's ``unit``].
    """
    amps = np.asarray(band["amplitude"], dtype=float)
    keep = np.isfinite(amps) & (amps > 0)
    amps = amps[keep]
    if amps.size < 2 or not amps.min() <= amplitude <= amps.max():
        return None
    lower, upper = (np.asarray(side, dtype=float)[keep] for side in band["interval"])
    mean = np.asarray(band["mean"], dtype=float)[keep]
    return {
        "mean": _loglog(amplitude, amps, mean),
        "low": _loglog(amplitude, amps, lower),
        "high": _loglog(amplitude, amps, upper),
    }


def dissipation_rows(
    groups: Mapping[str, Sequence[str]],
    bands: Mapping[str, Mapping[str, Any]],
    amplitude: float | None = None,
    metadata: Mapping[str, Mapping[str, Any]] | None = None,
) -> tuple[float | None, list[dict[str, Any]]]:
    """Each run's ΔE at one swing shared by the runs, per group.

    Parameters
    ----------
    groups : mapping of str to sequence of str
        Group label -> its runs (:func:`group_runs` of a campaign analysis).
    bands : mapping
        Run id -> ΔE(A) band (:func:`run_bands`); runs without one are left out.
    amplitude : float, optional
        The swing; default :func:`chosen_amplitude` of every band of the groups' runs,
        else (they share no swing) of each group's own.
    metadata : mapping, optional
        Run id -> its metadata or summary row (``law``, ``load_N``).

    Returns
    -------
    amplitude : float or None
        The swing shared by every run, or None where each group has its own.
    rows : list of dict
        ``group``, ``run``, ``law``, ``load_N``, ``amplitude``, ``amplitude_unit``,
        ``mean``, ``low``, ``high``, ``unit``, ``prob``; a run whose band does not
        reach the swing has no ``mean`` and says why in ``note``.
    """
    members = {label: [r for r in runs if r in bands] for label, runs in groups.items()}
    every = [bands[r] for runs in members.values() for r in runs]
    shared = amplitude if amplitude is not None else chosen_amplitude(every)
    meta = metadata or {}
    rows = []
    for label, runs in members.items():
        at = shared if shared is not None else chosen_amplitude([bands[r] for r in runs])
        for run in runs:
            band = bands[run]
            row: dict[str, Any] = {
                "group": label,
                "run": run,
                "law": meta.get(run, {}).get("law") or band.get("law"),
                "load_N": meta.get(run, {}).get("load_N"),
                "amplitude": at,
                "amplitude_unit": band.get("amplitude_unit"),
                "unit": band.get("unit"),
                "prob": band.get("prob"),
            }
            value = None if at is None else at_amplitude(band, at)
            if value is None:
                row["note"] = "its analysed motion does not reach this swing"
            else:
                row.update(value)
            rows.append(row)
    return (shared, rows)


def swing_record(
    groups: Mapping[str, Sequence[str]],
    bands: Mapping[str, Mapping[str, Any]],
    metadata: Mapping[str, Mapping[str, Any]] | None = None,
) -> dict[str, Any]:
    """:func:`dissipation_rows` as a campaign's JSON keeps them: the shared swing, and
    each run's ΔE there as a summary (``mean`` with ``interval`` [low, high]).

    Returns
    -------
    dict
        ``amplitude``: the swing shared by every run [its ``amplitude_unit``], or None
        where each group has its own; ``rows``: per run ``group``, ``run``, ``law``,
        ``load_N``, ``amplitude``, ``amplitude_unit``, ``unit``, ``prob`` and
        ``mean``, ``interval`` [``unit``], or ``note`` (why it has none).
    """
    shared, rows = dissipation_rows(groups, bands, metadata=metadata)
    out = []
    for row in rows:
        row = dict(row)
        if "mean" in row:
            row["interval"] = [row.pop("low"), row.pop("high")]
        out.append(row)
    return {"amplitude": shared, "rows": out}


def run_metadata(analysis: Any) -> dict[str, dict[str, Any]]:
    """Run id -> the analysis' summary row of the run (its ``law``, ``load_N``, ...)."""
    return {str(r.get("run_id")): r for r in analysis.runs}
