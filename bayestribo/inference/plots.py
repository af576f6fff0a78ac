"""Figures of a single-run fit: corner plot, traces, and Π with its predictive band.

Every function takes the matplotlib figure or axes to draw on and returns it; none
calls ``show()`` or ``savefig()`` (the caller decides where the figure goes).
Notation of Rigaud et al. (2010): τ = Ωt (dimensionless time), ζ (equivalent viscous
damping, Eq. 6), μ_k and μ_s (kinetic and static friction coefficients, Eq. 2-3),
Π(τ) = ∫_τ^{τ_f} E dτ' (the retrograde integral of the dimensionless energy
E = (y² + y'²)/2, Eq. 39).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from bayestribo._text import literal

if TYPE_CHECKING:
    from bayestribo.inference.result import FitResult

__all__ = ["FIGURES", "LABELS", "corner_plot", "pi_plot", "plot_fit", "plotted_names", "trace_plot"]

#: Axis label of each posterior quantity (paper notation, units in brackets).
LABELS: dict[str, str] = {
    "zeta": "ζ [-]",
    "mu_k": "μ_k [-]",
    "mu_s": "μ_s [-]",
    "mu_s_ratio": "μ_s/μ_k [-]",
    "friction_displacement": "x_c [displacement unit]",
    "static_friction_displacement": "x_s = μ_s N/k [displacement unit]",
    "y0": "y₀ (start of window) [-]",
    "zeta_k": "ζ_k = ζ − ζ₀ [-]",
    "d_k": "d_k [s/m]",
    "friction_torque": "T_c = κ θ_c [N m]",
    "static_friction_torque": "T_s = κ θ_s [N m]",
    "log10_discrepancy": "log₁₀ s (discrepancy) [-]",
    "log10_shape": "log₁₀ s_c (shape discrepancy) [-]",
}

_DEFAULT = (
    "zeta",
    "mu_k",
    "friction_displacement",
    "mu_s_ratio",
    "y0",
    "log10_discrepancy",
    "log10_shape",
)


def _label(result: FitResult, name: str) -> str:
    if name in ("friction_displacement", "static_friction_displacement"):
        unit = {"m": "m", "rad": "rad"}.get(
            result.metadata.get("length_unit", "m") or "m", "signal unit"
        )
        symbol = "x_c" if name == "friction_displacement" else "x_s"
        if unit == "rad":  # a rotation: friction angles
            symbol = "θ_c" if name == "friction_displacement" else "θ_s"
        return f"{symbol} [{unit}]"
    if name == "y0":
        return "y₀ (start of window) [-]"
    if name in LABELS:
        return LABELS[name]
    from bayestribo.model.laws import TERMS

    for term in TERMS.values():
        for p in term.parameters:
            if p.name == name:
                return f"{p.symbol} [{p.unit}]"
    unit = (result._attr("units_json", {}) or {}).get(name)
    return f"{name} [{unit}]" if unit else name


def plotted_names(result: FitResult, names: Sequence[str] | None = None) -> list[str]:
    """The quantities drawn by default: ζ, μ_k (or x_c without a load), μ_s/μ_k, the
    other sampled parameters of the law, y₀.

    Parameters
    ----------
    result : FitResult
    names : sequence of str, optional
        Explicit choice (each must be in the posterior).

    Raises
    ------
    KeyError
        Naming a requested quantity the posterior does not hold.
    """
    available = result.parameter_names
    if names is not None:
        missing = [n for n in names if n not in available]
        if missing:
            raise KeyError(f"{missing} not in this fit's posterior; it has {available}")
        return list(names)
    chosen = [n for n in _DEFAULT if n in available]
    # the sampled parameters of a law's other terms (γ, α, η, ...), before y₀
    own = [n for n in result.priors.names if n not in _DEFAULT and n in available]
    at = chosen.index("y0") if "y0" in chosen else len(chosen)
    chosen[at:at] = own
    if "mu_k" in chosen and "friction_displacement" in chosen:
        chosen.remove("friction_displacement")  # x_c = μ_k ℓ: the same information
    return chosen


def corner_plot(result: FitResult, fig: Any, names: Sequence[str] | None = None) -> Any:
    """Pairwise marginal posteriors (:func:`corner.corner`) of the fitted quantities.

    Parameters
    ----------
    result : FitResult
    fig : matplotlib.figure.Figure
        Figure to draw on (it receives a d × d grid of axes).
    names : sequence of str, optional
        Quantities to show (default :func:`plotted_names`).

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``, with 2.5 %, 50 % and 97.5 % quantiles marked on the diagonal.
    """
    import corner

    from bayestribo.summary import interval_text

    chosen = plotted_names(result, names)
    data = np.column_stack([result.samples(n) for n in chosen])
    labels = [_label(result, n) for n in chosen]
    fig = corner.corner(
        data,
        fig=fig,
        labels=labels,
        quantiles=[0.025, 0.5, 0.975],
        label_kwargs={"fontsize": 9},
        max_n_ticks=3,
    )
    # Titles with the digits the interval supports (corner's own format rounds a ζ of
    # 0.0242506 ± 4e-7 to 0.0243), on two lines: the quantity, then median [95 %].
    diagonal = np.asarray(fig.axes).reshape(len(chosen), len(chosen)).diagonal()
    for ax, label, column in zip(diagonal, labels, data.T, strict=True):
        low, median, high = np.quantile(column, [0.025, 0.5, 0.975])
        ax.set_title(f"{label}\n{interval_text(median, low, high)}", fontsize=8)
    return fig


def trace_plot(result: FitResult, axes: Sequence[Any], names: Sequence[str] | None = None) -> Any:
    """Posterior draws against draw index, one line per independent ensemble.

    Parameters
    ----------
    result : FitResult
    axes : sequence of matplotlib.axes.Axes
        One axes per quantity (e.g. ``plt.subplots(len(names), 1)[1]``).
    names : sequence of str, optional
        Quantities to show (default :func:`plotted_names`); as many as ``axes``.

    Returns
    -------
    sequence of matplotlib.axes.Axes
        ``axes``.

    Raises
    ------
    ValueError
        If the number of axes differs from the number of quantities.
    """
    chosen = plotted_names(result, names)
    axes_list = list(np.ravel(np.asarray(axes, dtype=object)))
    if len(axes_list) != len(chosen):
        raise ValueError(f"axes: need {len(chosen)} axes for {chosen}, got {len(axes_list)}")
    for ax, name in zip(axes_list, chosen, strict=True):
        draws = np.asarray(result.idata.posterior[name])  # (chain, draw)
        for c in range(draws.shape[0]):
            ax.plot(draws[c], lw=0.5, alpha=0.8, label=f"ensemble {c + 1}")
        ax.set_ylabel(_label(result, name), fontsize=8)
    axes_list[-1].set_xlabel("thinned draw (walkers of one step, then the next step)")
    axes_list[0].legend(fontsize=8, loc="upper right")
    return axes


def _increments(pi: NDArray) -> NDArray:
    """Increments D_j = Π(τ_j) − Π(τ_{j+1}) (the last: Π(τ_{m-1})), along the last axis."""
    inc = np.empty_like(pi)
    inc[..., :-1] = pi[..., :-1] - pi[..., 1:]
    inc[..., -1] = pi[..., -1]
    return inc


def pi_plot(result: FitResult, axes: Sequence[Any], prob: float = 0.95) -> Any:
    """Observed Π(τ) with the posterior predictive band, and standardized residuals.

    The top axes show the observed Π on the fit's grid and the central ``prob`` band
    and median of the replicated Π (``posterior_predictive``: model plus noise), on a
    logarithmic Π axis. The bottom axes show the standardized residuals of the
    increments D_j = Π(τ_j) − Π(τ_{j+1}) (independent under the noise model, unlike
    Π itself): (D_j,obs − mean D_j,rep)/sd D_j,rep, with ±2 guides; without model
    error they scatter as standard normals.

    Parameters
    ----------
    result : FitResult
    axes : sequence of two matplotlib.axes.Axes
        Π axes and residual axes (e.g. ``plt.subplots(2, 1, sharex=True)[1]``).
    prob : float
        Probability of the predictive band.

    Returns
    -------
    sequence of matplotlib.axes.Axes
        ``axes``.

    Raises
    ------
    ValueError
        If ``axes`` does not hold two axes or ``prob`` is not in (0, 1).
    """
    axes_list = list(np.ravel(np.asarray(axes, dtype=object)))
    if len(axes_list) != 2:
        raise ValueError(f"axes: need two axes (Π and residuals), got {len(axes_list)}")
    if not 0.0 < prob < 1.0:
        raise ValueError(f"prob must be in (0, 1), got {prob!r}")
    ax_pi, ax_res = axes_list
    observed = np.asarray(result.idata.observed_data["pi"])
    tau = np.asarray(result.idata.observed_data["grid"])
    rep = np.asarray(result.idata.posterior_predictive["pi"]).reshape(-1, observed.size)
    lo, med, hi = np.quantile(rep, [(1 - prob) / 2, 0.5, (1 + prob) / 2], axis=0)

    positive = (lo > 0) & (hi > 0)
    ax_pi.fill_between(
        tau[positive],
        lo[positive],
        hi[positive],
        color="C0",
        alpha=0.3,
        label=f"posterior predictive {100 * prob:g} %",
    )
    ax_pi.plot(tau, med, color="C0", lw=1, label="predictive median")
    ax_pi.plot(tau, observed, "k.", ms=3, label="observed")
    ax_pi.set_yscale("log")
    ax_pi.set_ylabel("Π(τ) = ∫_τ E dτ' [-]")
    ax_pi.legend(fontsize=8)
    ax_pi.set_title(literal(f"{result.run_name} ({result.model} model)"), fontsize=9)

    inc_rep = _increments(rep)
    sd = np.std(inc_rep, axis=0, ddof=1)
    z = (_increments(observed) - np.mean(inc_rep, axis=0)) / np.where(sd > 0, sd, np.nan)
    ax_res.axhline(0.0, color="0.5", lw=0.8)
    for level in (-2.0, 2.0):
        ax_res.axhline(level, color="0.5", lw=0.8, ls="--")
    ax_res.plot(tau, z, "k.", ms=3)
    ax_res.set_xlabel("τ = Ωt [-]")
    ax_res.set_ylabel("standardized\nresidual of ΔΠ [-]")
    return axes


def _pi_figure(result: FitResult, fig: Any, **kwargs: Any) -> Any:
    axes = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    pi_plot(result, axes, **kwargs)
    return fig


def _corner_figure(result: FitResult, fig: Any, **kwargs: Any) -> Any:
    return corner_plot(result, fig, **kwargs)


def _trace_figure(result: FitResult, fig: Any, **kwargs: Any) -> Any:
    n = len(plotted_names(result, kwargs.get("names")))
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    trace_plot(result, axes, **kwargs)
    return fig


def _corner_size(result: FitResult, **kwargs: Any) -> tuple[float, float]:
    d = len(plotted_names(result, kwargs.get("names")))
    return (2.2 * d + 1, 2.2 * d + 1)


def _trace_size(result: FitResult, **kwargs: Any) -> tuple[float, float]:
    return (8.0, 1.6 * len(plotted_names(result, kwargs.get("names"))) + 0.6)


#: The figures of a fit by kind: a function that draws on a figure (making its axes)
#: and returns it, and the figure's size [in] when one is made for it. ``"decay"``
#: is the same figure as ``"pi"``.
FIGURES: dict[str, tuple[Any, Any]] = {
    "pi": (_pi_figure, lambda result, **kwargs: (8.0, 6.0)),
    "corner": (_corner_figure, _corner_size),
    "trace": (_trace_figure, _trace_size),
}
_ALIASES = {"decay": "pi"}


def plot_fit(result: FitResult, kind: str = "pi", fig: Any = None, **kwargs: Any) -> Any:
    """One figure of a fit, by kind.

    Parameters
    ----------
    result : FitResult
    kind : {"pi", "decay", "corner", "trace"}
        ``"pi"`` (or ``"decay"``): the observed Π(τ) with the fitted model's
        posterior predictive band and the standardized residuals (:func:`pi_plot`);
        ``"corner"``: the pairwise marginal posteriors (:func:`corner_plot`);
        ``"trace"``: the draws of each ensemble (:func:`trace_plot`).
    fig : matplotlib.figure.Figure, optional
        An empty figure to draw on; default a new one (``matplotlib.pyplot.figure``)
        of a size that suits the kind.
    **kwargs
        Passed to the drawing function (``prob`` for ``"pi"``, ``names`` for
        ``"corner"`` and ``"trace"``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on; its axes are ``fig.axes``. Nothing is shown or saved.

    Raises
    ------
    ValueError
        If ``kind`` is not one of the kinds above (they are named).
    """
    key = _ALIASES.get(kind, kind)
    if key not in FIGURES:
        known = sorted([*FIGURES, *_ALIASES])
        raise ValueError(f"kind: expected one of {known}, got {kind!r}")
    draw, size = FIGURES[key]
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=size(result, **kwargs))
    return draw(result, fig, **kwargs)
