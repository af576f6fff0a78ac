"""Figures of a campaign analysis (matplotlib, no display needed).

* :func:`plot_against_load`: group means of ζ and μ_k against load with their
  credible intervals, one series per colour, beside the paper's values (section 3.1:
  ζ = 0.0236, σ 0.0012; μ_k = 0.0294, σ 0.0036) as a band of ± one σ;
* :func:`plot_forest`: each run's ζ and μ_k with its credible interval, and a panel
  of the intervals' relative widths on a log scale (a run's interval is often 10⁻⁴ of
  the spread between runs: invisible beside its dot, readable in that panel);
* :func:`plot_derived`: ζ_k and d_k per group against load;
* :func:`plot_against_viscosity`: a glycerol–water series' group means of ζ and μ_k
  against the kinematic viscosity ν of Eq. 43, one colour per load, beside the
  paper's glycerol values and the 6 % water above which its μ_k rises (Fig. 10).

Each function draws on the figure it is given (a new one if None) and returns it;
:func:`save_figures` is the one that writes files.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from bayestribo._text import literal
from bayestribo.campaign.analysis import CampaignAnalysis
from bayestribo.population.groups import group_words
from bayestribo.summary import summarize

__all__ = [
    "PAPER_VALUES",
    "plot_against_load",
    "plot_against_viscosity",
    "plot_derived",
    "plot_forest",
    "save_figures",
]

#: Paper values of the glycerol series (mean, repeat sd), section 3.1.
PAPER_VALUES = {"zeta": (0.0236, 0.0012), "mu_k": (0.0294, 0.0036)}
_LABELS = {"zeta": "ζ", "mu_k": "μ_k"}

#: Water mass fraction of the paper's glycerol (measured, section 3.1) and the one up to
#: which its μ_k keeps the glycerol value (section 3.2, Fig. 10).
GLYCEROL_WATER, MU_K_CONSTANT_UP_TO = 0.0055, 0.06


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


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _series_label(analysis: CampaignAnalysis, value: Any) -> str:
    """A series' legend label in words ("glycerol, water 0.55 % by mass")."""
    keys = [k for k in analysis.by if k != analysis.covariate]
    values = value if isinstance(value, tuple) else (value,)
    pairs = [f"{k}={v}" for k, v in zip(analysis.by, values, strict=False) if k in keys]
    return literal(group_words(",".join(pairs)) if pairs else "all")


def _ticks(ax: Any, axis: str = "x") -> None:
    """At most four plain tick labels: values of 0.0236 and 0.0237 never run together."""
    from matplotlib.ticker import MaxNLocator, ScalarFormatter

    target = ax.xaxis if axis == "x" else ax.yaxis
    target.set_major_locator(MaxNLocator(4))
    formatter = ScalarFormatter(useOffset=False)
    formatter.set_powerlimits((-3, 4))
    target.set_major_formatter(formatter)


def _new_figure(fig: Any, size: tuple[float, float]) -> Any:
    if fig is None:
        fig = _pyplot().figure(figsize=size, layout="constrained")
    return fig


