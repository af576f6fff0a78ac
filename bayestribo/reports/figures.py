"""Figures of the reports that are not a library result's own (matplotlib).

:func:`plot_estimates` draws estimates of several quantities with their intervals, one
row per estimate, beside a panel of the intervals' widths as fractions of their value
axis, on a log scale: an interval 10⁻⁴ of the axis is invisible in the value panels but
reads at once in the width panel. :func:`plot_dissipation` draws the energy a fit's
law dissipates per cycle, ΔE(A), with its band, and the turning points' ΔE(A) on the
same log-log axes. Functions draw
on the axes they are given and return them; none shows or saves a figure.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from bayestribo._text import literal

__all__ = ["half_cycle_losses", "plot_dissipation", "plot_estimates"]

_MARKERS = ("o", "^", "s", "D")


def _decades(ax: Any) -> None:
    """A log x axis spanning whole decades, labelled at the decades only.

    Labels at minor ticks (3×10⁻⁵, 4×10⁻⁵, ...) run together; whole decades give at
    least two labelled ticks.
    """
    from matplotlib.ticker import LogLocator, NullFormatter

    ax.set_xscale("log")
    lo, hi = ax.dataLim.intervalx
    if np.isfinite(lo) and np.isfinite(hi) and lo > 0:
        ax.set_xlim(10.0 ** np.floor(np.log10(lo)), 10.0 ** np.ceil(np.log10(hi) + 1e-12))
    ax.xaxis.set_major_locator(LogLocator(base=10.0, numticks=6))
    ax.xaxis.set_minor_formatter(NullFormatter())


def plot_estimates(
    axes: Sequence[Any],
    labels: Sequence[str],
    estimates: Mapping[str, tuple[Sequence[float], Sequence[float], Sequence[float]]],
    *,
    truth: Mapping[str, float | None] | None = None,
    highlight: int | None = None,
) -> Sequence[Any]:
    """Estimates with intervals per quantity, and the intervals' widths on a log scale.

    Parameters
    ----------
    axes : sequence of matplotlib Axes
        One per quantity for the values, then one for the widths (``len(estimates) + 1``),
        sharing the y axis.
    labels : sequence of str
        One per estimate (row), top to bottom.
    estimates : mapping
        Quantity label (with its unit) -> ``(value, low, high)`` arrays, one entry per
        row; NaN where an estimate has no value or no interval.
    truth : mapping, optional
        Quantity label -> true value (a dashed line), for a simulated run.
    highlight : int, optional
        Row drawn as a red square (the Bayesian posterior).

    Returns
    -------
    sequence of matplotlib Axes
        ``axes``. The width panel shows each interval's width as a fraction of its value
        panel's span, on a log scale [-] (an estimate near zero has no meaningful
        relative width; the fraction of the axis is what decides whether it is seen).
    """
    from matplotlib.ticker import MaxNLocator

    n = len(labels)
    y = np.arange(n)[::-1].astype(float)
    *value_axes, width_ax = axes
    for k, ((name, (val, lo, hi)), ax) in enumerate(
        zip(estimates.items(), value_axes, strict=True)
    ):
        val, lo, hi = (np.asarray(a, dtype=float) for a in (val, lo, hi))
        has = np.isfinite(lo) & np.isfinite(hi)
        # a point outside its interval (a posterior mean in a long tail) draws the
        # interval's side it lies beyond as zero, not a negative error bar
        err = np.vstack([np.where(has, val - lo, 0.0), np.where(has, hi - val, 0.0)])
        err = np.maximum(err, 0.0)
        ax.errorbar(val, y, xerr=err, fmt="o", color="C0", capsize=3, ms=5)
        if highlight is not None and np.isfinite(val[highlight]):
            ax.errorbar(
                val[highlight : highlight + 1],
                y[highlight : highlight + 1],
                xerr=err[:, highlight : highlight + 1],
                fmt="s",
                color="C3",
                capsize=3,
                ms=6,
            )
        true = None if truth is None else truth.get(name)
        if true is not None and np.isfinite(true):
            ax.axvline(true, color="k", ls="--", lw=1, label="true value")
            ax.legend(fontsize="small", loc="best")
        ax.set_xlabel(name)
        ax.xaxis.set_major_locator(MaxNLocator(4))
        ax.ticklabel_format(axis="x", useOffset=False)
        left, right = ax.get_xlim()
        rel = (hi - lo) / (right - left)  # the fraction of the value panel it spans
        ok = np.isfinite(rel) & (rel > 0)
        width_ax.plot(
            rel[ok],
            y[ok],
            _MARKERS[k % len(_MARKERS)],
            color=f"C{k + 1}",
            ms=6,
            alpha=0.85,
            label=name.split(" [")[0],
        )
    _decades(width_ax)
    width_ax.set_xlabel("interval width / span of the value axis [-]")
    width_ax.legend(fontsize="small", loc="best")
    value_axes[0].set_yticks(y, [literal(label) for label in labels])
    return axes


def half_cycle_losses(
    turning_points: Any, stiffness: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Each half cycle's energy loss, per cycle, at its swing: ``k (Y_n² - Y_n+1²)`` at
    ``(|Y_n| + |Y_n+1|)/2`` (a linear spring; twice the half cycle's loss, as ΔE(A) of
    :func:`bayestribo.inference.dissipation.turning_point_dissipation` counts it).

    Parameters
    ----------
    turning_points : array_like
        Turning points about the equilibrium, in order [length].
    stiffness : float, optional
        k [N/m] for energies in joules; None: ΔE/k [length²], as a fit's ΔE(A) is where
        the stiffness is not known.

    Returns
    -------
    swing, loss : ndarray
        Empty where fewer than two turning points are given.

    Examples
    --------
    >>> swing, loss = half_cycle_losses([1.0, -0.9, 0.8])
    >>> swing.round(2).tolist(), loss.round(2).tolist()
    ([0.95, 0.85], [0.19, 0.17])
    """
    y = np.abs(np.asarray(turning_points, dtype=float))
    if y.size < 2:
        return np.array([]), np.array([])
    k = 1.0 if stiffness is None else float(stiffness)
    return 0.5 * (y[:-1] + y[1:]), k * (y[:-1] ** 2 - y[1:] ** 2)


