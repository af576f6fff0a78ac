"""Run every applicable classical estimator on one recording: :func:`estimate_all`."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.estimators.decrement import exponential_envelope, log_decrement
from bayestribo.estimators.energy_ls import EnergyData, energy_data, energy_least_squares
from bayestribo.estimators.feeny_liang import feeny_liang
from bayestribo.estimators.nonsuccessive import nonsuccessive_peaks
from bayestribo.estimators.result import Estimate, EstimateTable
from bayestribo.io.run import Run
from bayestribo.model.scaling import Rig
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.peaks import Peaks, find_peaks

__all__ = ["METHODS", "estimate_all", "estimate_signals"]

#: Method names, in the order of the table (the command line lists them without
#: importing this module: bayestribo.cli.estimate.METHOD_NAMES, tested equal).
METHODS: tuple[str, ...] = (
    "log_decrement",
    "exponential_envelope",
    "feeny_liang",
    "nonsuccessive",
    "energy_ls_averaged",
    "energy_ls_exact",
)


_PEAK_METHODS: dict[str, Callable[[Peaks, Rig | None], Estimate]] = {
    "log_decrement": log_decrement,
    "exponential_envelope": exponential_envelope,
    "feeny_liang": feeny_liang,
    "nonsuccessive": nonsuccessive_peaks,
}


def _failed(method: str, data: str, exc: BaseException) -> Estimate:
    return Estimate(method=method, data=data, notes=f"no estimate: {exc}")


def _window_start(
    t: ArrayLike, x: ArrayLike | None, v: ArrayLike | None, rig: Rig | None, skip: int
) -> float | None:
    """Start [s] of the fit's analysed window, less three quarters of a sample step;
    None when the recording has no energy decay to find."""
    try:
        decay = energy_decay(t, x, v, rig=rig, skip_oscillations=skip)
    except BayestriboError:
        return None
    step = float(np.median(np.diff(np.asarray(t, dtype=float))))
    # The window starts at the sample nearest a turning point; the turning point's
    # sub-sample time may lie up to half a step before it.
    return float(decay.start_time - 0.75 * step)


def estimate_all(
    run: Run | str | os.PathLike[str],
    *,
    rig: Rig | None = None,
    skip_oscillations: int = 1,
    offset: float | Literal["auto", "constant"] | None = "auto",
    methods: Sequence[str] | None = None,
    name: str | None = None,
) -> EstimateTable:
    """Every applicable classical estimator on one run, as a table.

    Parameters
    ----------
    run : Run or path
        The recording (its time, displacement, velocity, rig and source are used), or
        a run file read by :func:`bayestribo.io.as_run`. For bare arrays use
        :func:`estimate_signals`.
    rig : Rig, optional
        Overrides the run's rig. Without any rig Ω comes from the recording and
        friction is reported as a friction displacement in the signal's unit.
    skip_oscillations, offset, methods, name
        As in :func:`estimate_signals` (``name`` defaults to the run's source).

    Returns
    -------
    EstimateTable
    """
    from bayestribo.io import as_run

    recording = as_run(run)
    return estimate_signals(
        recording.time,
        recording.displacement,
        recording.velocity,
        rig=recording.rig() if rig is None else rig,
        skip_oscillations=skip_oscillations,
        offset=offset,
        methods=methods,
        name=name if name is not None else recording.source,
    )


def estimate_signals(
    t: ArrayLike,
    x: ArrayLike | None = None,
    v: ArrayLike | None = None,
    *,
    rig: Rig | None = None,
    skip_oscillations: int = 1,
    offset: float | Literal["auto", "constant"] | None = "auto",
    methods: Sequence[str] | None = None,
    name: str | None = None,
) -> EstimateTable:
    """Every applicable classical estimator on sampled signals, as a table.

    Parameters
    ----------
    t : array_like
        Sample times [s].
    x, v : array_like, optional
        Displacement and velocity (at least one).
    rig : Rig, optional
        Without a rig Ω comes from the recording and friction is reported as a
        friction displacement in the signal's unit.
    skip_oscillations : int
        Oscillations after the release left out, default 1, counted as the Bayesian
        fit counts them (:func:`bayestribo.signal.decay.energy_decay`): every method
        analyses the fit's window, the peak methods from the first turning point at
        or after its start. When no energy decay can be found in the recording, the
        peak methods skip ``2 × skip_oscillations`` extrema from the first one found.
    offset : float, "auto", "constant" or None
        Equilibrium of the displacement (see :func:`bayestribo.signal.peaks.find_peaks`).
    methods : sequence of str, optional
        Subset of :data:`METHODS` (default all). The peak methods run on the
        displacement peaks and, when a velocity is recorded, on the velocity peaks.
    name : str, optional
        Name of the recording in the table.

    Returns
    -------
    EstimateTable
        One :class:`Estimate` per method and signal; a method that cannot work on
        this recording gives an Estimate with no values and the reason in ``notes``.

    Raises
    ------
    RecordingError
        No usable signal, or an unknown method name.
    """
    if x is None and v is None:
        raise RecordingError("x, v: expected a displacement x or a velocity v (or both)")
    chosen = list(METHODS if methods is None else methods)
    unknown = [m for m in chosen if m not in METHODS]
    if unknown:
        raise RecordingError(f"unknown method(s) {unknown}; expected some of {list(METHODS)}")

    out: list[Estimate] = []
    signals = [(kind, s) for kind, s in (("displacement", x), ("velocity", v)) if s is not None]
    peak_methods = [m for m in chosen if m in _PEAK_METHODS]
    energy_models = [m for m in chosen if m.startswith("energy_ls_")]
    data: EnergyData | None = None
    failure: BayestriboError | None = None
    if energy_models:
        try:
            data = energy_data(t, x, v, rig=rig, skip_oscillations=skip_oscillations, offset=offset)
        except BayestriboError as exc:
            failure = exc
    start = None
    if peak_methods and data is not None:
        # The peak methods start where the energy decay does: the fit's window.
        start = data.start_time - 0.75 * float(np.median(np.diff(np.asarray(t, dtype=float))))
    elif peak_methods:
        start = _window_start(t, x, v, rig, skip_oscillations)
    for kind, s in signals:
        if not peak_methods:
            break
        try:
            level = offset if kind == "displacement" else "auto"
            skip = 2 * skip_oscillations
            if start is not None:
                found = find_peaks(t, s, kind=kind, offset=level)
                skip = int(np.count_nonzero(found.t < start))
            pk = find_peaks(t, s, kind=kind, skip=skip, offset=level)
        except BayestriboError as exc:
            out += [_failed(m, f"{kind} peaks", exc) for m in peak_methods]
            continue
        for m in peak_methods:
            try:
                out.append(_PEAK_METHODS[m](pk, rig))
            except BayestriboError as exc:
                out.append(_failed(m, f"{kind} peaks (n={len(pk)})", exc))

    if failure is not None:
        out += [_failed(m, "energy", failure) for m in energy_models]
    for m in energy_models if data is not None else []:
        try:
            model = m.removeprefix("energy_ls_")
            out.append(energy_least_squares(t, model=model, rig=rig, data=data))
        except BayestriboError as exc:
            out.append(_failed(m, "energy", exc))
    return EstimateTable(out, run=None if name is None else str(name))