def plot_against_load(analysis: CampaignAnalysis, fig: Any = None) -> Any:
    """ζ and μ_k group means against load, with intervals, each run's median beside its
    group, and the paper's values where the series is glycerol.

    Parameters
    ----------
    analysis : CampaignAnalysis
    fig : matplotlib Figure, optional
        Empty figure to draw on (two axes are added); a new one if None.

    Returns
    -------
    matplotlib Figure
    """
    fig = _new_figure(fig, (10, 4))
    axes = fig.subplots(1, 2)
    pop = analysis.contact
    if pop is not None and analysis.covariate in analysis.by:
        i_load = analysis.by.index(analysis.covariate)
        series: dict[str, list[Any]] = {}
        for value, g in pop.groups.items():
            values = value if isinstance(value, tuple) else (value,)
            series.setdefault(_series_label(analysis, value), []).append((values[i_load], g))
        # each run's median as a small dot beside its group's mean, in the series' colour
        repeats: dict[str, list[dict[str, Any]]] = {}
        for r in analysis.runs:
            if r.get(analysis.covariate) is None or "mu_k" not in r:
                continue
            value = tuple(r.get(k) for k in analysis.by)
            repeats.setdefault(_series_label(analysis, value), []).append(r)
        for k, (label, members) in enumerate(sorted(series.items())):
            members.sort(key=lambda m: m[0])
            shift = 0.004 * (k - (len(series) - 1) / 2)
            colour = f"C{k % 10}"
            for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
                x = np.array([m[0] for m in members], dtype=float) + shift
                s = [summarize(m[1].mean[name], analysis.prob) for m in members]
                med = np.array([v["median"] for v in s])
                err = np.array(
                    [[v["median"] - v["interval"][0], v["interval"][1] - v["median"]] for v in s]
                ).T
                ax.errorbar(x, med, yerr=err, fmt="o", capsize=3, color=colour, label=label)
                runs = [r for r in repeats.get(label, []) if name in r]
                if runs:
                    ax.plot(
                        np.array([r[analysis.covariate] for r in runs], dtype=float)
                        + shift
                        + 0.002,
                        [r[name]["median"] for r in runs],
                        ".",
                        ms=4,
                        alpha=0.6,
                        color=colour,
                        label="a run (median)" if k == 0 else None,
                    )
    glycerol = pop is not None and any(
        "glycerol" in str(v) and "glycerol-water" not in str(v) for v in pop.groups
    )
    for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
        if glycerol:  # the paper's values are those of glycerol
            mean, sd = PAPER_VALUES[name]
            ax.axhspan(mean - sd, mean + sd, color="0.85", zorder=0, label="paper, glycerol")
            ax.axhline(mean, color="0.5", lw=1, zorder=0)
        ax.set_xlabel("load N [N]")
        ax.set_ylabel(f"population mean of {_LABELS[name]} [-]")
        ax.grid(alpha=0.3)
        _ticks(ax, "y")
        _ticks(ax, "x")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize="small")
    fig.suptitle(f"Group means with {100 * analysis.prob:.0f} % credible intervals")
    return fig


def _value_label(key: str, value: Any) -> str:
    """A legend entry for a metadata value: ``load 0.07 N``, not ``load_N = 0.07``."""
    if value is None:
        return f"no {key}"
    if key == "load_N":
        return f"load {value:g} N"
    return literal(f"{key} = {value}")


def plot_forest(
    analysis: CampaignAnalysis,
    fig: Any = None,
    truth: Mapping[str, Mapping[str, float]] | None = None,
) -> Any:
    """Each run's ζ and μ_k with its credible interval, and the intervals' widths.

    One row per run, coloured by load. The third panel gives each interval's width
    relative to the run's median on a log scale, so intervals far narrower than the
    spread between runs (invisible beside their dots) can still be read and compared.

    Parameters
    ----------
    analysis : CampaignAnalysis
    fig : matplotlib Figure, optional
        Empty figure to draw on (three axes are added); a new one if None.
    truth : mapping, optional
        Run id -> {"zeta": ..., "mu_k": ...}: true values of simulated runs (crosses).

    Returns
    -------
    matplotlib Figure
    """
    runs = analysis.runs
    fig = _new_figure(fig, (11, max(3.0, 0.22 * len(runs) + 1.4)))
    axes = fig.subplots(1, 3, sharey=True, gridspec_kw={"width_ratios": [1.2, 1.2, 1]})
    y = np.arange(len(runs))[::-1]
    loads = sorted({r.get(analysis.covariate) for r in runs}, key=lambda v: (v is None, v))
    colour = {v: f"C{i % 10}" for i, v in enumerate(loads)}
    for k, (ax, name) in enumerate(zip(axes[:2], ("zeta", "mu_k"), strict=True)):
        for yi, run in zip(y, runs, strict=True):
            if name not in run:
                continue
            c = colour[run.get(analysis.covariate)]
            lo, hi = run[name]["interval"]
            med = run[name]["median"]
            ax.plot([lo, hi], [yi, yi], color=c, lw=2)
            ax.plot(med, yi, "o", color=c, ms=3)
            if hi > lo and med:
                axes[2].plot(
                    (hi - lo) / abs(med),
                    yi,
                    "o^"[k],
                    color=c,
                    ms=4,
                    mfc="none" if k else c,
                )
            true = (truth or {}).get(str(run.get("run_id")), {}).get(name)
            if true is not None:  # a tick, not hiding the run's coloured dot
                ax.plot(true, yi, "k|", ms=9, mew=1.2)
        ax.set_xlabel(f"{_LABELS[name]} [-]")
        ax.grid(alpha=0.3)
        _ticks(ax)
    _decades(axes[2])
    axes[2].set_xlabel("interval width / median [-]\n(o: ζ, △: μ_k)")
    axes[2].grid(alpha=0.3)
    # 8 pt: the smallest a journal prints; a row is 0.22 in (16 pt) high
    axes[0].set_yticks(y, [literal(r["run_id"]) for r in runs], fontsize=8)
    handles = [
        axes[0].plot([], [], "o-", color=colour[v], label=_value_label(analysis.covariate, v))[0]
        for v in loads
    ]
    if truth:
        handles.append(axes[0].plot([], [], "k|", ms=9, mew=1.2, label="true value")[0])
    fig.legend(
        handles=handles, loc="outside lower center", ncols=min(6, len(handles)), fontsize="small"
    )
    fig.suptitle(f"Runs: medians and {100 * analysis.prob:.0f} % credible intervals")
    return fig


