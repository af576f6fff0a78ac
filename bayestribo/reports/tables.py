"""Results as tables for people: symbols and units, intervals in the digits they support.

The reports show a fit, a table of classical estimates or an adequacy check as HTML
tables (pandas DataFrames shown by :func:`bayestribo.reports.kit.table`), not as the
terminal's fixed-width text: a quantity is named by its symbol (ζ, μ_k, x_c) with its
unit, a value with its 95 % interval in one cell (:func:`bayestribo.summary.interval_text`),
a method by its name in words. Every function here returns plain data (a DataFrame, a
dict of texts) and shows nothing.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from bayestribo._plural import count
from bayestribo.inference.flatness import FLAT_KS as _FLAT_KS
from bayestribo.inference.flatness import (
    SPREAD_OF,
    end_density,
    is_bound,
    is_flat,
    prior_end,
    prior_flatness,
)
from bayestribo.inference.quantities import unit_words
from bayestribo.summary import NUMERICAL_ZERO, interval_text, probability_text

__all__ = [
    "METHOD_NAMES",
    "SYMBOLS",
    "caveat_text",
    "diagnostics_frame",
    "dissipation_frame",
    "estimates_frame",
    "fit_facts",
    "fit_frame",
    "interval_too_narrow",
    "law_text",
    "method_text",
    "nonnegative_text",
    "normal_interval",
    "physical_symbols",
    "prior_flatness",
    "probability_text",
    "prose",
    "quantiles_text",
    "quantity_text",
    "share_text",
    "unit_text",
    "windows_frame",
]

#: Symbols of the quantities a fit reports that are not a law's own parameter.
SYMBOLS = {
    "zeta": "ζ",
    "mu_k": "μ_k",
    "mu_s": "μ_s",
    "mu_s_ratio": "μ_s/μ_k",
    "log10_discrepancy": "log₁₀ σ_d",
    "log10_shape": "log₁₀ σ_s",
    "friction_displacement": "x_c",
    "static_friction_displacement": "x_s",
    "friction_torque": "T_c",
    "static_friction_torque": "T_s",
    "zeta_k": "ζ_k",
    "d_k": "d_k",
    "y0": "y₀",
}

#: The classical estimators by name in words.
METHOD_NAMES = {
    "log_decrement": "logarithmic decrement",
    "exponential_envelope": "exponential envelope",
    "feeny_liang": "Feeny–Liang",
    "nonsuccessive": "non-successive peaks",
    "energy_ls_averaged": "least squares on Π, averaged model",
    "energy_ls_exact": "least squares on Π, exact model",
}

#: Quantities of a fit not shown among the results (nuisances, sampled scales).
_HIDDEN = ("y0", "mu_s_ratio")

#: Quantiles of a 95 % normal interval, in standard errors.
_Z95 = 1.959963984540054

#: The flat-posterior test and its threshold (:mod:`bayestribo.inference.flatness`).
FLAT_KS = _FLAT_KS
_SPREAD_OF = SPREAD_OF


def law_text(law: str) -> str:
    """A dissipation law in words, each term as its registry entry describes it
    (:func:`bayestribo.reports.laws.law_text`).

    Examples
    --------
    >>> law_text("viscous+coulomb")
    'viscous damping + Coulomb friction'
    """
    from bayestribo.reports.laws import law_text as words

    return words(law)


#: Column names of a run file as a reader names the quantity.
_COLUMNS = {
    "time_s": "time",
    "displacement_m": "displacement",
    "velocity_m_per_s": "velocity",
}


def prose(text: str, *, paths: Mapping[str, str] | None = None) -> str:
    """A message of the package (a warning, a note) as report text: laws in words
    ("viscous+coulomb" -> "viscous damping + Coulomb friction"), run-file column names as the
    quantity ("velocity_m_per_s" -> "velocity"), quantities by their symbol ("mu_k" ->
    "μ_k"), ``law='auto'`` as "law = auto", the
    advice on ``columns=[...]`` and a command's option in parentheses left out, and each
    path in ``paths`` replaced by its short name.

    Examples
    --------
    >>> prose("the law viscous+coulomb misfits; fit with law='auto' (--law auto)")
    'the law viscous damping + Coulomb friction misfits; fit with law = auto'
    >>> prose(prose("the law viscous+coulomb misfits; the law viscous holds"))
    'the law viscous damping + Coulomb friction misfits; the law viscous damping holds'
    >>> prose("the law quadratic holds; the power of the test")
    'the law quadratic drag holds; the power of the test'
    >>> prose("raise max_steps (--param max_steps=20000)")
    'raise maximum number of steps'
    >>> prose("R-hat 1.02 for log_sigma[mu_k] and beta[0,ΔE(A=1e-04 m)]")
    'R-hat 1.02 for log σ of μ_k and the mean of ΔE(A=1e-04 m)'
    >>> prose("/d/r.csv: 1 row(s) have no value for velocity_m_per_s; they are left out "
    ...       "of the run (give columns=[...] with 'ignore' for a channel not to use)",
    ...       paths={"/d/r.csv": "r"})
    'r: 1 row(s) have no value for velocity; they are left out of the run'
    """
    import re

    for path, short in (paths or {}).items():
        text = text.replace(path, short)
    text = re.sub(r" \(give columns=\[\.\.\.\][^)]*\)", "", text)
    text = re.sub(r" \(printed as '[^']*'\)", "", text)  # the terminal's label
    text = text.replace("law='auto'", "law = auto")
    # a command's option in parentheses ("(--law auto)", "(--param max_steps=20000)"): a
    # report says the setting in words, not the command line that sets it
    text = re.sub(r" \(--[a-z][a-z-]*(?: [^()]*)?\)", "", text)
    # a population sampler's coordinates in words: log_sigma[zeta] -> log σ of zeta
    text = re.sub(r"\blog_sigma\[([^\]]+)\]", r"log σ of \1", text)
    text = re.sub(r"\bbeta\[0,([^\]]+)\]", r"the mean of \1", text)
    text = re.sub(r"\bbeta\[1,([^\]]+)\]", r"the slope of \1", text)
    # the setting in words, but not inside the option that sets it (--param max_steps=N)
    text = re.sub(r"(?<!--param )\bmax_steps\b(?!=)", "maximum number of steps", text)
    from bayestribo.model.laws import TERMS

    own = {p.name: p.symbol for t in TERMS.values() for p in t.parameters}
    for name, symbol in {**own, **SYMBOLS}.items():  # quantities by symbol: mu_k -> μ_k
        text = re.sub(rf"\b{name}\b", symbol, text)
    for name, words in _COLUMNS.items():
        text = re.sub(rf"\b{name}\b", words, text)
    from bayestribo.reports.laws import term_words

    terms = "|".join(TERMS)
    # one term named as "the law ..." ("power" alone is a word), unless its words follow
    # it already ("the law viscous damping": text said once is not said again)
    said = {n: term_words(n)[len(n) :] if term_words(n).startswith(n) else "" for n in TERMS}
    single = "|".join(f"{n}(?!{re.escape(rest)})" if rest else n for n, rest in said.items())
    # a law's name: terms joined by "+", or a single term so named
    law = rf"\b(?:{terms})(?:\+(?:{terms}))+\b|(?<=\blaw )(?:{single})\b"
    return re.sub(law, lambda m: law_text(m.group(0)), text)


def unit_text(unit: str | None) -> str:
    """A unit as a reader writes it, in a report's tables as in the command line's:
    ``"dimensionless"`` for a number without a dimension, ``"signal unit"`` for a
    length in a recording's unstated unit, superscript squares
    (:func:`bayestribo.inference.quantities.unit_words`, which ``bayestribo fit``
    prints).

    Examples
    --------
    >>> unit_text("1"), unit_text("signal length unit^2"), unit_text("J")
    ('dimensionless', 'signal unit²', 'J')
    """
    return unit_words(unit)


def _symbols(result: Any) -> dict[str, str]:
    """Symbols of a fit's own law parameters and of their physical quantities (each
    term's :meth:`~bayestribo.model.laws.Term.physical`, with and without a known
    stiffness), then the common ones."""
    own = dict(getattr(result, "symbols", {}) or {})
    out = {**physical_symbols(getattr(result, "law", "")), **own, **SYMBOLS}
    # the fit's own description last: a rotation's friction is the angle θ_c, not x_c
    info = getattr(result, "quantity_info", None)
    if callable(info):
        out.update({name: q.symbol for name, q in info().items()})
    return out


def physical_symbols(law: str) -> dict[str, str]:
    """The symbol of each physical quantity a law's terms report, by name
    (``{"c2_SI": "c₂", "c2_per_mass": "c₂/m", ...}``), from the registry; empty for a
    law that is not registered.

    Examples
    --------
    >>> physical_symbols("power")["c_alpha_per_k"]
    'c_α/k'
    """
    from bayestribo.inference.quantities import law_quantities

    _, physical = law_quantities(law)
    return {name: symbol for name, (symbol, _, _) in physical.items()}


def interval_too_narrow(estimate: Any) -> bool:
    """Whether a classical estimate's interval is known to be too narrow: from the peaks'
    noise only, or from a Jacobian with correlated residuals (its ``notes`` say so).

    Examples
    --------
    >>> from types import SimpleNamespace as E
    >>> interval_too_narrow(E(notes="SE from the peak noise only"))
    True
    >>> interval_too_narrow(E(notes="Eq. 21 sign corrected"))
    False
    """
    notes = getattr(estimate, "notes", "") or ""
    return "peak noise only" in notes or "too small" in notes


def normal_interval(
    value: float | None, se: float | None, *, positive: bool = False, too_narrow: bool = False
) -> str:
    """``value [low, high]`` of a classical estimate: ±1.96 standard errors, in the digits
    the interval supports; a positive quantity whose interval reaches below zero is shown
    at its bound (``0 (at the bound) [0, 8.2e-05]``). A dash without a value; the value alone
    (3 digits) without a standard error. An interval known to be ``too_narrow``
    (:func:`interval_too_narrow`) does not support the digits it would give (ten, for the
    peaks' noise of a clean record): the value in four significant digits, its half width
    said apart.

    Examples
    --------
    >>> normal_interval(0.0236, 0.0001)
    '0.02360 [0.02340, 0.02380]'
    >>> normal_interval(0.0242509127, 1.5e-09, too_narrow=True).replace("\\xa0", " ")
    '0.02425 (± 3e-09, too narrow)'
    >>> normal_interval(3.97e-19, 4.2e-05, positive=True)
    '0 (at the bound) [0, 8.2e-05]'
    >>> normal_interval(9.31e-26, None), normal_interval(0.0236, None)
    ('0', '0.0236')
    """
    if value is None or not math.isfinite(value):
        return "–"
    if se is None or not math.isfinite(se) or se <= 0:
        # a numerical zero (a least-squares ζ of 9.3e-26 at its bound) is zero, not a value
        return "0" if abs(value) < NUMERICAL_ZERO else f"{value:.3g}"
    if too_narrow:
        shown = "0" if abs(value) < NUMERICAL_ZERO else f"{value:.4g}"
        # no-break spaces: the number and its half width stay on one line in a table
        return f"{shown}\u00a0(±\u00a0{_Z95 * se:.1g}, too narrow)"
    low, high = value - _Z95 * se, value + _Z95 * se
    if positive and low < 0.0 < high:
        return interval_text(max(value, 0.0), 0.0, high)
    return interval_text(value, low, high)


def nonnegative_text(name: str, center: float, low: float, high: float) -> str:
    """``center [low, high]`` of a quantity by name, in the digits the interval supports;
    an energy lost per cycle (``ΔE(A=...)``, the law-free comparison across runs) held at
    zero below: a free decay never gains energy, so an interval of a population mean
    that reaches below zero is at its bound there.

    Examples
    --------
    >>> nonnegative_text("ΔE(A=1e-04 m)", 2e-07, -1e-07, 5e-07)
    '0 (at the bound) [0, 5.0e-07]'
    >>> nonnegative_text("zeta", 0.0236, 0.0230, 0.0242)
    '0.02360 [0.02300, 0.02420]'
    """
    if str(name).startswith("ΔE("):
        center, low = max(center, 0.0), max(low, 0.0)
    return interval_text(center, low, high)


def quantiles_text(samples: Any, prob: float = 0.95) -> str:
    """Draws as ``median [low, high]``, the equal-tailed ``prob`` interval, in the digits
    it supports (:func:`bayestribo.summary.interval_text`).

    Examples
    --------
    >>> import numpy as np
    >>> quantiles_text(np.linspace(0.02, 0.03, 1001))
    '0.0250 [0.0203, 0.0297]'
    """
    import numpy as np

    x = np.asarray(samples, dtype=float).ravel()
    if x.size == 0:
        return "–"
    lo, mid, hi = np.quantile(x, [(1 - prob) / 2, 0.5, (1 + prob) / 2])
    return interval_text(float(mid), float(lo), float(hi))


def quantity_text(result: Any, name: str, summary: Any) -> str:
    """One quantity of a fit as a reader should read it: ``mean [low, high]`` in the
    digits the interval supports, or, where its posterior is flat over its prior from
    the prior's lower end up to where the data allow (:func:`prior_flatness` at most
    :data:`FLAT_KS`, :func:`~bayestribo.inference.flatness.prior_end`), a bound:
    ``not constrained by the data: μ_s < 0.082 (...)``, the upper end of its interval in
    two digits (the fit's summary gives that interval from the prior's end, ``kind``
    ``"bound"``).

    Parameters
    ----------
    result : FitResult
    name : str
        The quantity's name in the fit.
    summary : ParameterSummary
        Its summary (``result.summary(prob)[name]``).
    """
    distance = prior_flatness(result, name)
    if is_flat(distance) and prior_end(result, name) is not None:
        symbol = _symbols(result).get(name, name)
        return (
            f"not constrained by the data: {symbol} < {summary.high:.2g} (the posterior is its "
            f"prior's up to there: Kolmogorov–Smirnov distance {distance:.2f})"
        )
    if is_bound(result, name):
        # a static friction the data bound from above only (its density at the prior's
        # lower end at least half its highest: inference/flatness.py, end_density)
        symbol = _symbols(result).get(name, name)
        share = end_density(result, name)
        return (
            f"not constrained by the data: {symbol} < {summary.high:.2g} (bounded from above "
            f"only: its density at the prior's lower end {share:.2f} of its highest)"
        )
    return interval_text(summary.mean, *summary.interval)


def share_text(share: float | None) -> str:
    """A share between 0 and 1 in three digits, ``< 0.001`` and ``> 0.999`` at its ends
    (a least-squares share of 4e-16 is zero at the precision of any estimate).

    Examples
    --------
    >>> share_text(3.8e-16), share_text(0.01845), share_text(0.99999)
    ('< 0.001', '0.0185', '> 0.999')
    """
    if share is None or not math.isfinite(share):
        return "–"
    if share < 1e-3:
        return "< 0.001"
    if share > 0.999:
        return "> 0.999"
    return f"{share:.3g}"


def _swings(band: Mapping[str, Any]) -> list[int]:
    """Indices of the largest, middle and smallest swing of a ΔE(A) band."""
    n = len(band.get("amplitude") or [])
    return sorted({n - 1, n // 2, 0}, reverse=True) if n else []


def _band_text(band: Mapping[str, Any], i: int) -> str:
    """ΔE at one swing with its interval, held at zero below (a free decay never gains
    energy: an interval reaching below zero is at its bound there)."""
    mean, (low, high) = band["mean"][i], (band["interval"][0][i], band["interval"][1][i])
    if mean is None or low is None or high is None:
        return "–"
    return interval_text(max(mean, 0.0), max(low, 0.0), high)


def fit_frame(
    result: Any,
    *,
    prob: float = 0.95,
    hidden: tuple[str, ...] = _HIDDEN,
    dissipation: bool = True,
) -> Any:
    """A Bayesian fit's results: its quantities by symbol with their interval and unit,
    then the energy dissipated per cycle ΔE(A) at the largest, middle and smallest swing
    of the analysed motion, the law's and the one measured from the turning points.

    Parameters
    ----------
    result : FitResult
    prob : float
        Probability of the intervals.
    hidden : tuple of str
        Quantities left out (the amplitude at the window's start and the static to
        kinetic friction ratio by default; sampled scales ``log10_*`` unless ``hidden``
        is empty).
    dissipation : bool
        Add the rows of ΔE(A).

    Returns
    -------
    pandas.DataFrame
        Index ``quantity``; columns ``value [95 % interval]`` and ``unit``.
    """
    import pandas as pd

    symbols = _symbols(result)
    units = result.units()
    column = f"value [{100 * prob:g} % interval]"
    rows = []
    for name, s in result.summary(prob).items():
        if name in hidden or (hidden and name.startswith("log10_")):
            continue
        rows.append(
            {
                "quantity": symbols.get(name, name),
                column: quantity_text(result, name, s),
                "unit": unit_text(units.get(name)),
            }
        )
    band = (result.dissipation or {}) if dissipation else {}
    measured = result.turning_point_dissipation or {}
    for i in _swings(band):
        amp = f"{band['amplitude'][i]:.3g} {unit_text(band['amplitude_unit'])}"
        sources = [("law", band)]
        if measured.get("amplitude"):
            sources.append(("turning points", measured))
        for source, b in sources:
            rows.append(
                {
                    "quantity": f"ΔE(A = {amp}), {source}",
                    column: _band_text(b, i),
                    "unit": unit_text(band.get("unit")),
                }
            )
    return pd.DataFrame(rows, columns=["quantity", column, "unit"]).set_index("quantity")


def dissipation_frame(result: Any, *, prob: float = 0.95, law: bool = True) -> Any:
    """The energy dissipated per cycle ΔE(A) at the largest, middle and smallest swing:
    from the turning points (the law-free answer, whatever the law) and, with ``law``,
    the fitted law's, side by side.

    Parameters
    ----------
    result : FitResult
    prob : float
        Probability of the intervals, as the fit recorded them (said in the header).
    law : bool
        Add the law's ΔE(A) as a second column.

    Returns
    -------
    pandas.DataFrame
        Index ``swing A [unit]``; columns ``ΔE(A), turning points [unit]`` and, with
        ``law``, ``ΔE(A), the law's [unit]``; empty without a band.
    """
    import pandas as pd

    measured = result.turning_point_dissipation or {}
    band = result.dissipation or {}
    base = measured if measured.get("amplitude") else band
    if not base.get("amplitude"):
        return pd.DataFrame()
    unit = unit_text(base.get("unit"))
    share = f"{100 * base.get('prob', prob):g} %"
    rows = []
    for i in _swings(base):
        row = {
            f"swing A [{unit_text(base.get('amplitude_unit'))}]": f"{base['amplitude'][i]:.3g}",
            f"ΔE(A), turning points (law-free) [{unit}] [{share}]": _band_text(measured, i)
            if measured.get("amplitude")
            else "– (too few half cycles)",
        }
        if law and band.get("amplitude"):
            row[f"ΔE(A), the law's [{unit}] [{share}]"] = _band_text(band, i)
        rows.append(row)
    frame = pd.DataFrame(rows)
    return frame.set_index(frame.columns[0])


def diagnostics_frame(result: Any) -> Any:
    """The sampler's diagnostics per sampled quantity, by symbol: autocorrelation time,
    effective sample size, R-hat between the ensembles, and how far the posterior mean
    moves when the prior is weakened or strengthened, with the prior's contraction.

    Returns
    -------
    pandas.DataFrame
        Index ``quantity``.
    """
    import pandas as pd

    d = result.diagnostics
    symbols = _symbols(result)
    if "mu_k" not in result.summary():  # no load: the sampled friction is x_c in units of ℓ
        symbols["mu_k"] = "x_c/ℓ"
    sensitivity = result.prior_sensitivity or {}
    rows = []
    for name, tau in (d.get("autocorr_time") or {}).items():
        sens = sensitivity.get(name, {})
        rows.append(
            {
                "quantity": symbols.get(name, name),
                "autocorrelation time [steps]": f"{tau:.1f}",
                "effective sample size": f"{d['ess'][name]:.0f}",
                "R-hat": f"{d['rhat'][name]:.4f}",
                "mean's shift, prior ×/÷ [posterior sd]": "–"
                if sens.get("mean_shift_sd") is None
                else f"{sens['mean_shift_sd']:.2g}",
                "prior contraction": "–"
                if sens.get("contraction") is None
                else f"{sens['contraction']:.3f}",
            }
        )
    return pd.DataFrame(rows).set_index("quantity")


def fit_facts(result: Any) -> dict[str, str]:
    """How a Bayesian fit was made and how it went, as label -> sentence: the law, the
    model, the noise, the sampler's convergence, the shape of the decay against the law,
    the frequency's change along the decay, any posterior piled on a prior bound, and
    the time the fit took."""
    d = result.diagnostics
    facts = {"law": law_text(result.law)}
    comparison = result.law_comparison
    if comparison:
        facts["law"] += f" (chosen among the registered laws; best: {law_text(comparison['best'])})"
    facts["model"] = f"{result.model} model of Π, seed {result.seed}"
    noise = (result.noise or {}).get("description")
    if noise:
        facts["noise"] = noise
    runs = (
        f"{count(d.get('n_walkers'), 'walker')} × {count(d.get('n_ensembles'), 'ensemble')} × "
        f"{count(d.get('n_steps'), 'step')}"
    )
    stats = (
        f"autocorrelation time ≤ {d.get('autocorr_time_max', 0):.1f} steps, effective sample "
        f"size ≥ {d.get('ess_min', 0):.0f}, R-hat ≤ {d.get('rhat_max', 0):.4f}"
    )
    if d.get("converged"):
        facts["sampler"] = f"converged: {runs}; {stats}"
    else:
        reasons = prose("; ".join(d.get("reasons", [])))
        facts["sampler"] = f"not converged ({reasons}): {runs}"
    shape = d.get("shape_departure") or {}
    if shape.get("p_value") is not None:
        if getattr(result, "law_departs", False):
            from bayestribo.inference.likelihood import departure_size

            facts["shape of the decay"] = (
                f"departs from the law by up to {departure_size(shape)} along the decay: the "
                "law does not hold, and its parameters are not a measurement"
            )
        else:
            facts["shape of the decay"] = f"follows the law (p = {shape['p_value']:.2g})"
    trend = result.frequency_trend
    if trend:
        facts["frequency"] = (
            f"the half period changes by {100 * trend['change']:+.3g} % along the decay "
            f"({trend['z']:+.1f} standard errors)"
        )
    for entry in result.at_prior_bound:
        symbol = _symbols(result).get(entry["parameter"], entry["parameter"])
        facts[f"{symbol} at its prior's bound"] = (
            f"piles on {entry['bound']:.4g}: not a measurement; check units and channels"
        )
    facts["fit time"] = f"{result.seconds:.1f} s"
    return facts


def method_text(estimate: Any, *, physics: bool = False) -> str:
    """A classical estimate's method in words, with the signal it used (x: displacement
    peaks, v: velocity peaks); with ``physics``, a method that leaves friction out of its
    model says so ("logarithmic decrement (x), ignores friction").

    Examples
    --------
    >>> from types import SimpleNamespace as E
    >>> e = E(method="log_decrement", data="displacement peaks", notes="assumes no friction")
    >>> method_text(e), method_text(e, physics=True)
    ('logarithmic decrement (x)', 'logarithmic decrement (x), ignores friction')
    """
    name = METHOD_NAMES.get(estimate.method, estimate.method.replace("_", " "))
    if estimate.data.startswith("displacement"):
        name += " (x)"
    elif estimate.data.startswith("velocity"):
        name += " (v)"
    if physics and _ignores_friction(estimate.notes or ""):
        name += ", ignores friction"
    return name


def _ignores_friction(notes: str) -> bool:
    return "assumes no friction" in notes


def caveat_text(estimate: Any) -> str:
    """What a reader must know before using a classical estimate, in a few words: an
    unphysical (negative) ζ or friction, a method that ignores friction (its ζ is too
    high where there is some), an interval too narrow (correlated residuals) or one that
    holds the peaks' noise only; a dash when there is nothing to say.

    Examples
    --------
    >>> from types import SimpleNamespace as E
    >>> caveat_text(E(zeta=0.02, mu_k=-0.003, friction_displacement=None, notes=""))
    'negative friction: unphysical, not a measurement'
    >>> caveat_text(E(zeta=0.05, mu_k=None, friction_displacement=None,
    ...               notes="assumes no friction (μ_k = 0)"))
    'ignores friction: ζ too high where there is some'
    """
    notes = estimate.notes or ""
    said = []
    if estimate.zeta is not None and estimate.zeta < 0:
        said.append("negative ζ: unphysical, not a measurement")
    friction = [getattr(estimate, n, None) for n in ("mu_k", "friction_displacement")]
    if any(f is not None and f < 0 for f in friction):
        said.append("negative friction: unphysical, not a measurement")
    if _ignores_friction(notes):
        said.append("ignores friction: ζ too high where there is some")
    if "too small" in notes:
        said.append("interval too narrow (correlated residuals)")
    if "peak noise only" in notes and not _ignores_friction(notes):
        said.append("interval from the peak noise only")
    return "; ".join(said) or "–"


def _signed_interval(value: float | None, se: float | None, too_narrow: bool = False) -> str:
    """A classical estimate's interval: at its bound at zero where it reaches below zero
    from a positive value, as it is where the value itself is negative (unphysical,
    said in the caveat); four digits where it is known to be too narrow."""
    positive = value is not None and value >= 0
    return normal_interval(value, se, positive=positive, too_narrow=too_narrow)


def estimates_frame(table: Any, *, unit: str = "m") -> Any:
    """Classical estimates of one recording: per method (x: displacement peaks, v:
    velocity peaks), ζ and the friction (μ_k where load and mass are known, else the
    friction displacement x_c in ``unit``) with ±1.96 standard errors, the share of the
    energy lost to friction, and a caveat (:func:`caveat_text`): a negative ζ or friction
    is unphysical, a method that *ignores friction* gives a ζ too high where there is
    some, an interval may be *too narrow* (correlated residuals) or hold the peaks' noise
    only.

    Returns
    -------
    pandas.DataFrame
        Index ``method``; columns ``ζ [95 %]``, ``μ_k [95 %]`` or ``x_c [unit] [95 %]``
        (``θ_c [rad] [95 %]`` for a rotation), ``friction share``, ``caveat``.
    """
    import pandas as pd

    estimates = list(table)
    has_mu = any(e.mu_k is not None for e in estimates)
    friction = "mu_k" if has_mu else "friction_displacement"
    symbol = "θ_c" if unit == "rad" else "x_c"  # a rotation's friction is an angle
    label = "μ_k [95 %]" if has_mu else f"{symbol} [{unit_text(unit)}] [95 %]"
    rows = []
    for e in estimates:
        value = getattr(e, friction)
        rows.append(
            {
                "method": method_text(e),
                "ζ [95 %]": _signed_interval(e.zeta, e.zeta_se, interval_too_narrow(e)),
                label: "–"
                if value is None
                else _signed_interval(value, getattr(e, f"{friction}_se"), interval_too_narrow(e)),
                "friction share": share_text(e.friction_fraction),
                "caveat": caveat_text(e),
            }
        )
    return pd.DataFrame(rows).set_index("method")


def windows_frame(adequacy: Any, *, unit: str | None = None) -> Any:
    """The windowed fits of an adequacy check, then its two halves (if made): time span,
    amplitude range, ζ and the friction with their 95 % intervals (the friction left out
    where the windows hold it at the whole decay's value), and whether an estimate sits
    on a parameter's bound.

    Parameters
    ----------
    adequacy : AdequacyResult
    unit : str, optional
        The amplitudes' and friction displacement's unit (default: the check's own,
        "signal unit" without a load; "m" for a recording in metres).

    Returns
    -------
    pandas.DataFrame
        Index ``window`` (1, 2, ..., "first half", "second half").
    """
    import pandas as pd

    w = adequacy.windows
    unit = unit_text(unit or w.length_unit)
    friction = "μ_k" if w.friction_name == "mu_k" else f"{w.friction_symbol} [{unit}]"
    held = w.extra.get("friction_mode", "fit") == "fixed"

    def row(label: Any, x: Any) -> dict[str, Any]:
        out = {
            "window": label,
            "t [s]": f"{x.t_start:.3f} to {x.t_end:.3f}",
            f"amplitude [{unit}]": f"{x.amplitude_range[0]:.3g} to {x.amplitude_range[1]:.3g}",
            "ζ [95 %]": interval_text(x.zeta, *x.zeta_interval),
        }
        if not held:
            out[f"{friction} [95 %]"] = interval_text(x.mu, *x.mu_interval)
        out["on a bound"] = "–" if getattr(x, "regular", True) else "yes"
        return out

    rows = [row(x.index + 1, x) for x in w.windows]
    if adequacy.halves is not None:
        h = adequacy.halves
        rows += [row("first half", h.first), row("second half", h.second)]
    return pd.DataFrame(rows).set_index("window")
