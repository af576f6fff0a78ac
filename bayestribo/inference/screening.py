"""Screening: laws that cannot win, told at their optima before any sampling.

Every law is first taken to its optimum (smallest first, each starting
also from the optimum of the largest law it nests), on the posterior it would be
sampled on (the second pass of :func:`bayestribo.inference.chains.sample`), and its
expected log predictive density estimated there: the log-likelihood of the increments
at the optimum less one per sampled parameter (:func:`optimum_elpd`, Akaike's
estimate, which PSIS-LOO's matches for a law whose posterior is near normal). A law
whose estimate falls behind the best one's by more than :data:`SCREEN_FACTOR` (3)
times the tie rule's reach, ``max(4, 2 dse)`` with dse the standard error of the
pointwise difference at the two optima, cannot be as good as the best once sampled:
it is *screened out*, not sampled and not compared by PSIS-LOO (:func:`screen`); its
row says ``screened``, ``screen`` (the estimate, its sd and the limit) and the
misfit checks at its optimum, and the comparison's text names it. The rest are
sampled as before (a law that reduces to a nested law sampled is not), compared by
PSIS-LOO, and decide the verdict. Against the sampled comparison of every candidate
(``benchmarks/auto_screening.py``: the bundled run and the five real recordings of
``../shared/external-data``, side by side with the comparison before screening) no
law screened out was as good as the best there, and the verdicts are the same.

A law that is, at its optimum, a law screened out is screened out with it
(:func:`screened_by_reduction`): its extra terms sit on their null there, within
half a unit of log density (the rule of :mod:`bayestribo.inference.reduction`), and
its own estimate is clearly behind the best's (beyond the tie rule's reach by a
third of it, as :mod:`bayestribo.inference.settling` judges a standing). The nested law
stands for it, as a law sampled and converged stands for the laws that reduce to it.
Such a law's own estimate is no steadier than its optimiser's path: far behind the
best, the dse grows with the difference, and a change in the last digits of the exact
Π kernel that moves the optimiser's path moves their ratio across the screen's limit.
On the simulated ``coulomb+hysteretic`` decay of ``benchmarks/laws.py`` (run 1 at 10x
the resolution), ``viscous+quadratic`` and ``quadratic+hysteretic`` have γ = 0 at their
optimum and are 3.3e9 behind the best at 4.3 and 4.7 dse, where the ``viscous`` and
``hysteretic`` they reduce to are at 6.1 dse, screened out; sampled (on the exact
posterior, three surrogates having failed) they took nine tenths of the fit's time, and
PSIS-LOO put them 5.9 and 6.1 dse behind the best, misfitting.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.choice import SMALL_ELPD_DIFFERENCE, law_of
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.types import PreparedRun

__all__ = [
    "SCREEN_FACTOR",
    "TURNING_POINT_FACTOR",
    "LawOptimum",
    "optimum_elpd",
    "screen",
    "screened_by_reduction",
    "turning_point_misfit",
    "turning_point_screen",
]

#: How many times the tie rule's reach (``max(SMALL_ELPD_DIFFERENCE, 2 dse)``) a law's
#: elpd estimated at its optimum must fall behind the best's to be screened out, not
#: sampled (module notes).
SCREEN_FACTOR = 3.0
#: How many times the best law's χ² against the turning points' ΔE(A) (plus the number
#: of swings) a law's must exceed for it to be screened out before its optimum is
#: sought (module notes).
TURNING_POINT_FACTOR = 1000.0


#: A law's second pass: the posterior sampled, its optimum and the pointwise
#: log-likelihood there (:class:`LawOptimum`).
SecondPass = tuple[Posterior, tuple[NDArray, NDArray, tuple[float, float] | None], NDArray]


class LawOptimum:
    """One law at its optimum, before any sampling (the screening's input).

    The second pass (``second``, ``second_optimum``, ``pointwise``) is given, or made
    by ``finish`` when first asked for (:attr:`pending` until then): the comparison
    leaves it undone for a law whose optimum is a law it nests (its extra terms at
    zero, :mod:`bayestribo.inference.reduction`) until the law is judged on its own.

    Attributes
    ----------
    law : str
        The law compared.
    posterior : Posterior
        Its posterior on the first pass (variances from the observed channels).
    optimum : tuple
        Its maximum a posteriori there, Laplace covariance and μ_s/μ_k interval
        (:func:`bayestribo.inference.start.find_optimum`).
    second : Posterior
        The posterior that is sampled: the second pass's, variances from the law's
        motion at ``optimum`` (:func:`bayestribo.inference.reweight.reweighted_posterior`),
        or ``posterior`` where there is none.
    second_optimum : tuple
        The maximum a posteriori of ``second``.
    pointwise : ndarray
        Log-likelihood of each Π increment at ``second_optimum`` under ``second``.
    """

    def __init__(
        self,
        law: str,
        posterior: Posterior,
        optimum: tuple[NDArray, NDArray, tuple[float, float] | None],
        second: Posterior | None = None,
        second_optimum: tuple[NDArray, NDArray, tuple[float, float] | None] | None = None,
        pointwise: NDArray | None = None,
        *,
        finish: Callable[[], SecondPass] | None = None,
    ) -> None:
        self.law, self.posterior, self.optimum = law, posterior, optimum
        if finish is None and (second is None or second_optimum is None or pointwise is None):
            raise ValueError("LawOptimum: expected the second pass or a way to make it")
        self._second: SecondPass | None = None
        if finish is None:
            self._second = (second, second_optimum, pointwise)
        self._finish = finish

    @property
    def pending(self) -> bool:
        """Whether the second pass is still to be made."""
        return self._second is None

    def _second_pass(self) -> SecondPass:
        if self._second is None:
            assert self._finish is not None
            self._second, self._finish = self._finish(), None
        return self._second

    @property
    def second(self) -> Posterior:
        """The posterior that is sampled (class notes)."""
        return self._second_pass()[0]

    @property
    def second_optimum(self) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
        """The maximum a posteriori of :attr:`second`."""
        return self._second_pass()[1]

    @property
    def pointwise(self) -> NDArray:
        """Log-likelihood of each Π increment at :attr:`second_optimum`."""
        return self._second_pass()[2]

    @property
    def n_parameters(self) -> int:
        """Sampled parameters of its posterior (the same on both passes)."""
        return len(self.posterior.names)


def optimum_elpd(pointwise: NDArray, n_parameters: int) -> float:
    """Expected log predictive density estimated at a law's optimum: the sum of the
    pointwise log-likelihood there less one per sampled parameter (Akaike 1974; what
    PSIS-LOO's ``p_loo`` is for a law whose posterior is near normal)."""
    return float(np.sum(pointwise)) - float(n_parameters)


def screen(
    pointwise: Mapping[str, NDArray],
    n_parameters: Mapping[str, int],
    *,
    factor: float | None = None,
) -> dict[str, dict[str, Any]]:
    """Which laws can still win, judged at their optima (module notes).

    Parameters
    ----------
    pointwise : mapping of str to ndarray
        Each law's log-likelihood of every Π increment at its optimum (one shape).
    n_parameters : mapping of str to int
        Each law's sampled parameters.
    factor : float, optional
        How many times the comparison's own tie rule, ``max(SMALL_ELPD_DIFFERENCE,
        2 dse)``, a law must fall behind the best to be screened out; default
        :data:`SCREEN_FACTOR`.

    Returns
    -------
    dict
        Law -> ``elpd_diff`` (the best law's :func:`optimum_elpd` less this one's),
        ``dse`` (the standard error of that difference over the increments),
        ``limit`` (the difference beyond which the law is screened out), ``best`` (the
        law of the highest estimate) and ``screened`` (True: it cannot win). A law whose
        estimate is not finite is screened out.
    """
    factor = SCREEN_FACTOR if factor is None else float(factor)
    elpd = {
        law: optimum_elpd(np.asarray(lpd, dtype=float), n_parameters[law])
        for law, lpd in pointwise.items()
    }
    finite = [law for law, value in elpd.items() if np.isfinite(value)]
    out: dict[str, dict[str, Any]] = {}
    if not finite:
        return {law: {"screened": False, "best": None} for law in elpd}
    best = max(finite, key=elpd.__getitem__)
    top = np.asarray(pointwise[best], dtype=float)
    for law, value in elpd.items():
        if law not in finite:
            out[law] = {"elpd_diff": None, "dse": None, "limit": None, "best": best}
            out[law]["screened"] = True
            continue
        d = top - np.asarray(pointwise[law], dtype=float)
        dse = float(np.sqrt(d.size * np.var(d))) if d.size > 1 else 0.0
        diff = elpd[best] - value
        limit = factor * max(SMALL_ELPD_DIFFERENCE, 2.0 * dse)
        out[law] = {
            "elpd_diff": float(diff),
            "dse": dse,
            "limit": float(limit),
            "best": best,
            "screened": bool(diff > limit),
        }
    return out


def screened_by_reduction(
    order: Sequence[str],
    screens: Mapping[str, Mapping[str, Any]],
    reduces: Callable[[str, list[str]], tuple[str, list[str]] | None],
) -> dict[str, dict[str, Any]]:
    """The laws left by :func:`screen` that are, at their optimum, a law it screened out
    (module notes).

    Parameters
    ----------
    order : sequence of str
        The laws, smallest first: a law screened out here counts as screened out for
        the laws after it.
    screens : mapping
        :func:`screen`'s answer.
    reduces : callable
        ``reduces(law, laws)``: the one of ``laws`` that ``law`` reduces to at its
        optimum and the terms at zero, or None
        (:func:`bayestribo.inference.reduction.reduction_among`).

    Returns
    -------
    dict
        Law -> its row of ``screens`` with ``stage`` "reduction", ``screened`` True,
        ``reduces_to`` (the law screened out that it is at its optimum) and
        ``terms_at_zero``. A law whose estimate is not clearly behind the best's,
        beyond the tie rule's reach ``max(4, 2 dse)`` by a third of it (as
        :func:`bayestribo.inference.settling.settle` judges a law's standing), is never
        screened out this way.
    """
    out_laws = [law for law in order if screens.get(law, {}).get("screened")]
    out: dict[str, dict[str, Any]] = {}
    for law in order:
        row = screens.get(law)
        if not row or row.get("screened") or row.get("elpd_diff") is None:
            continue
        reach = max(SMALL_ELPD_DIFFERENCE, 2.0 * row["dse"])
        if not row["elpd_diff"] >= reach * (1.0 + 1.0 / SCREEN_FACTOR):
            continue
        reduced = reduces(law, list(out_laws))
        if reduced is None:
            continue
        out[law] = {
            **row,
            "stage": "reduction",
            "screened": True,
            "reduces_to": reduced[0],
            "terms_at_zero": list(reduced[1]),
        }
        out_laws.append(law)
    return out


def _shape_grid(p: Any, reference: float, n: int = 25) -> NDArray:
    """Values of a parameter that shapes a term (not its amount) to scan: its prior's
    range where that is finite, else its support's."""
    spec = p.prior(reference)
    low, high = float(spec.get("low", p.low)), float(spec.get("high", p.high))
    if not (np.isfinite(low) and np.isfinite(high)):
        low, high = p.low, p.high
    return np.linspace(low, high, n) if np.isfinite(high) else np.array([low])


def _term_bases(term: Any, swings: NDArray, reference: float) -> list[tuple[NDArray, Any]] | None:
    """Each shape of a term's ΔE(A) at ``swings`` per unit of its amount (the parameter
    whose null stops the term and in which ΔE(A) is linear), with that parameter;
    None when the term has no such parameter (it is then never screened this way)."""
    for amount in term.parameters:
        others = [p for p in term.parameters if p is not amount]
        grids = [_shape_grid(p, reference) for p in others]
        combos = np.zeros((1, 0))
        if others:
            combos = np.array(np.meshgrid(*grids, indexing="ij")).reshape(len(others), -1).T
        out = []
        for combo in combos:
            values = {p.name: np.array([v]) for p, v in zip(others, combo, strict=True)}

            def at(x: float, values: dict = values, name: str = amount.name) -> NDArray:
                vals = {**values, name: np.array([x])}
                return np.asarray(term.dissipation(swings, vals, reference), dtype=float).ravel()

            with np.errstate(all="ignore"):
                zero, one = at(float(amount.null)), at(float(amount.null) + 1.0)
                two = at(float(amount.null) + 2.0)
            if not (np.all(zero == 0.0) and np.allclose(two, 2.0 * one, rtol=1e-9)):
                out = None
                break
            out.append((one, amount))
        if out:
            # shapes that do not differ (a parameter ΔE(A) does not see) count once
            unique = {tuple(np.round(b / (np.max(np.abs(b)) or 1.0), 12)): (b, a) for b, a in out}
            return list(unique.values())
    return None


def turning_point_misfit(
    law: str, swings: NDArray, mean: NDArray, sd: NDArray, reference: float
) -> float | None:
    """The least χ² of a law's ΔE(A) over one cycle of the harmonic motion
    (:meth:`~bayestribo.model.laws.Law.dissipation`, each term's amount within its
    support, each shape parameter over its prior) against the turning points' ΔE(A)
    (:func:`bayestribo.inference.dissipation.turning_point_dissipation`); None when a
    term's ΔE(A) is not linear in an amount (the law is then not judged this way)."""
    from itertools import product

    from scipy.optimize import lsq_linear

    per_term = [_term_bases(t, swings, reference) for t in law_of(law).terms]
    if any(b is None for b in per_term):
        return None
    best = np.inf
    for choice in product(*per_term):
        design = np.column_stack([b / sd for b, _ in choice])
        low = [a.low - a.null for _, a in choice]
        high = [a.high - a.null for _, a in choice]
        fit = lsq_linear(design, mean / sd, bounds=(low, high))
        best = min(best, float(2.0 * fit.cost))
    return best


def turning_point_screen(
    prepared: PreparedRun, laws: Sequence[str], factor: float | None = None
) -> dict[str, dict[str, Any]]:
    """Laws whose ΔE(A) cannot follow the turning points' (module notes):
    law -> ``chi2`` (:func:`turning_point_misfit`), ``limit`` (``factor`` times the
    best law's χ² plus the number of swings; :data:`TURNING_POINT_FACTOR` by default)
    and ``screened``. Empty without a turning-point ΔE(A)."""
    from bayestribo.inference.dissipation import (
        dissipation_amplitudes,
        turning_point_dissipation,
    )
    from bayestribo.model.laws import PhysicalScale

    factor = TURNING_POINT_FACTOR if factor is None else float(factor)
    from bayestribo.inference.law_free import law_free_turning_points

    # the turning points of the law-free answer (a coarse displacement's staircase's)
    peaks, _ = law_free_turning_points(prepared, warn_levels=False)
    swings = dissipation_amplitudes(peaks)
    try:
        measured = turning_point_dissipation(peaks, swings, PhysicalScale())
    except ValueError:
        measured = None
    if not measured or not measured.get("amplitude"):
        return {}
    mean = np.asarray(measured["mean"], dtype=float)
    sd = np.asarray(measured["sd"], dtype=float)
    ok = np.isfinite(mean) & np.isfinite(sd) & (sd > 0)
    if ok.sum() < 3:
        return {}
    amp = np.asarray(measured["amplitude"], dtype=float)[ok]
    reference = float(abs(prepared.data.y0))
    chi2 = {law: turning_point_misfit(law, amp, mean[ok], sd[ok], reference) for law in laws}
    known = [v for v in chi2.values() if v is not None and np.isfinite(v)]
    if not known:
        return {}
    limit = factor * (min(known) + int(ok.sum()))
    return {
        law: {"chi2": value, "limit": limit, "screened": value is not None and value > limit}
        for law, value in chi2.items()
    }
