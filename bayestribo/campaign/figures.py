"""Figures of a campaign analysis (matplotlib, no display needed).

* :func:`plot_against_load`: group means of ζ and μ_k against load with their
  credible intervals, one series per colour, beside the paper's values (section 3.1:
  ζ = 0.0236, σ 0.0012; μ_k = 0.0294, σ 0.0036) as a band of ± one σ;
* :func:`plot_forest`: each run's ζ and μ_k with its credible interval;
* :func:`plot_derived`: ζ_k and d_k per group against load.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bayestribo.campaign.analysis import CampaignAnalysis
from bayestribo.summary import summarize

__all__ = ["PAPER_VALUES", "plot_against_load", "plot_derived", "plot_forest", "save_figures"]

#: Paper values of the glycerol series (mean, repeat sd), section 3.1.
PAPER_VALUES = {"zeta": (0.0236, 0.0012), "mu_k": (0.0294, 0.0036)}
_LABELS = {"zeta": "ζ", "mu_k": "μ_k"}


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _series_label(analysis: CampaignAnalysis, value: Any) -> str:
    keys = [k for k in analysis.by if k != analysis.covariate]
    values = value if isinstance(value, tuple) else (value,)
    pairs = [f"{k}={v}" for k, v in zip(analysis.by, values, strict=False) if k in keys]
    return ", ".join(pairs) or "all"


def plot_against_load(analysis: CampaignAnalysis) -> Any:
    """ζ and μ_k group means against load, with intervals and the paper's values."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    pop = analysis.contact
    if pop is not None and analysis.covariate in analysis.by:
        i_load = analysis.by.index(analysis.covariate)
        series: dict[str, list[Any]] = {}
        for value, g in pop.groups.items():
            values = value if isinstance(value, tuple) else (value,)
            series.setdefault(_series_label(analysis, value), []).append((values[i_load], g))
        for k, (label, members) in enumerate(sorted(series.items())):
            members.sort(key=lambda m: m[0])
            shift = 0.004 * (k - (len(series) - 1) / 2)
            for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
                x = np.array([m[0] for m in members], dtype=float) + shift
                s = [summarize(m[1].mean[name], analysis.prob) for m in members]
                med = np.array([v["median"] for v in s])
                err = np.array(
                    [[v["median"] - v["interval"][0], v["interval"][1] - v["median"]] for v in s]
                ).T
                ax.errorbar(x, med, yerr=err, fmt="o", capsize=3, label=label)
    for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
        mean, sd = PAPER_VALUES[name]
        ax.axhspan(mean - sd, mean + sd, color="0.85", zorder=0, label="paper: mean ± σ")
        ax.axhline(mean, color="0.5", lw=1, zorder=0)
        ax.set_xlabel("load N [N]")
        ax.set_ylabel(f"population mean of {_LABELS[name]} [-]")
    axes[0].legend(fontsize="small")
    fig.suptitle(f"Group means with {100 * analysis.prob:.0f} % credible intervals")
    return fig


def plot_forest(analysis: CampaignAnalysis) -> Any:
    """Each run's ζ and μ_k with its credible interval."""
    plt = _pyplot()
    runs = analysis.runs
    fig, axes = plt.subplots(
        1, 2, figsize=(10, max(3.0, 0.18 * len(runs) + 1)), sharey=True, constrained_layout=True
    )
    y = np.arange(len(runs))[::-1]
    for ax, name in zip(axes, ("zeta", "mu_k"), strict=True):
        for yi, run in zip(y, runs, strict=True):
            if name in run:
                lo, hi = run[name]["interval"]
                ax.plot([lo, hi], [yi, yi], color="C0", lw=2)
                ax.plot(run[name]["median"], yi, "o", color="C0", ms=3)
        ax.set_xlabel(f"{_LABELS[name]} [-]")
    axes[0].set_yticks(y, [str(r["run_id"]) for r in runs], fontsize="x-small")
    fig.suptitle(f"Runs: medians and {100 * analysis.prob:.0f} % credible intervals")
    return fig


def plot_derived(analysis: CampaignAnalysis) -> Any:
    """ζ_k = ζ − ζ₀ and d_k per contact group against load."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    rows = [r for r in analysis.derived if "load_N" in r]
    for ax, key, label in (
        (axes[0], "zeta_k", "ζ_k = ζ − ζ₀ [-]"),
        (axes[1], "d_k_s_per_m", "d_k [s/m]"),
    ):
        if rows:
            x = np.array([r["load_N"] for r in rows])
            med = np.array([r[key]["median"] for r in rows])
            lo = np.array([r[key]["interval"][0] for r in rows])
            hi = np.array([r[key]["interval"][1] for r in rows])
            ax.errorbar(x, med, yerr=[med - lo, hi - med], fmt="o", capsize=3)
        ax.set_xlabel("load N [N]")
        ax.set_ylabel(label)
    return fig


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
