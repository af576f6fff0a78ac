"""A fit's law as the reports say it: its terms in words, whether it holds, and the
share of the energy its friction terms dissipate.

Everything here is read from the law's registry entry
(:data:`bayestribo.model.laws.TERMS`: each term's kind, parameters, symbols and units)
and from the fit result, never from a list of laws: a term registered tomorrow is
named, tabulated and split into friction and drag with no edit here.

* :func:`term_words` and :func:`law_text`: ``"coulomb+power"`` -> ``"Coulomb friction +
  power-law drag"``, from each term's one-line description;
* :func:`law_holds`: whether the fit's law describes the recording (no misfit, the
  shape of its ΔE(A) that of the turning points, and, for ``law = auto``, a law found
  adequate); where none holds the answer is the turning points' ΔE(A) (the law-free
  answer, :func:`bayestribo.inference.dissipation.turning_point_dissipation`);
* :func:`energy_share`: per posterior draw, the share of the energy lost per cycle at a
  swing A to the law's friction terms against its drag terms (each term's own
  ΔE(A) over the harmonic motion, :meth:`bayestribo.model.laws.Law.dissipation`), or
  why there is none (no friction term, no drag term);
* :func:`paper_parameters`: the paper's ζ and friction (μ_k, or x_c without a load)
  where the law has them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "EnergyShare",
    "adequacy_reason",
    "energy_share",
    "law_holds",
    "law_text",
    "paper_parameters",
    "share_rows",
    "term_words",
    "terms_of_kind",
]


def term_words(name: str) -> str:
    """A registered term in words: the leading words of its description (the words
    before its first symbol), the term's name for a term not registered.

    Examples
    --------
    >>> term_words("coulomb"), term_words("power"), term_words("hysteretic")
    ('Coulomb friction', 'power-law drag', 'friction proportional to amplitude')
    >>> term_words("unknown_term")
    'unknown_term'
    """
    from bayestribo.model.laws import TERMS

    term = TERMS.get(name)
    if term is None:
        return name
    words = []
    for word in term.description.split():
        if not (word.replace("-", "").isascii() and word.replace("-", "").isalpha()):
            break
        if len(word) == 1:  # a one-letter symbol (the c of "c v")
            break
        words.append(word)
    return " ".join(words) or name


def law_text(law: str) -> str:
    """A dissipation law in words, each term from the registry (:func:`term_words`).

    Examples
    --------
    >>> law_text("viscous+coulomb")
    'viscous damping + Coulomb friction'
    >>> law_text("coulomb+power")
    'Coulomb friction + power-law drag'
    """
    return " + ".join(term_words(t) for t in str(law).split("+"))


def _law(result: Any) -> Any | None:
    """The registered law of a fit, or None for a law this version does not register."""
    from bayestribo.model.laws import get_law

    try:
        return get_law(result.law)
    except ValueError:
        return None


def terms_of_kind(law: str, kind: str) -> list[str]:
    """Names of a law's terms of one kind (``"drag"`` or ``"friction"``), in the
    law's order; empty for a law that is not registered.

    Examples
    --------
    >>> terms_of_kind("viscous+coulomb+quadratic", "drag")
    ['viscous', 'quadratic']
    """
    from bayestribo.model.laws import get_law

    try:
        return [t.name for t in get_law(law).terms if t.kind == kind]
    except ValueError:
        return []


def law_holds(result: Any) -> tuple[bool, str]:
    """Whether the fit's law describes the recording, and why not.

    The law does not hold when the decay's shape departs from it
    (``diagnostics["shape_departure"]``) or its residuals misfit the noise
    (``diagnostics["misfit_p"]`` without discrepancy terms), both below the fit's
    misfit threshold; when its ΔE(A) has another shape than the turning points'
    (:attr:`~bayestribo.inference.result.FitResult.law_departs`); or when
    ``law = auto`` found no law compared adequate. Then the measurement is ΔE(A) from
    the turning points, whatever the law.

    Returns
    -------
    holds : bool
    why : str
        Empty when it holds; else the reason in a few words.
    """
    from bayestribo.inference.pipeline import MISFIT_P

    d = result.diagnostics or {}
    comparison = result.law_comparison or {}
    if comparison and comparison.get("adequate") is False:
        return False, "no law compared describes the recording"
    shape = d.get("shape_departure") or {}
    if shape.get("p_value") is not None and shape["p_value"] < MISFIT_P:
        from bayestribo.inference.likelihood import departure_size

        off = shape.get("max_relative")
        by = "" if off is None else f" by up to {departure_size(shape)}".replace("-", "−")
        return False, f"the decay departs from the law{by}"
    discrepancy = any(n.startswith("log10_") for n in result.parameter_names)
    white = d.get("misfit_p")
    if not discrepancy and white is not None and white < MISFIT_P:
        return False, f"the law misfits the decay beyond its noise (p = {white:.2g})"
    agreement = result.shape_agreement or {}
    if agreement and agreement.get("same_shape") is False:
        return False, "the law's ΔE(A) has another shape than the turning points'"
    return True, ""


def paper_parameters(result: Any) -> dict[str, str]:
    """The paper's quantities the fit has, by name -> symbol: ζ where the law has
    viscous damping, μ_k (with a load) or x_c (without) where it has Coulomb friction.

    Examples
    --------
    >>> from types import SimpleNamespace as R
    >>> paper_parameters(R(parameter_names=["zeta_alpha", "alpha", "friction_displacement"]))
    {'friction_displacement': 'x_c'}
    """
    from bayestribo.reports.tables import SYMBOLS

    names = set(result.parameter_names)
    info = getattr(result, "quantity_info", None)
    symbols = {**SYMBOLS, **({n: q.symbol for n, q in info().items()} if callable(info) else {})}
    out = {}
    if "zeta" in names:
        out["zeta"] = symbols["zeta"]
    for friction in ("mu_k", "friction_displacement"):
        if friction in names:
            out[friction] = symbols[friction]  # θ_c for a rotation
            break
    return out


@dataclass(frozen=True)
class EnergyShare:
    """The share of the energy lost per cycle to a law's friction terms, per draw.

    Attributes
    ----------
    swing : float
        The swing A it is taken at [``unit``].
    unit : str
        Unit of the swing.
    draws : ndarray or None
        Friction's share of ΔE(A) per posterior draw, in [0, 1]; None where the law
        lacks a friction or a drag term (``said`` tells which).
    friction : list of str
        The law's friction terms in words.
    drag : list of str
        The law's drag terms in words.
    said : str
        Empty, or why there is no share ("no friction term: all drag").
    """

    swing: float
    unit: str
    draws: NDArray | None
    friction: list[str]
    drag: list[str]
    said: str = ""

    @property
    def median(self) -> float:
        """Median share; 0 or 1 for a law of one kind of term, NaN without a law."""
        if self.draws is not None:
            return float(np.median(self.draws))
        if not self.friction and self.drag:
            return 0.0
        if self.friction and not self.drag:
            return 1.0
        return float("nan")

    def interval(self, prob: float = 0.95) -> tuple[float, float]:
        """Equal-tailed interval of the share (both ends the median for a law of one
        kind of term)."""
        if self.draws is None:
            return self.median, self.median
        tail = 0.5 * (1.0 - prob)
        lo, hi = np.quantile(self.draws, [tail, 1.0 - tail])
        return float(lo), float(hi)

    def text(self, prob: float = 0.95) -> str:
        """The share with its interval in the digits the interval supports
        (:func:`bayestribo.summary.interval_text`: its ends never print as its median),
        or what the law says instead."""
        from bayestribo.summary import interval_text

        if self.draws is None:
            return self.said or "–"
        return interval_text(self.median, *self.interval(prob))

    def to_dict(self, prob: float = 0.95) -> dict[str, Any]:
        """JSON-ready: the swing [``unit``], and the share's ``median`` with its
        ``interval`` (absent without draws, ``said`` telling why)."""
        out: dict[str, Any] = {"swing": self.swing, "unit": self.unit}
        if self.draws is None:
            return {**out, "said": self.said}
        return {**out, "median": self.median, "interval": list(self.interval(prob))}

    @property
    def dominant(self) -> str:
        """Which kind of term dissipates most at this swing, in words ("friction",
        "drag (viscous damping)"), or "–"."""
        share = self.median
        if not np.isfinite(share):
            return "–"
        if share > 0.5:
            return "friction"
        return "drag (" + " + ".join(self.drag) + ")" if self.drag else "drag"


def _draws_of(result: Any, law: Any, size: int, rng: np.random.Generator) -> dict[str, NDArray]:
    """``size`` posterior draws of the law's dimensionless parameters, by name: sampled
    ones from the posterior (the Coulomb friction of a run without a load from its
    friction displacement over ℓ), fixed ones at their value, absent ones at the value
    at which their term exerts no force."""
    names = set(result.parameter_names)
    n = result.samples("y0").size
    pick = rng.choice(n, size=min(size, n), replace=False)
    fixed = json.loads(result.attrs.get("fixed_json", "{}") or "{}")
    length = float(result.attrs.get("length_scale", 1.0) or 1.0)
    values: dict[str, NDArray] = {"y0": np.abs(result.samples("y0")[pick])}
    for p in law.parameters:
        if p.name == "mu_k" and "mu_k" not in names and "friction_displacement" in names:
            values[p.name] = result.samples("friction_displacement")[pick] / length
        elif p.name in names:
            values[p.name] = result.samples(p.name)[pick]
        elif p.name in fixed:
            values[p.name] = np.full(pick.size, float(fixed[p.name]))
        else:
            values[p.name] = np.full(pick.size, float(p.null))
    return values


def energy_share(
    result: Any,
    swing: float | None = None,
    *,
    draws: int = 400,
    seed: int | None = 0,
) -> EnergyShare:
    """The share of the energy lost per cycle at the swing A to the law's friction
    terms, against its drag terms, per posterior draw.

    Each term's energy per cycle of the harmonic motion ``y = A cos τ``
    (:meth:`bayestribo.model.laws.Law.dissipation` with ``by_term``) is summed over
    the terms of each kind; the share is friction's over the total, as the fit's ΔE(A)
    band splits between its terms (``by_term`` of
    :func:`bayestribo.inference.dissipation.dissipation_band`). For viscous damping and
    Coulomb friction it is ``4μ_kA / (4μ_kA + 2πζA²)``: friction's share grows as the
    swing shrinks.

    Parameters
    ----------
    result : FitResult
    swing : float, optional
        The swing A [the band's amplitude unit]; default the largest swing of the fit's
        ΔE(A) band (the analysed motion's first).
    draws : int
        Posterior draws used (at most all).
    seed : int or None
        Seed of the choice of draws.

    Returns
    -------
    EnergyShare
        Its ``draws`` None where the law has no friction term or no drag term (said),
        or is not registered.
    """
    band = result.dissipation or {}
    amplitudes = band.get("amplitude") or []
    unit = band.get("amplitude_unit") or ""
    if swing is None:
        swing = float(max(amplitudes)) if amplitudes else float("nan")
    law = _law(result)
    if law is None:
        return EnergyShare(swing, unit, None, [], [], f"the law {result.law} is not registered")
    friction = [term_words(t.name) for t in law.terms if t.kind == "friction"]
    drag = [term_words(t.name) for t in law.terms if t.kind == "drag"]
    if not friction:
        return EnergyShare(swing, unit, None, friction, drag, "0: no friction term (all drag)")
    if not drag:
        return EnergyShare(swing, unit, None, friction, drag, "1: no drag term (all friction)")
    if not np.isfinite(swing) or "y0" not in result.parameter_names:
        return EnergyShare(swing, unit, None, friction, drag, "no swing to take it at")
    rng = np.random.default_rng(seed)
    values = _draws_of(result, law, draws, rng)
    length = float(result.attrs.get("length_scale", 1.0) or 1.0)
    reference = float(np.median(values.pop("y0")))
    parts = law.dissipation(np.array([swing / length]), values, reference, by_term=True)
    kinds = {t.name: t.kind for t in law.terms}
    lost = {
        kind: sum(np.ravel(v) for k, v in parts.items() if kinds[k] == kind)
        for kind in ("friction", "drag")
    }
    total = lost["friction"] + lost["drag"]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total > 0, lost["friction"] / total, np.nan)
    share = share[np.isfinite(share)]
    if share.size == 0:
        return EnergyShare(swing, unit, None, friction, drag, "no energy lost at this swing")
    return EnergyShare(swing, unit, np.clip(share, 0.0, 1.0), friction, drag)


def share_rows(result: Any, *, seed: int | None = 0) -> dict[str, EnergyShare]:
    """:func:`energy_share` at the largest and the smallest swing of the fit's ΔE(A)
    band, by label (``"largest swing"``, ``"smallest swing"``); empty without a band."""
    amplitudes = (result.dissipation or {}).get("amplitude") or []
    if not amplitudes:
        return {}
    out = {"largest swing": energy_share(result, float(max(amplitudes)), seed=seed)}
    if min(amplitudes) < max(amplitudes):
        out["smallest swing"] = energy_share(result, float(min(amplitudes)), seed=seed)
    return out


#: The sampled parameters the adequacy checks' windowed fits model (viscous damping and
#: Coulomb friction, :mod:`bayestribo.adequacy.windows`), with the static friction.
_WINDOWED = frozenset({"zeta", "mu_k", "mu_s_ratio"})


def adequacy_reason(result: Any) -> str | None:
    """Why the adequacy checks (windows, end of motion, predictive peaks, halves:
    :func:`bayestribo.adequacy.check_adequacy`) do not apply to a fit, or None where
    they do: they model ζ and Coulomb friction (the paper's law), so they test a law
    whose parameters are those (a friction term among them), and no other.

    Examples
    --------
    >>> from types import SimpleNamespace as R
    >>> adequacy_reason(R(law="viscous+coulomb")) is None
    True
    >>> adequacy_reason(R(law="coulomb+power"))[:40]
    "the model checks' windowed fits model ζ "
    """
    law = _law(result)
    if law is None:
        return f"the law {result.law} is not registered: the model checks cannot test it"
    names = set(law.parameter_names)
    if names <= _WINDOWED and "zeta" in names and law.friction:
        return None
    if names <= _WINDOWED and not law.friction:
        return (
            "this fit's law has no friction term (no contact): the model checks test constant "
            "ζ and friction together, so they are left out"
        )
    return (
        "the model checks' windowed fits model ζ and Coulomb friction (the paper's law); "
        f"this fit's law is {law_text(law.name)}: it is tested instead by the shape of the "
        "decay against the law and by its ΔE(A) against the turning points' (the answer)"
    )