def plot_derived(analysis: CampaignAnalysis, fig: Any = None) -> Any:
    """ζ_k = ζ − ζ₀ and d_k per contact group against load.

    Parameters
    ----------
    analysis : CampaignAnalysis
    fig : matplotlib Figure, optional
        Empty figure to draw on (two axes are added); a new one if None.

    Returns
    -------
    matplotlib Figure
    """
    fig = _new_figure(fig, (10, 4))
    axes = fig.subplots(1, 2)
    rows = [r for r in analysis.derived if "load_N" in r]
    # one colour and legend entry per series (the group without its load), placed side
    # by side at each load, as in plot_against_load
    series: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        series.setdefault(_series_of(str(r["group"])), []).append(r)
    for k, (name, members) in enumerate(sorted(series.items())):
        shift = 0.004 * (k - (len(series) - 1) / 2)
        for ax, key in ((axes[0], "zeta_k"), (axes[1], "d_k_s_per_m")):
            x = np.array([r["load_N"] for r in members], dtype=float) + shift
            med = np.array([r[key]["median"] for r in members])
            lo = np.array([r[key]["interval"][0] for r in members])
            hi = np.array([r[key]["interval"][1] for r in members])
            ax.errorbar(x, med, yerr=[med - lo, hi - med], fmt="o", capsize=3, label=name)
    for ax, label in ((axes[0], "ζ_k = ζ − ζ₀ [-]"), (axes[1], "d_k [s/m]")):
        ax.set_xlabel("load N [N]")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        _ticks(ax, "y")
        _ticks(ax, "x")
    if len(series) > 1:
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize="small")
    fig.suptitle(f"Contact damping per group: median and {100 * analysis.prob:.0f} % interval")
    return fig


def _series_of(group: str) -> str:
    """A contact group's label without its load, as the legend shows it: ``glycerol,
    water 0.55 % by mass`` for ``lubricant=glycerol,water_mass_fraction=0.0055,load_N=0.12``."""
    parts = [item for item in group.split(",") if item.partition("=")[0] != "load_N"]
    return literal(group_words(",".join(parts)) if parts else "all")


def save_figures(analysis: CampaignAnalysis, folder: str | Path) -> list[Path]:
    """Write the three figures as PNG files in ``folder``; return their paths."""
    plt = _pyplot()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, make in (
        ("means_vs_load", plot_against_load),
        ("forest", plot_forest),
        ("zeta_k_d_k", plot_derived),
    ):
        fig = make(analysis)
        path = folder / f"{name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        out.append(path)
    return out


