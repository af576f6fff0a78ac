"""Reduction: a law whose extra terms the data put at zero is the law it nests.

At its optimum such a law's extra terms' amounts sit on their null (ζ, γ, ζ_α at 0: the
lower bound of their support, :func:`bayestribo.inference.start.refine`), and the
parameters that only shape those terms (a power drag's exponent α, μ_s/μ_k without μ_k)
are left to their prior. Sampling such a posterior judges convergence on parameters the
data say nothing of, and runs to the step ceiling: ``coulomb+power`` on a record of
Coulomb friction alone (ζ_α → 0 leaves α free, and α → 0 makes the drag a second Coulomb
friction) ran all its steps without converging: a third of the time ``law="auto"`` took
there (``benchmarks/auto_speed.py``). The laws are fitted smallest first, and a law
*reduces* to the largest law it nests that is fitted and converged already when its
optimum loses at most :data:`REDUCTION_LOSS` (half a unit) of log posterior density with
the extra terms' amounts put on their null (the others where they are, or at the nested
law's optimum). It is then not sampled and not compared by PSIS-LOO (the nested law,
simpler and of the same optimum, stands for it in the verdict and in the ΔE(A) averaged
over the laws as good as the verdict): its table row says ``reduces_to``,
``terms_at_zero``, ``sampled`` False and ``converged`` None (not "converged"), with the
misfit checks at its optimum, and the comparison's text names it. The law-free fit never
reduces.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.choice import complexity, law_of
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.types import PreparedRun, Sampled

__all__ = ["REDUCTION_LOSS", "nested_start", "nested_starts", "reduction", "reduction_among"]

#: Log posterior density a law's optimum may lose with its extra terms at zero and
#: still reduce to the law it nests (module notes): half a unit, the reach of a bound
#: in :func:`bayestribo.inference.start.refine` and of the μ_s/μ_k interval.
REDUCTION_LOSS = 0.5


def _amount(term: Any, values: Mapping[str, float], reference: float) -> Any:
    """The parameter of ``term`` whose null on a bound of its support stops the term
    (its ΔE(A) 0 at every amplitude, the others at ``values``): a drag's coefficient,
    μ_k; None when there is none (a friction that may take either sign)."""
    amplitudes = reference * np.array([1e-3, 0.1, 0.5, 1.0])
    for p in term.parameters:
        if p.null not in (p.low, p.high):
            continue
        at = {q.name: np.array([values[q.name]]) for q in term.parameters}
        at[p.name] = np.array([p.null])
        energy = np.asarray(term.dissipation(amplitudes, at, reference), dtype=float)
        if np.all(energy == 0.0):
            return p
    return None


def reduction(
    law: str,
    posterior: Posterior,
    theta: NDArray,
    fitted: Mapping[str, Sampled],
    optima: Mapping[str, Mapping[str, float]],
) -> tuple[str, list[str]] | None:
    """The law compared that ``law`` reduces to at its optimum ``theta``, and the terms
    at zero; None when it reduces to none (module notes).

    A law reduces to a law it nests, fitted and converged in this comparison, when its
    extra terms at zero lose at most :data:`REDUCTION_LOSS` of log posterior density
    from ``theta``: each extra term's amount (the parameter whose null, a bound of its
    support, stops the term) put on its null, the other coordinates at ``theta`` or at
    the nested law's optimum, whichever is higher. The largest such law is the one. The
    law-free fit never reduces (its answer is its ΔE(A), not a mechanism)."""
    converged = [other for other, sampled in fitted.items() if sampled.run.converged]
    return reduction_among(law, posterior, theta, converged, optima)


def reduction_among(
    law: str,
    posterior: Posterior,
    theta: NDArray,
    laws: Iterable[str],
    optima: Mapping[str, Mapping[str, float]],
) -> tuple[str, list[str]] | None:
    """The largest of ``laws`` that ``law`` nests and reduces to at its optimum
    ``theta``, and the terms at zero; None when it reduces to none.

    The rule of :func:`reduction`, over any laws whose optimum is in ``optima`` (by
    coordinate) rather than over the laws sampled and converged: the screening takes
    the laws screened out (:func:`bayestribo.inference.screening.screened_by_reduction`).

    Parameters
    ----------
    law : str
        The law judged.
    posterior : Posterior
        Its posterior (log density in units of log probability).
    theta : ndarray
        Its optimum, in the coordinates of ``posterior.names``.
    laws : iterable of str
        The laws it may reduce to.
    optima : mapping
        Law -> its optimum by coordinate name; a law not in it is not reduced to.

    Returns
    -------
    (str, list of str) or None
        The law reduced to and the names of the terms at zero.
    """
    the_law = posterior.law
    if the_law.name == law_of("free").name:
        return None
    names = list(posterior.names)
    values = dict(zip(names, np.asarray(theta, dtype=float).tolist(), strict=True))
    reference = float(posterior.likelihood.reference_amplitude)
    best = float(posterior(np.asarray(theta, dtype=float)[None])[0])
    nested = [
        other
        for other in dict.fromkeys(laws)
        if other in optima and law_of(other).name != the_law.name and the_law.nests(law_of(other))
    ]
    for other in sorted(nested, key=complexity, reverse=True):
        extra = [t for t in the_law.terms if t.name not in law_of(other).term_names]
        if any(p.name not in names for t in extra for p in t.parameters):
            continue  # a held parameter: not the optimiser's answer
        amounts = [_amount(t, values, reference) for t in extra]
        if any(a is None for a in amounts):
            continue
        at_zero = np.array(theta, dtype=float)
        for a in amounts:
            at_zero[names.index(a.name)] = a.null
        embedded = at_zero.copy()
        for name, value in optima[other].items():
            if name in names:
                embedded[names.index(name)] = value
        lp = posterior(np.vstack([at_zero, embedded]))
        if np.isfinite(best) and np.max(lp) >= best - REDUCTION_LOSS:
            return other, [t.name for t in extra]
    return None


def nested_start(
    law: str, prepared: PreparedRun, optima: Mapping[str, dict[str, float]]
) -> dict[str, float] | None:
    """The optimum of the largest law already fitted that this one nests, with the extra
    parameters at small values: a weak extra term is otherwise hard to find."""
    the_law = law_of(law)
    nested = [
        other
        for other in optima
        if other != law and the_law.nests(law_of(other)) and len(law_of(other).terms) > 0
    ]
    if not nested:
        return None
    other = max(nested, key=lambda o: len(law_of(o).parameters))
    return _embedded(law, optima[other], abs(prepared.data.y0))


def nested_starts(
    law: str, prepared: PreparedRun, optima: Mapping[str, dict[str, float]]
) -> list[dict[str, float]] | None:
    """The optima of every law with one term fewer that this one nests, each with the
    missing term's parameters at small values (as :func:`nested_start`), in the order
    of its terms; None for a law of one term, or where one of those laws has no
    optimum in ``optima``.

    A law's optimum lies where one of its terms takes the loss its nested laws leave
    (the arms of ``coulomb+power``'s L are its two one-term laws), so the least squares
    from these starts reach it: on the two bundled runs and the 17 real recordings of
    the speed goals (7 laws of two or three terms each) they found an optimum as good as
    the first guesses' multi-start (within 0.01 of log density) on 128 of the 133, a
    better one on 5 (by 0.01 to 3.9), in 0.38 of its CPU time over all (the module notes
    of :mod:`bayestribo.inference.comparison`, Optima).
    """
    the_law = law_of(law)
    names = the_law.term_names
    if len(names) < 2:
        return None
    starts = []
    for dropped in names:
        key = next(
            (other for other in optima if set(law_of(other).term_names) == set(names) - {dropped}),
            None,
        )
        if key is None:
            return None
        starts.append(_embedded(law, optima[key], abs(prepared.data.y0)))
    return starts


def _embedded(law: str, optimum: Mapping[str, float], amplitude: float) -> dict[str, float]:
    """A nested law's ``optimum`` (by coordinate) as a start of ``law``: its parameters
    that the nested law lacks at small values (μ_k at 1e-6 of the amplitude, μ_s/μ_k at
    1.2, α at 1, the others 1e-6 of their range above their null)."""
    start = dict(optimum)
    for p in law_of(law).parameters:
        if p.name not in start:
            if p.name == "mu_s_ratio":
                start[p.name] = 1.2
            elif p.name == "mu_k":
                start[p.name] = 1e-6 * amplitude
            elif p.name == "alpha":
                start[p.name] = 1.0
            else:
                start[p.name] = p.null + 1e-6 * (1.0 if p.high == np.inf else p.high - p.null)
    return start
