"""The verdict of a comparison of dissipation laws: which law is best, which are as good
as it, and the simplest adequate one among those.

A law is *as good* as the best when its difference of expected log predictive density
is below :data:`SMALL_ELPD_DIFFERENCE` (4) or below two standard errors of the difference
(Sivula, Magnusson & Vehtari 2020: smaller differences are not reliably resolved). The
verdict is the simplest adequate law among those as good as the best: fewest terms,
then fewest parameters, then the order of the laws compared, not the PSIS-LOO rank,
which is noise between laws this close (:mod:`bayestribo.inference.comparison`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from bayestribo.errors import BayestriboError
from bayestribo.model.laws import Law, get_law

__all__ = [
    "LAWS",
    "SMALL_ELPD_DIFFERENCE",
    "choose_law",
    "complexity",
    "law_of",
    "loo_standing",
    "tie_key",
    "verdict_of",
]

#: The original comparison's names and the laws they stand for.
LAWS: Mapping[str, str] = {"viscous": "viscous", "coulomb": "coulomb", "both": "viscous+coulomb"}

#: elpd difference below which two laws are not told apart.
SMALL_ELPD_DIFFERENCE = 4.0


def law_of(name: str | Law) -> Law:
    """The law of a comparison entry (the original names included)."""
    if isinstance(name, str) and name in LAWS:
        return get_law(LAWS[name])
    try:
        return get_law(name)
    except ValueError as exc:
        raise BayestriboError(f"laws: {exc}") from None


def tie_key(law: str, rank: Sequence[str]) -> tuple[int, int, int]:
    """The verdict's tie-break: fewest terms, then fewest parameters, then the order of
    the laws compared (``rank``)."""
    return (*complexity(law), rank.index(law) if law in rank else len(rank))


def complexity(law: str) -> tuple[int, int]:
    """Fewest terms first, then fewest parameters."""
    the_law = law_of(law)
    return len(the_law.terms), len(the_law.parameters)


def verdict_of(
    laws: Sequence[str], table: dict[str, dict[str, Any]], frame: Mapping[str, Any]
) -> tuple[str, list[str], str, bool]:
    """Best law, the laws as good as the best, the simplest adequate of those, and
    whether it is adequate (``frame``: the laws' PSIS-LOO rows, best first,
    :func:`bayestribo.inference.loo.loo_frame`)."""
    differences = {law: (table[law]["elpd_diff"], table[law]["dse"]) for law in laws}
    return choose_law(laws, next(iter(frame)), differences, table)


def choose_law(
    laws: Sequence[str],
    best: str,
    differences: Mapping[str, tuple[float, float]],
    table: Mapping[str, Mapping[str, Any]],
) -> tuple[str, list[str], str, bool]:
    """:func:`verdict_of` from each law's elpd difference from the best and its sd."""
    as_good = [
        law
        for law in laws
        if law == best
        or differences[law][0] < max(SMALL_ELPD_DIFFERENCE, 2.0 * differences[law][1])
    ]
    # ties go to the simplest, then to the order compared, not to the PSIS-LOO rank:
    # laws this close are ranked by noise (the seed chose between two misfitting laws
    # of HarmOsc1's second half, benchmarks/results/real.json)
    order = {law: i for i, law in enumerate(laws)}

    def simplest(candidates: list[str]) -> str:
        return min(candidates, key=lambda law: (*complexity(law), order[law]))

    adequate = [law for law in as_good if table[law]["adequate"] and table[law]["converged"]]
    if not adequate:
        converged = [law for law in as_good if table[law]["converged"]]
        return best, as_good, simplest(converged) if converged else best, False
    return best, as_good, simplest(adequate), True


def loo_standing(loos: Mapping[str, Any]) -> tuple[str, dict[str, tuple[float, float]]]:
    """The best of the laws sampled so far by PSIS-LOO, and each law's difference from
    it with its sd (as :func:`arviz.compare` computes them)."""
    elpd = {law: float(loo["elpd_loo"]) for law, loo in loos.items()}
    best = max(elpd, key=elpd.__getitem__)
    top = np.asarray(loos[best]["loo_i"], dtype=float)
    out = {}
    for law, loo in loos.items():
        d = top - np.asarray(loo["loo_i"], dtype=float)
        out[law] = (elpd[best] - elpd[law], float(np.sqrt(d.size * np.var(d))))
    return best, out
