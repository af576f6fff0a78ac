"""Figures of the reports that are not a library result's own (matplotlib).

:func:`plot_estimates` draws estimates of several quantities with their intervals, one
row per estimate, beside a panel of the intervals' widths as fractions of their value
axis, on a log scale: an interval 10⁻⁴ of the axis is invisible in the value panels but
reads at once in the width panel. Functions draw on the axes they are given and return them; none
shows or saves a figure.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from bayestribo._text import literal

__all__ = ["plot_estimates"]

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