def _positive_band(band: Mapping[str, Any]) -> tuple[np.ndarray, ...]:
    """Swing, mean, lower and upper end of a ΔE(A) band, the lower end held at zero
    (ΔE of a free decay is never negative: an interval reaching below zero is at its
    bound there), sorted by swing; NaN where a value is missing."""

    def arr(values: Any) -> np.ndarray:
        return np.array([np.nan if v is None else v for v in values], dtype=float)

    amp = arr(band["amplitude"])
    mean = arr(band["mean"])
    low, high = arr(band["interval"][0]), arr(band["interval"][1])
    order = np.argsort(amp)
    return amp[order], mean[order], np.maximum(low[order], 0.0), high[order]


def plot_dissipation(
    ax: Any,
    law_band: Mapping[str, Any] | None,
    measured: Mapping[str, Any] | None,
    *,
    points: tuple[Any, Any] | None = None,
    law_label: str = "the law's ΔE(A)",
    color: str = "C0",
    holds: bool = True,
) -> Any:
    """ΔE(A): the law's band, the turning points' band and points, log-log.

    Parameters
    ----------
    ax : matplotlib Axes
    law_band : mapping or None
        A fit's ΔE(A) (:attr:`bayestribo.inference.result.FitResult.dissipation`):
        drawn as its mean and a shaded band.
    measured : mapping or None
        The turning points' ΔE(A) at the same swings
        (:attr:`~bayestribo.inference.result.FitResult.turning_point_dissipation`): drawn as
        points with their intervals (the law-free answer).
    points : (swing, loss), optional
        Each half cycle's loss (:func:`half_cycle_losses`), drawn as small grey dots.
    law_label : str
        Legend text of the law's band.
    color : str
        Colour of the law's band.
    holds : bool
        Whether the law holds: a law that does not is drawn dashed, its label saying so.

    Returns
    -------
    matplotlib Axes
        ``ax``, on log-log axes. ΔE is never negative: an interval whose lower end
        reaches zero is drawn down to the axis' bottom (a log axis has no zero), and the
        axis spans the values, not the intervals' ends at zero.
    """
    from matplotlib.ticker import LogLocator, NullFormatter

    shown: list[np.ndarray] = []
    unit = None
    if points is not None and len(points[0]):
        swing, loss = (np.asarray(v, dtype=float) for v in points)
        ok = (swing > 0) & (loss > 0)
        ax.plot(swing[ok], loss[ok], ".", color="0.6", ms=3, label="each half cycle")
    if measured and measured.get("amplitude"):
        amp, mean, low, high = _positive_band(measured)
        ok = np.isfinite(mean) & (mean > 0)
        err = np.vstack([mean - low, high - mean])[:, ok]
        ax.errorbar(
            amp[ok],
            mean[ok],
            yerr=np.maximum(err, 0.0),
            fmt="s",
            color="k",
            ms=4,
            capsize=2,
            label=f"turning points (law-free), {100 * measured.get('prob', 0.95):g} %",
        )
        shown.append(mean[ok])
        unit = measured.get("unit")
    if law_band and law_band.get("amplitude"):
        amp, mean, low, high = _positive_band(law_band)
        ok = np.isfinite(mean) & (mean > 0)
        label = law_label if holds else f"{law_label} (does not hold)"
        ax.plot(amp[ok], mean[ok], "-" if holds else "--", color=color, lw=1.5, label=label)
        ax.fill_between(amp[ok], low[ok], high[ok], color=color, alpha=0.25, lw=0)
        shown.append(mean[ok])
        unit = unit or law_band.get("unit")
    ax.set_xscale("log")
    ax.set_yscale("log")
    values = np.concatenate(shown) if shown else np.array([])
    values = values[np.isfinite(values) & (values > 0)]
    if values.size:
        # the values' decades, with room: an interval at zero runs to the bottom
        ax.set_ylim(values.min() / 3.0, values.max() * 3.0)
    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        axis.set_major_locator(LogLocator(base=10.0, numticks=6))
        if lo > 0 and hi / lo > 10.0:  # whole decades labelled: the minor labels crowd
            axis.set_minor_formatter(NullFormatter())
    from bayestribo.reports.tables import unit_text

    amp_unit = unit_text((law_band or measured or {}).get("amplitude_unit"))
    ax.set_xlabel(f"swing A [{amp_unit}]")
    ax.set_ylabel(f"energy lost per cycle ΔE [{unit_text(unit)}]")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small", loc="best")
    return ax
