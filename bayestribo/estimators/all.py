"""Run every applicable classical estimator on one recording: :func:`estimate_all`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal

from numpy.typing import ArrayLike

from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.estimators.decrement import exponential_envelope, log_decrement
from bayestribo.estimators.energy_ls import energy_data, energy_least_squares
from bayestribo.estimators.feeny_liang import feeny_liang
from bayestribo.estimators.nonsuccessive import nonsuccessive_peaks
from bayestribo.estimators.result import Estimate, EstimateTable
from bayestribo.model.scaling import Rig
from bayestribo.signal.peaks import Peaks, find_peaks

__all__ = ["METHODS", "estimate_all"]

#: Method names, in the order of the table.
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


def estimate_all(
    run: Any,
    x: ArrayLike | None = None,
    v: ArrayLike | None = None,
    *,
    rig: Rig | None = None,
    skip: int = 0,
    offset: float | Literal["auto", "constant"] | None = "auto",
    methods: Sequence[str] | None = None,
    name: str | None = None,
) -> EstimateTable:
    """Every applicable classical estimator on one recording, as a table.

    Parameters
    ----------
    run : Run or array_like
        A :class:`bayestribo.io.run.Run` (its time, displacement, velocity, rig and
        source are used), or the sample times t [s] with ``x`` and/or ``v``.
    x, v : array_like, optional
        Displacement and velocity when ``run`` is an array of times.
    rig : Rig, optional
        Overrides the run's rig. Without any rig Ω comes from the recording and
        friction is reported as a friction displacement in the signal's unit.
    skip : int
        Leading extrema to skip (2 = the first oscillation).
    offset : float, "auto", "constant" or None
        Equilibrium of the displacement (see :func:`bayestribo.signal.peaks.find_peaks`).
    methods : sequence of str, optional
        Subset of :data:`METHODS` (default all). The peak methods run on the
        displacement peaks and, when a velocity is recorded, on the velocity peaks.
    name : str, optional
        Name of the run in the table (default: the run's source).

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
    if hasattr(run, "time") and hasattr(run, "displacement"):
        if x is not None or v is not None:
            raise RecordingError("give either a Run or arrays t, x, v, not both")
        t = run.time
        x, v = run.displacement, run.velocity
        if rig is None and hasattr(run, "rig"):
            rig = run.rig()
        name = name if name is not None else getattr(run, "source", None)
    else:
        t = run
    if x is None and v is None:
        raise RecordingError("estimate_all needs a displacement x or a velocity v")
    chosen = list(METHODS if methods is None else methods)
    unknown = [m for m in chosen if m not in METHODS]
    if unknown:
        raise RecordingError(f"unknown method(s) {unknown}; expected some of {list(METHODS)}")

    out: list[Estimate] = []
    signals = [(kind, s) for kind, s in (("displacement", x), ("velocity", v)) if s is not None]
    peak_methods = [m for m in chosen if m in _PEAK_METHODS]
    for kind, s in signals:
        if not peak_methods:
            break
        try:
            pk = find_peaks(
                t, s, kind=kind, skip=skip, offset=offset if kind == "displacement" else "auto"
            )
        except BayestriboError as exc:
            out += [_failed(m, f"{kind} peaks", exc) for m in peak_methods]
            continue
        for m in peak_methods:
            try:
                out.append(_PEAK_METHODS[m](pk, rig))
            except BayestriboError as exc:
                out.append(_failed(m, f"{kind} peaks (n={len(pk)})", exc))

    energy_models = [m for m in chosen if m.startswith("energy_ls_")]
    if energy_models:
        try:
            first = energy_data(t, x, v, rig=rig, skip=skip, offset=offset)
            try:
                guess = feeny_liang(first.peaks, rig).zeta
            except BayestriboError:
                guess = None
            data = energy_data(t, x, v, rig=rig, skip=skip, offset=offset, zeta_guess=guess)
        except BayestriboError as exc:
            out += [_failed(m, "energy", exc) for m in energy_models]
        else:
            for m in energy_models:
                try:
                    out.append(
                        energy_least_squares(
                            t, model=m.removeprefix("energy_ls_"), rig=rig, data=data
                        )
                    )
                except BayestriboError as exc:
                    out.append(_failed(m, "energy", exc))
    return EstimateTable(out, run=None if name is None else str(name))
