"""Figures of the adequacy checks (matplotlib).

Each function draws on the axes or figure it is given (a new one if none) and
returns it; none shows or saves a figure.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bayestribo.adequacy.constancy import ConstancyTest
from bayestribo.adequacy.extinction import ExtinctionCheck
from bayestribo.adequacy.halves import SplitHalves
from bayestribo.adequacy.predictive import PredictiveCheck
from bayestribo.adequacy.windows import WindowedAnalysis

__all__ = ["plot_extinction", "plot_peak_residuals", "plot_windows"]


def _figure(fig: Any, nrows: int) -> Any:
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(6.4, 2.6 * nrows))
    if not fig.axes:
        fig.subplots(nrows, 1, sharex=True)
    return fig


def plot_windows(
    windows: WindowedAnalysis,
    constancy: ConstancyTest | None = None,
    fig: Any = None,
    halves: SplitHalves | None = None,
) -> Any:
    """ζ and μ per window against the window amplitude, with 95 % intervals.

    The friction's panel is left out when the windows do not fit the friction (it is
    held at the whole decay's value, as for a decay without measurable friction) or
    when it is zero in every window: such a panel has nothing to show. Horizontal bars
    span each window's amplitude range; the constancy test's line
    (if given) is drawn over the windows it used. Windows whose estimate sits on a
    parameter bound are drawn as crosses, and the vertical scale is set by the
    other windows (a bound estimate's interval is meaningless and huge). The two
    halves of the split-half check (if given) are shaded boxes: each spans its
    half's amplitude range and its 95 % interval.

    Parameters
    ----------
    windows : WindowedAnalysis
    constancy : ConstancyTest, optional
    fig : matplotlib Figure, optional
        With two axes, or empty (two are added, or one without the friction's panel;
        of two given axes the second is removed then).
    halves : SplitHalves, optional
        The split-half check (:func:`bayestribo.adequacy.halves.split_halves`).

    Returns
    -------
    matplotlib Figure
    """
    friction = windows.column("mu")
    friction_iv = np.array([w.mu_interval for w in windows.windows], dtype=float)
    shown = windows.extra.get("friction_mode", "fit") != "fixed" and bool(
        np.nanmax(np.abs(np.concatenate([friction, friction_iv.ravel()])), initial=0.0) > 1e-12
    )
    fig = _figure(fig, 2 if shown else 1)
    if not shown and len(fig.axes) > 1:
        fig.delaxes(fig.axes[1])
    ax_z = fig.axes[0]
    ax_m = fig.axes[1] if shown else None
    amp = windows.column("amplitude")
    lo_a = amp - np.array([w.amplitude_range[0] for w in windows.windows])
    hi_a = np.array([w.amplitude_range[1] for w in windows.windows]) - amp
    regular = np.array([w.regular for w in windows.windows])
    panels = [(ax_z, "zeta", None if constancy is None else constancy.zeta)]
    if shown:
        panels.append((ax_m, "mu", None if constancy is None else constancy.mu))
    for ax, name, trend in panels:
        val = windows.column(name)
        iv = np.array([getattr(w, f"{name}_interval") for w in windows.windows])
        err = np.vstack([val - iv[:, 0], iv[:, 1] - val])
        for mask, style in ((regular, "o"), (~regular, "x")):
            if np.any(mask):
                ax.errorbar(
                    amp[mask],
                    val[mask],
                    yerr=err[:, mask],
                    xerr=np.vstack([lo_a, hi_a])[:, mask],
                    fmt=style,
                    capsize=2,
                    label="on a bound"
                    if style == "x"
                    else f"{windows.method.replace('_', ' ')} per window",
                )
        if halves is not None and name in halves.parameters:
            for k, (half, colour) in enumerate(((halves.first, "C1"), (halves.second, "C2"))):
                lo_h, hi_h = getattr(half, f"{name}_interval")
                ax.fill_between(
                    list(half.amplitude_range),
                    [lo_h, lo_h],
                    [hi_h, hi_h],
                    color=colour,
                    alpha=0.25,
                    label=f"{('first', 'second')[k]} half" if name == "zeta" else None,
                )
        if np.any(regular):
            # scale on the regular windows: estimates on a bound have huge intervals
            lo, hi = float(np.min(iv[regular, 0])), float(np.max(iv[regular, 1]))
            if halves is not None and name in halves.parameters:
                for half in (halves.first, halves.second):
                    if half.regular:
                        lo = min(lo, getattr(half, f"{name}_interval")[0])
                        hi = max(hi, getattr(half, f"{name}_interval")[1])
            pad = 0.15 * (hi - lo) if hi > lo else 0.05 * max(abs(hi), 1e-12)
            ax.set_ylim(lo - pad, hi + pad)
        if trend is not None:
            a = np.linspace(*constancy.amplitude_range, 50)
            mean_amp = float(np.mean(amp[regular]))
            ax.plot(a, trend.mean + trend.slope * (a - mean_amp), "k--", label="trend")
        ax.grid(alpha=0.3)
    ax_z.set_ylabel("ζ [-]")
    symbol = windows.friction_symbol
    if ax_m is None:
        ax_z.set_xlabel(f"window amplitude [{windows.length_unit}]")
    elif windows.friction_name == "mu_k":
        ax_m.set_ylabel("μ_k [-]")
    else:  # the friction displacement x_c (angle θ_c), in the signal's unit
        ax_m.set_ylabel(f"{symbol} [{windows.length_unit}]")
    if ax_m is not None:
        ax_m.set_xlabel(f"window amplitude [{windows.length_unit}]")
    ax_z.legend(fontsize="small")
    titles = []
    if ax_m is None:
        held = windows.extra.get("friction_mode", "fit") == "fixed"
        titles.append(f"{symbol} held at the whole decay's value" if held else f"{symbol} = 0")
    if constancy is not None:
        titles.append(
            ("constant" if constancy.constant else "not constant")
            + f" (p = {constancy.p_value:.2g})"
        )
    if halves is not None:
        titles.append(
            ("halves agree" if halves.consistent else "halves disagree")
            + f" (p = {halves.p_value:.2g})"
        )
    if titles:
        ax_z.set_title("; ".join(titles))
    return fig


def plot_extinction(check: ExtinctionCheck, ax: Any = None) -> Any:
    """Predicted end of motion (exact model and Eq. 38) against the measured one.

    Each model's predictions over the draws are shown as their median and the central
    interval the check tests (``1 - check.alpha``: 95 %, or 98.3 % in the verdict of
    :func:`~bayestribo.adequacy.check_adequacy`), on the scale of the difference from
    the measured end (or from the record's end when the motion outlasts the record) in
    milliseconds, so that intervals far narrower than the time since the release stay
    visible; the measured end's resolution (two sample periods) is the grey band around
    zero. A model whose
    draws never stop is said so on its row, and so is Eq. 38 where it was not evaluated
    (a nonlinear restoring force).

    Parameters
    ----------
    check : ExtinctionCheck
    ax : matplotlib Axes, optional
        Drawn on (a new figure's axes if None).

    Returns
    -------
    matplotlib Axes
    """
    from matplotlib.ticker import MaxNLocator

    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6.4, 2.4))
    ref = check.measured if check.measured is not None else check.record_end
    ms = 1e3
    rows = (("exact model", check.exact, "C0"), ("averaged, Eq. 38", check.averaged, "C1"))
    spans = [0.0, check.resolution * ms, -check.resolution * ms]
    for y, (label, values, color) in zip((1, 0), rows, strict=True):
        finite = (values[np.isfinite(values)] - ref) * ms
        if values is check.averaged and check.averaged_note:
            ax.text(0.0, y, f"{label}: none on this restoring force", ha="center", fontsize=9)
            continue
        if finite.size == 0:
            ax.text(0.0, y, f"{label}: never stops", ha="center", va="center", fontsize=9)
            continue
        tail = 0.5 * check.alpha
        lo, med, hi = np.quantile(finite, [tail, 0.5, 1.0 - tail])
        ax.plot([lo, hi], [y, y], color=color, lw=3, solid_capstyle="butt")
        ax.plot([med], [y], "o", color=color, ms=6, label=f"{label}: median, {check.interval_text}")
        spans += [lo, hi]
    if check.resolution > 0:
        ax.axvspan(
            -check.resolution * ms,
            check.resolution * ms,
            color="0.85",
            zorder=0,
            label="measured end ± resolution" if check.measured is not None else None,
        )
    ax.axvline(0.0, color="k", lw=1)
    lo, hi = min(spans), max(spans)
    pad = 0.15 * (hi - lo) if hi > lo else 1.0
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_ylim(-0.7, 1.7)
    ax.set_yticks([1, 0], [r[0] for r in rows])
    ax.xaxis.set_major_locator(MaxNLocator(6))
    what = "measured end" if check.measured is not None else "end of the analysis (still moving)"
    ax.set_xlabel(f"predicted end of motion − {what} [ms]")
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ax


def plot_peak_residuals(check: PredictiveCheck, fig: Any = None) -> Any:
    """Peak residuals (recorded minus predicted) with their 95 % predictive intervals.

    Top: displacement peaks |Y_n|; bottom: velocity peaks, both dimensionless.

    Returns
    -------
    matplotlib Figure
    """
    fig = _figure(fig, 2)
    for ax, peaks in zip(fig.axes[:2], (check.displacement, check.velocity), strict=True):
        ax.fill_between(
            peaks.t,
            peaks.low - peaks.predicted,
            peaks.high - peaks.predicted,
            color="C0",
            alpha=0.3,
            step="mid",
            label="95 % predictive interval",
        )
        ax.plot(peaks.t, peaks.residual, "o", ms=3, color="C1", label="recorded - predicted")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_ylabel(f"{peaks.kind} peak residual [-]")
        ax.grid(alpha=0.3)
    fig.axes[0].legend(fontsize="small")
    fig.axes[0].set_title(
        f"{100 * check.coverage:.0f} % inside, RMS standardized {check.rms_standardized:.2g}"
    )
    fig.axes[1].set_xlabel("t [s]")
    return fig
