"""A term the record does not see: its other parameters are not identified.

A term's first parameter scales its force (ζ_α of the power-law drag, μ_k of Coulomb
friction); at its ``null`` the term exerts no force, and the term's other parameters
(α, μ_s/μ_k) have no effect on the motion. When the draws of the first parameter
reach its null, the posterior of the others is a ridge along their whole prior, not a
mode: the sampler crosses it slowly (HarmOsc3 under ``coulomb+power``: ζ_α at 0 with α
anywhere in 0-3, and at α = 0 a drag that is a constant force trading with μ_k; τ ~
1300 steps). :func:`unidentified_reasons` says so, naming the term, the parameters
and the law without that term, so that a fit that does not converge there says why
instead of only which criterion failed.

The rule: the first parameter *reaches its null* when the lower end of its central 95 %
interval is within :data:`REACH` of that interval's width from the null (the draws
pile against it), and a *term's other parameter* is named when it is sampled.

A record of few turning points identifies no more parameters than it has increments.
Where the sampled parameters are at least as many as the increments (a sticking
record of 4-6 turning points under ``coulomb+power``: five parameters on five
increments, χ² at the optimum ~1e-5), the increments leave the parameters free to
trade along a ridge whatever the force of each term (ζ_α well clear of 0 there):
:func:`unidentified_reasons` says so when given the number of increments.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws.law import Law

__all__ = ["REACH", "too_few_increments", "unidentified_reasons"]

#: The lower end of the central 95 % interval within this fraction of the interval's
#: width from the null: the draws reach the null.
REACH = 0.05


def too_few_increments(names: Sequence[str], n_increments: int, law_name: str) -> str | None:
    """Why a record of ``n_increments`` increments does not identify a law whose sampled
    parameters ``names`` are at least as many (None when they are fewer).

    Parameters
    ----------
    names : sequence of str
        The law's sampled parameters (its posterior's ``names``, y₀ included).
    n_increments : int
        The record's number of Π increments (the data the parameters are fitted to).
    law_name : str
        The law's name, for the reason.

    Returns
    -------
    str or None

    Raises
    ------
    ValueError
        If ``n_increments`` is not a positive integer.
    """
    if isinstance(n_increments, bool) or not isinstance(n_increments, (int, np.integer)):
        raise ValueError(f"n_increments: expected a positive integer, got {n_increments!r}")
    if n_increments < 1:
        raise ValueError(f"n_increments: expected a positive integer, got {n_increments}")
    names = list(names)
    if len(names) < n_increments:
        return None
    return (
        f"the law's {len(names)} sampled parameters ({', '.join(names)}) are at least as "
        f"many as the record's {int(n_increments)} increments: the increments leave them "
        f"free to trade along a ridge, and the record does not identify law '{law_name}'"
    )


def unidentified_reasons(
    draws: NDArray, names: Sequence[str], law: Law, n_increments: int | None = None
) -> list[str]:
    """Reasons naming the parameters a record does not identify because their term's
    force reaches zero in the draws.

    Parameters
    ----------
    draws : ndarray
        Posterior draws in sampling coordinates, shape (n, len(names)).
    names : sequence of str
        The sampled parameters' names (the columns of ``draws``).
    law : Law
        The fitted law (:class:`~bayestribo.model.laws.Law`).
    n_increments : int, optional
        The record's number of Π increments (the data the parameters are fitted to);
        None (the default) leaves out the count of parameters against increments.

    Returns
    -------
    list of str
        One reason per term whose first parameter reaches its null while another of
        its parameters is sampled, and one when the sampled parameters are at least
        as many as ``n_increments`` (empty when there is none).

    Raises
    ------
    ValueError
        If ``n_increments`` is given and is not a positive integer.
    """
    draws = np.atleast_2d(np.asarray(draws, dtype=float))
    names = list(names)
    terms = list(law.terms)
    reasons: list[str] = []
    if n_increments is not None:
        outnumbered = too_few_increments(names, n_increments, law.name)
        if outnumbered is not None:
            reasons.append(outnumbered)
    for term in terms:
        if not term.parameters or term.parameters[0].name not in names:
            continue
        scale = term.parameters[0]
        others = [p for p in term.parameters[1:] if p.name in names]
        if not others:
            continue
        x = draws[:, names.index(scale.name)]
        x = x[np.isfinite(x)]
        if x.size < 2:
            continue
        null = float(scale.null if scale.null is not None else scale.low)
        low, high = (float(v) for v in np.quantile(x, [0.025, 0.975]))
        if not high > null or low - null > REACH * (high - null):
            continue
        spread = []
        for p in others:
            y = draws[:, names.index(p.name)]
            y = y[np.isfinite(y)]
            a, b = (float(v) for v in np.quantile(y, [0.025, 0.975]))
            spread.append(f"{p.symbol} ({p.name}) {a:.3g} to {b:.3g}")
        rest = [t.name for t in terms if t is not term]
        without = (
            f"; the {term.name} term can be left out: fit law='{'+'.join(rest)}' "
            f"(--law {'+'.join(rest)})"
            if rest
            else ""
        )
        symbols = ", ".join(p.symbol for p in others)
        reasons.append(
            f"{scale.symbol} ({scale.name}) reaches {null:g}, where the {term.name} term "
            f"exerts no force (95 % of the draws {low:.3g} to {high:.3g}): there "
            f"{symbols} {'has' if len(others) == 1 else 'have'} no effect, so this record "
            f"does not identify {symbols} (95 % of the draws: {', '.join(spread)}) and the "
            f"walkers cross a ridge, not a mode{without}"
        )
    return reasons