def plot_against_viscosity(analysis: CampaignAnalysis, fig: Any = None) -> Any:
    """ζ and μ_k of a glycerol–water series against the lubricant's kinematic viscosity.

    Each group's population mean (a water fraction at one load) with its credible
    interval, one colour per load, each run's median beside it; the paper's glycerol
    values (0.55 % water, mean ± the repeats' σ, section 3.1) as a diamond, and a dotted
    line at 6 % water: the paper's μ_k keeps its glycerol value at higher viscosities
    and rises below (section 3.2, Fig. 10). ν of each water fraction is Eq. 43's.

    Parameters
    ----------
    analysis : CampaignAnalysis
        Grouped by the water mass fraction (and the load).
    fig : matplotlib Figure, optional
        Empty figure to draw on (two axes are added); a new one if None.

    Returns
    -------
    matplotlib Figure
    """
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    from bayestribo.model.viscosity import glycerol_water_viscosity

    def nu(water: Any) -> float:
        return float(glycerol_water_viscosity(float(water)))

    fig = _new_figure(fig, (10, 4))
    axes = fig.subplots(1, 2)
    pop, by = analysis.contact, analysis.by
    if pop is not None and "water_mass_fraction" in by:
        i_w = by.index("water_mass_fraction")
        i_n = by.index("load_N") if "load_N" in by else None
        series: dict[Any, list[tuple[float, Any]]] = {}
        for value, g in pop.groups.items():
            values = value if isinstance(value, tuple) else (value,)
            load = values[i_n] if i_n is not None else None
            series.setdefault(load, []).append((nu(values[i_w]), g))
        loads = sorted(series, key=lambda v: (v is None, v or 0.0))
        for k, load in enumerate(loads):
            members = sorted(series[load], key=lambda m: m[0])
            factor = 1.0 + 0.02 * (k - (len(loads) - 1) / 2)  # apart on the log axis
            colour = f"C{k % 10}"
            where = "all loads" if load is None else f"N = {load:g} N"
            runs = [
                r
                for r in analysis.runs
                if r.get("water_mass_fraction") is not None
                and (load is None or r.get("load_N") == load)
            ]
            for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
                x = np.array([m[0] for m in members]) * factor
                s = [summarize(m[1].mean[name], analysis.prob) for m in members]
                med = np.array([v["median"] for v in s])
                err = np.array(
                    [[v["median"] - v["interval"][0], v["interval"][1] - v["median"]] for v in s]
                ).T
                ax.errorbar(x, med, yerr=err, fmt="s-", ms=4, capsize=3, color=colour, label=where)
                shown = [r for r in runs if name in r]
                if shown:
                    ax.plot(
                        [nu(r["water_mass_fraction"]) * factor * 1.01 for r in shown],
                        [r[name]["median"] for r in shown],
                        ".",
                        ms=4,
                        alpha=0.6,
                        color=colour,
                        label="a run (median)" if k == 0 else None,
                    )
    for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
        mean, sd = PAPER_VALUES[name]
        ax.errorbar(
            [nu(GLYCEROL_WATER)],
            [mean],
            yerr=[sd],
            fmt="D",
            ms=7,
            mfc="none",
            capsize=3,
            color="0.3",
            label="paper, glycerol (mean ± σ)",
        )
        ax.axvline(
            nu(MU_K_CONSTANT_UP_TO),
            color="0.5",
            ls=":",
            lw=1,
            label=f"{100 * MU_K_CONSTANT_UP_TO:g} % water",
        )
        ax.set_xscale("log")
        ax.set_xticks([200, 300, 500, 700, 1000])
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("kinematic viscosity ν [mm²/s]")
        ax.set_ylabel(f"population mean of {_LABELS[name]} [-]")
        _ticks(ax, "y")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize="small")
    fig.suptitle(
        f"Glycerol–water: group means with {100 * analysis.prob:.0f} % credible intervals "
        "against viscosity"
    )
    return fig
