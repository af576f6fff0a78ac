"""Figures of a campaign analysis (matplotlib, no display needed), in any law.

Every figure takes its quantities from the analysis (``CampaignAnalysis.quantities``:
ζ and μ_k in the paper's law, ζ and c₂ [kg/m] in ``viscous+quadratic``, ...), one panel
per quantity, their symbols and units from the law registry; a group is drawn in the
panels of the quantities its law has.

* :func:`plot_against_load`: group means against load with their credible intervals,
  one series per colour (the law first where the runs have several), the trend's
  population mean against load as a band, and, beside ζ and μ_k of glycerol, the
  paper's values (section 3.1: ζ = 0.0236, σ 0.0012; μ_k = 0.0294, σ 0.0036) as a
  band of ± one σ;
* :func:`plot_forest`: each run's quantities with their credible intervals, and a
  panel of the intervals' relative widths on a log scale (a run's interval is often
  10⁻⁴ of the spread between runs: invisible beside its dot, readable in that panel);
* :func:`plot_derived`: ζ_k and d_k per group against load (where ζ is a quantity);
* :func:`plot_against_viscosity`: a glycerol–water series' group means against the
  kinematic viscosity ν of Eq. 43, one colour per load, beside the paper's glycerol
  values and the 6 % water above which its μ_k rises (Fig. 10);
* :func:`plot_dissipation`, :func:`plot_dissipation_against_load`: ΔE(A), the one
  quantity of every law (and of the law-free answer), per group of repeats and at a
  swing the runs share against load (:mod:`bayestribo.campaign.bands`).

Each function draws on the figure it is given (a new one if None) and returns it;
:func:`save_figures` is the one that writes files.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bayestribo._files import atomic_file
from bayestribo._text import literal
from bayestribo.campaign.analysis import CampaignAnalysis
from bayestribo.population.groups import group_words
from bayestribo.summary import summarize

__all__ = [
    "PAPER_VALUES",
    "plot_against_load",
    "plot_against_viscosity",
    "plot_derived",
    "plot_dissipation",
    "plot_dissipation_against_load",
    "plot_forest",
    "quantity_label",
    "quantity_names",
    "save_figures",
]

#: Paper values of the glycerol series (mean, repeat sd), section 3.1.
PAPER_VALUES = {"zeta": (0.0236, 0.0012), "mu_k": (0.0294, 0.0036)}
#: Symbols of the paper's quantities where an analysis does not describe them.
_PAPER_SYMBOLS = {"zeta": "ζ", "mu_k": "μ_k"}

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


def _keys(pop: Any) -> tuple[str, ...]:
    """A population's grouping keys as a tuple."""
    by = getattr(pop, "by", None)
    if by is None:
        return ()
    return (by,) if isinstance(by, str) else tuple(by)


def _group_meta(pop: Any, group: Any) -> dict[str, Any]:
    """A group's value of each grouping key."""
    keys = _keys(pop)
    values = group.value if isinstance(group.value, tuple) else (group.value,)
    return dict(zip(keys, values, strict=False))


def _words(label: str) -> str:
    return literal(group_words(label) if label else "all")


def _series_label(meta: Mapping[str, Any], covariate: str) -> str:
    """A series' legend label in words ("glycerol, water 0.55 % by mass"): its group's
    keys but the covariate (the law first where the runs have several)."""
    return _words(",".join(f"{k}={v}" for k, v in meta.items() if k != covariate))


def quantity_names(analysis: CampaignAnalysis, pop: Any = None) -> list[str]:
    """The quantities a figure draws, in the analysis' order: those of ``pop``'s groups
    (any of them), else those any run has."""
    if pop is not None:
        held = {n for g in pop.groups.values() for n in g.parameters}
        if pop.pooled is not None:
            held |= set(pop.pooled.parameters)
    else:
        held = {n for r in analysis.runs for n in analysis.quantities if n in r}
    ordered = [n for n in analysis.quantities if n in held]
    return ordered + sorted(held - set(ordered))


def quantity_label(analysis: CampaignAnalysis, name: str) -> str:
    """A quantity's symbol and unit, ``"ζ [-]"``, ``"c₂ [kg/m]"``, from the analysis'
    description of it (:mod:`bayestribo.campaign.quantities`)."""
    q = analysis.quantities.get(name) or {}
    symbol = q.get("symbol") or _PAPER_SYMBOLS.get(name, name)
    unit = str(q.get("unit") or "1")
    return f"{symbol} [{'-' if unit in ('1', '-', '') else unit}]"


def _panel_size(n: int, width: float = 10.0, height: float = 4.0) -> tuple[float, float]:
    """A figure of ``n`` panels: two side by side as before, three to a row beyond."""
    cols = min(max(n, 1), 3)
    rows = max(1, math.ceil(n / 3))
    return (max(width, 3.6 * cols), height + 3.2 * (rows - 1))


def _panels(fig: Any, n: int) -> list[Any]:
    """``n`` axes, at most three to a row."""
    n = max(n, 1)
    cols = min(n, 3)
    rows = math.ceil(n / cols)
    grid = fig.subplots(rows, cols, squeeze=False)
    flat = list(grid.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return flat[:n]


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
    """Each quantity's group means against load, with intervals, each run's median
    beside its group, the trend's band, and the paper's values where the series is
    glycerol.

    One panel per quantity the groups compare (``analysis.quantities``: ζ and μ_k in
    the paper's law, each law's own otherwise; a quantity is drawn for the groups that
    have it). Where a series has a trend against load, its population mean against
    load is drawn as a line (median) in a band (the ``analysis.prob`` interval).

    Parameters
    ----------
    analysis : CampaignAnalysis
    fig : matplotlib Figure, optional
        Empty figure to draw on (one axes per quantity is added); a new one if None.

    Returns
    -------
    matplotlib Figure
    """
    pop = analysis.contact
    names = quantity_names(analysis, pop)
    fig = _new_figure(fig, _panel_size(len(names)))
    axes = _panels(fig, len(names))
    covariate = analysis.covariate
    if pop is not None and covariate in _keys(pop):
        series: dict[str, list[Any]] = {}
        for g in pop.groups.values():
            meta = _group_meta(pop, g)
            series.setdefault(_series_label(meta, covariate), []).append((meta[covariate], g))
        # each run's median as a small dot beside its group's mean, in the series' colour
        repeats: dict[str, list[dict[str, Any]]] = {}
        for g in pop.groups.values():
            meta = _group_meta(pop, g)
            rows = [r for r in analysis.runs if r.get("run_id") in set(g.runs)]
            repeats.setdefault(_series_label(meta, covariate), []).extend(rows)
        bands = _trend_bands(analysis, pop)
        for k, (label, members) in enumerate(sorted(series.items())):
            members.sort(key=lambda m: m[0])
            shift = 0.004 * (k - (len(series) - 1) / 2)
            colour = f"C{k % 10}"
            for ax, name in zip(axes, names, strict=True):
                shown = [m for m in members if name in m[1].parameters]
                if not shown:
                    continue
                x = np.array([m[0] for m in shown], dtype=float) + shift
                s = [summarize(m[1].mean[name], analysis.prob) for m in shown]
                med = np.array([v["median"] for v in s])
                err = np.array(
                    [[v["median"] - v["interval"][0], v["interval"][1] - v["median"]] for v in s]
                ).T
                ax.errorbar(x, med, yerr=err, fmt="o", capsize=3, color=colour, label=label)
                runs = [r for r in repeats.get(label, []) if name in r]
                if runs:
                    ax.plot(
                        np.array([r[covariate] for r in runs], dtype=float) + shift + 0.002,
                        [r[name]["median"] for r in runs],
                        ".",
                        ms=4,
                        alpha=0.6,
                        color=colour,
                        label="a run (median)" if k == 0 else None,
                    )
                trend = bands.get(label)
                if trend is not None and name in trend.parameters:
                    xs = np.linspace(min(m[0] for m in members), max(m[0] for m in members), 40)
                    _band(ax, trend, name, xs, xs + shift, analysis.prob, colour, first=k == 0)
    glycerol = pop is not None and any(
        "glycerol" in str(v) and "glycerol-water" not in str(v) for v in pop.groups
    )
    for ax, name in zip(axes, names, strict=True):
        if glycerol and name in PAPER_VALUES:  # the paper's values are those of glycerol
            mean, sd = PAPER_VALUES[name]
            ax.axhspan(mean - sd, mean + sd, color="0.85", zorder=0, label="paper, glycerol")
            ax.axhline(mean, color="0.5", lw=1, zorder=0)
        ax.set_xlabel("load N [N]")
        ax.set_ylabel(f"population mean of {quantity_label(analysis, name)}")
        ax.grid(alpha=0.3)
        _ticks(ax, "y")
        _ticks(ax, "x")
    _legend(fig, axes)
    fig.suptitle(f"Group means with {100 * analysis.prob:.0f} % credible intervals")
    return fig


def _legend(fig: Any, axes: Sequence[Any]) -> None:
    """One legend below the panels, of every entry of every panel (each once)."""
    entries: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    if entries:
        fig.legend(
            list(entries.values()),
            list(entries),
            loc="outside lower center",
            ncols=3,
            fontsize="small",
        )


def _band(
    ax: Any,
    trend: Any,
    name: str,
    xs: np.ndarray,
    drawn_at: np.ndarray,
    prob: float,
    colour: str,
    *,
    first: bool,
) -> None:
    """A trend's population mean against its covariate: median line and band."""
    draws = np.stack([trend.mean_at(name, float(x)) for x in xs], axis=1)
    lo, med, hi = np.quantile(draws, [(1 - prob) / 2, 0.5, (1 + prob) / 2], axis=0)
    ax.fill_between(drawn_at, lo, hi, color=colour, alpha=0.15, lw=0)
    ax.plot(
        drawn_at,
        med,
        "-",
        color=colour,
        lw=1,
        alpha=0.8,
        label=f"trend against load: median, {100 * prob:g} % band" if first else None,
    )


def _trend_bands(analysis: CampaignAnalysis, pop: Any) -> dict[str, Any]:
    """The trends against ``analysis.covariate``, by their series' legend label."""
    keys = tuple(k for k in _keys(pop) if k != analysis.covariate)
    out = {}
    for label, trend in analysis.trends.items():
        if trend.covariate != analysis.covariate:
            continue
        pairs = dict(item.partition("=")[::2] for item in label.split(",") if "=" in item)
        if set(pairs) == set(keys) or (label == "all" and not keys):
            out[_words(",".join(f"{k}={pairs[k]}" for k in keys))] = trend
    return out


def _value_label(key: str, value: Any) -> str:
    """A legend entry for a metadata value: ``load 0.07 N``, not ``load_N = 0.07``."""
    if value is None:
        return f"no {key}"
    if key == "load_N":
        return f"load {value:g} N"
    return literal(f"{key} = {value}")


#: Markers of the quantities in the forest plot's width panel, in order.
_MARKERS = "o^sDvP"
_MARKER_WORDS = {"o": "o", "^": "△", "s": "□", "D": "◇", "v": "▽", "P": "+"}


def plot_forest(
    analysis: CampaignAnalysis,
    fig: Any = None,
    truth: Mapping[str, Mapping[str, float]] | None = None,
) -> Any:
    """Each run's quantities with their credible intervals, and the intervals' widths.

    One row per run, coloured by load; one panel per quantity the runs have
    (``analysis.quantities``: ζ and μ_k in the paper's law), a run drawn in the panels
    of its own law's quantities. The last panel gives each interval's width relative
    to the run's median on a log scale, so intervals far narrower than the spread
    between runs (invisible beside their dots) can still be read and compared.

    Parameters
    ----------
    analysis : CampaignAnalysis
    fig : matplotlib Figure, optional
        Empty figure to draw on (one axes per quantity and one more are added); a new
        one if None.
    truth : mapping, optional
        Run id -> {quantity name: value}: true values of simulated runs (ticks).

    Returns
    -------
    matplotlib Figure
    """
    runs = analysis.runs
    names = quantity_names(analysis)
    width = max(11.0, 3.3 * len(names) + 3.0)
    fig = _new_figure(fig, (width, max(3.0, 0.22 * len(runs) + 1.4)))
    axes = fig.subplots(
        1, len(names) + 1, sharey=True, gridspec_kw={"width_ratios": [1.2] * len(names) + [1]}
    )
    y = np.arange(len(runs))[::-1]
    loads = sorted({r.get(analysis.covariate) for r in runs}, key=lambda v: (v is None, v))
    colour = {v: f"C{i % 10}" for i, v in enumerate(loads)}
    for k, (ax, name) in enumerate(zip(axes[:-1], names, strict=True)):
        marker = _MARKERS[k % len(_MARKERS)]
        for yi, run in zip(y, runs, strict=True):
            if name not in run:
                continue
            c = colour[run.get(analysis.covariate)]
            lo, hi = run[name]["interval"]
            med = run[name]["median"]
            ax.plot([lo, hi], [yi, yi], color=c, lw=2)
            ax.plot(med, yi, "o", color=c, ms=3)
            if hi > lo and med:
                axes[-1].plot(
                    (hi - lo) / abs(med), yi, marker, color=c, ms=4, mfc="none" if k else c
                )
            true = (truth or {}).get(str(run.get("run_id")), {}).get(name)
            if true is not None:  # a tick, not hiding the run's coloured dot
                ax.plot(true, yi, "k|", ms=9, mew=1.2)
        ax.set_xlabel(quantity_label(analysis, name))
        ax.grid(alpha=0.3)
        _ticks(ax)
    _decades(axes[-1])
    key = ", ".join(
        f"{_MARKER_WORDS[_MARKERS[k % len(_MARKERS)]]}: {_symbol(analysis, name)}"
        for k, name in enumerate(names)
    )
    axes[-1].set_xlabel(f"interval width / median [-]\n({key})")
    axes[-1].grid(alpha=0.3)
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


def _symbol(analysis: CampaignAnalysis, name: str) -> str:
    q = analysis.quantities.get(name) or {}
    return str(q.get("symbol") or _PAPER_SYMBOLS.get(name, name))


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


def save_figures(
    analysis: CampaignAnalysis,
    folder: str | Path,
    bands: Mapping[str, Mapping[str, Any]] | None = None,
) -> list[Path]:
    """Write the campaign's figures as PNG files in ``folder``; return their paths.

    The group means against load and the forest plot always; ζ_k and d_k where the
    analysis has them (ζ a quantity of runs with and without contact); ΔE(A) per group
    where ``bands`` (run id -> ΔE(A) band, :func:`bayestribo.campaign.bands.
    run_bands`) are given.
    """
    plt = _pyplot()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    makers: list[tuple[str, Any]] = [
        ("means_vs_load", plot_against_load),
        ("forest", plot_forest),
    ]
    if analysis.derived:
        makers.append(("zeta_k_d_k", plot_derived))
    if bands:
        from bayestribo.campaign.bands import group_runs

        makers.append(("dissipation", lambda a: plot_dissipation(group_runs(a), bands)))
    out = []
    for name, make in makers:
        fig = make(analysis)
        path = folder / f"{name}.png"
        with atomic_file(path, "wb") as fh:
            fig.savefig(fh, format="png", dpi=120)
        plt.close(fig)
        out.append(path)
    return out


def plot_against_viscosity(analysis: CampaignAnalysis, fig: Any = None) -> Any:
    """The quantities of a glycerol–water series against the lubricant's kinematic
    viscosity (ζ and μ_k in the paper's law, each law's own otherwise).

    One panel per quantity; each group's population mean (a water fraction at one
    load) with its credible interval, one colour per load, each run's median beside
    it; the paper's glycerol
    values (0.55 % water, mean ± the repeats' σ, section 3.1) as a diamond, and a dotted
    line at 6 % water: the paper's μ_k keeps its glycerol value at higher viscosities
    and rises below (section 3.2, Fig. 10); both beside ζ and μ_k only. ν of each water
    fraction is Eq. 43's.

    Parameters
    ----------
    analysis : CampaignAnalysis
        Grouped by the water mass fraction (and the load).
    fig : matplotlib Figure, optional
        Empty figure to draw on (one axes per quantity is added); a new one if None.

    Returns
    -------
    matplotlib Figure
    """
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    from bayestribo.model.viscosity import glycerol_water_viscosity

    def nu(water: Any) -> float:
        return float(glycerol_water_viscosity(float(water)))

    pop = analysis.contact
    names = quantity_names(analysis, pop)
    fig = _new_figure(fig, _panel_size(len(names)))
    axes = _panels(fig, len(names))
    if pop is not None and "water_mass_fraction" in _keys(pop):
        series: dict[Any, list[tuple[float, Any]]] = {}
        for g in pop.groups.values():
            meta = _group_meta(pop, g)
            series.setdefault(meta.get("load_N"), []).append((nu(meta["water_mass_fraction"]), g))
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
            for ax, name in zip(axes, names, strict=True):
                shown_groups = [m for m in members if name in m[1].parameters]
                if not shown_groups:
                    continue
                x = np.array([m[0] for m in shown_groups]) * factor
                s = [summarize(m[1].mean[name], analysis.prob) for m in shown_groups]
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
    for ax, name in zip(axes, names, strict=True):
        if name in PAPER_VALUES:
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
        ax.set_ylabel(f"population mean of {quantity_label(analysis, name)}")
        _ticks(ax, "y")
    _legend(fig, axes)
    fig.suptitle(
        f"Glycerol–water: group means with {100 * analysis.prob:.0f} % credible intervals "
        "against viscosity"
    )
    return fig


def _energy_label(unit: str) -> str:
    return "ΔE per cycle [J]" if unit == "J" else f"ΔE per cycle / k [{unit}]"


def plot_dissipation(
    groups: Mapping[str, Sequence[str]],
    bands: Mapping[str, Mapping[str, Any]],
    fig: Any = None,
    amplitude: float | None = None,
    measured: Mapping[str, Mapping[str, Any]] | None = None,
) -> Any:
    """ΔE(A) per group: each run's energy loss per cycle with its credible band.

    One panel per group of repeats, on log-log axes, each run's band
    (:attr:`bayestribo.inference.FitResult.dissipation`, its law's or the law-free
    mixture's) in its own colour; a dotted line at the swing where the runs are
    compared (:func:`bayestribo.campaign.bands.dissipation_rows`). Every law has
    a ΔE(A), so runs of any laws are drawn alike.

    Parameters
    ----------
    groups : mapping of str to sequence of str
        Group label (``key=value`` pairs, drawn in words) -> its runs;
        :func:`bayestribo.campaign.bands.group_runs` of a campaign analysis.
    bands : mapping
        Run id -> ΔE(A) band (:func:`bayestribo.campaign.bands.run_bands`).
    fig : matplotlib Figure, optional
        Empty figure to draw on (one axes per group is added); a new one if None.
    amplitude : float, optional
        The swing of comparison; default the middle of the range the runs share.
    measured : mapping, optional
        Run id -> the ΔE(A) measured from its turning points (the law-free answer,
        :attr:`bayestribo.inference.FitResult.turning_point_dissipation`), drawn as
        squares with their intervals in the run's colour.

    Returns
    -------
    matplotlib Figure
        ΔE is never negative: a lower end at or below zero is drawn down to the axis'
        bottom (a log axis has no zero), never left out.
    """
    from bayestribo.campaign.bands import dissipation_rows

    shown = {
        label: [r for r in runs if r in bands]
        for label, runs in groups.items()
        if any(r in bands for r in runs)
    }
    _, rows = dissipation_rows(shown, bands, amplitude)
    at = {row["group"]: row["amplitude"] for row in rows}
    n = max(len(shown), 1)
    cols = min(n, 3)
    fig = _new_figure(fig, (max(10.0, 3.6 * cols), 3.4 * math.ceil(n / cols) + 0.8))
    axes = _panels(fig, n)
    for ax, (label, runs) in zip(axes, shown.items(), strict=False):
        units = {str(bands[r].get("unit")) for r in runs}
        drawn = []
        for k, run in enumerate(runs):
            band = bands[run]
            amps = np.asarray(band["amplitude"], dtype=float)
            lo, hi = (np.asarray(side, dtype=float) for side in band["interval"])
            mean = np.asarray(band["mean"], dtype=float)
            keep = (amps > 0) & (hi > 0) & (mean > 0)
            colour = f"C{k % 10}"
            # ΔE is never negative: a lower end at or below zero is at its bound, drawn
            # down to the axis' bottom (a log axis has no zero), not left out
            floor = np.where(lo > 0, lo, np.min(mean[keep], initial=np.inf) * 1e-3)
            ax.fill_between(amps[keep], floor[keep], hi[keep], color=colour, alpha=0.2, lw=0)
            ax.plot(amps[keep], mean[keep], "-", color=colour, lw=1.2, label=literal(run))
            drawn += [mean[keep], hi[keep]]
            points = (measured or {}).get(run) or {}
            if points.get("amplitude"):
                a = np.asarray(points["amplitude"], dtype=float)
                m = np.asarray([np.nan if v is None else v for v in points["mean"]], dtype=float)
                low, high = (
                    np.asarray([np.nan if v is None else v for v in side], dtype=float)
                    for side in points["interval"]
                )
                ok = (a > 0) & np.isfinite(m) & (m > 0)
                below = m - np.where(low > 0, low, m * 1e-3)
                ax.errorbar(
                    a[ok],
                    m[ok],
                    yerr=np.maximum(np.vstack([below, high - m])[:, ok], 0.0),
                    fmt="s",
                    ms=3,
                    capsize=1.5,
                    color=colour,
                    mec="k",
                    mew=0.4,
                    lw=0.8,
                    label="turning points (law-free)" if k == 0 else None,
                )
                drawn.append(m[ok])
        values = np.concatenate(drawn) if drawn else np.array([])
        if values.size:  # the values' decades: a band at zero runs to the bottom
            ax.set_ylim(values.min() / 3.0, values.max() * 1.5)
        if at.get(label) is not None:
            ax.axvline(at[label], color="0.4", ls=":", lw=1)
        ax.set_yscale("log")
        _decades(ax)  # whole decades: labels at minor ticks run together
        words = "no contact" if label == "no contact" else _words(label.removeprefix("no contact,"))
        ax.set_title(words if len(words) <= 48 else words[:46] + "…", fontsize="medium")
        amplitude_unit = str(bands[runs[0]].get("amplitude_unit") or "-")
        ax.set_xlabel(f"swing A [{amplitude_unit}]")
        ax.set_ylabel(_energy_label(units.pop() if len(units) == 1 else "mixed units"))
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="upper left")
    probs = {float(b["prob"]) for b in bands.values() if b.get("prob")}
    within = f"{100 * probs.pop():.0f} % band" if len(probs) == 1 else "credible band"
    fig.suptitle(
        f"Energy loss per cycle ΔE(A), each run's mean and {within}"
        + (", squares: from its turning points" if measured else "")
        + ("\n(dotted: the swing where the runs are compared)" if at else "")
    )
    return fig


def plot_dissipation_against_load(
    analysis: CampaignAnalysis,
    bands: Mapping[str, Mapping[str, Any]],
    fig: Any = None,
    amplitude: float | None = None,
) -> Any:
    """Each run's ΔE at one swing against load, with its credible interval.

    The runs of a series (the groups' keys but the load) in one colour; the swing is
    one every run reaches (:func:`bayestribo.campaign.bands.dissipation_rows`).
    Each run's own interval, not a population of repeats.

    Parameters
    ----------
    analysis : CampaignAnalysis
    bands : mapping
        Run id -> ΔE(A) band.
    fig : matplotlib Figure, optional
        Empty figure to draw on (one axes is added); a new one if None.
    amplitude : float, optional
        The swing; default the middle of the range every run shares.

    Returns
    -------
    matplotlib Figure
    """
    from bayestribo.campaign.bands import dissipation_rows, group_runs, run_metadata

    fig = _new_figure(fig, (7, 4.2))
    ax = fig.subplots()
    shared, rows = dissipation_rows(
        group_runs(analysis), bands, amplitude, metadata=run_metadata(analysis)
    )
    pop = analysis.contact
    series_of: dict[str, str] = {}
    if pop is not None:
        for g in pop.groups.values():
            label = _series_label(_group_meta(pop, g), analysis.covariate)
            series_of.update({run: label for run in g.runs})
    shown = [r for r in rows if "mean" in r and r.get("load_N") is not None]
    units = {str(r["unit"]) for r in shown}
    series = sorted({series_of.get(r["run"], "no contact") for r in shown})
    for k, label in enumerate(series):
        members = [r for r in shown if series_of.get(r["run"], "no contact") == label]
        x = np.array([r["load_N"] for r in members], dtype=float)
        mean = np.array([r["mean"] for r in members])
        err = np.array([[r["mean"] - r["low"], r["high"] - r["mean"]] for r in members]).T
        ax.errorbar(
            x,
            mean,
            yerr=np.maximum(err, 0),
            fmt="o",
            ms=4,
            capsize=3,
            color=f"C{k % 10}",
            label=label,
        )
    ax.set_xlabel("load N [N]")
    ax.set_ylabel(_energy_label(units.pop() if len(units) == 1 else "mixed units"))
    ax.grid(alpha=0.3)
    _ticks(ax, "x")
    _ticks(ax, "y")
    if series:
        _legend(fig, [ax])
    unit = next((str(r["amplitude_unit"]) for r in shown), "")
    at = f"A = {shared:.3g} {unit}" if shared is not None else "a swing per group"
    fig.suptitle(f"ΔE per cycle at {at}: each run's mean and interval")
    return fig
