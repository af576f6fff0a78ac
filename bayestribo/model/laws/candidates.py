"""The laws ``law="auto"`` compares, built from the registry of terms by one rule.

The rule (:func:`candidate_laws`), over the registered terms that are compared
(:attr:`~bayestribo.model.laws.base.Term.compared`, True unless a term says otherwise):

1. every term alone;
2. every pair of terms (a drag with a friction, two drags, two frictions);
3. the paper's law (:data:`~bayestribo.model.laws.law.DEFAULT_LAW`, viscous damping and
   Coulomb friction, Rigaud et al. 2010, Eq. 7) with one more term;

leaving out every law that holds a term and a term it *overlaps*
(:attr:`~bayestribo.model.laws.base.Term.overlaps`, declared by either of the two: a
term whose ΔE(A) the other makes too, at a value inside its prior or with the same
power of the amplitude, so that the law trades one for the other along a ridge of its
posterior, slow to sample and saying nothing either alone does not).

The laws come in order: fewest terms first, then by the registration order of their
terms (the order that settles a tie between laws of the same size in
:mod:`bayestribo.inference.comparison`). With the built-in terms (``cubic`` is the
law-free fit's building block, not compared; ``power`` overlaps ``viscous``,
``quadratic`` and ``hysteretic``; ``hysteretic`` overlaps ``viscous``) that is twelve
laws::

    viscous, coulomb, quadratic, power, hysteretic,
    viscous+coulomb, viscous+quadratic, coulomb+quadratic, coulomb+power,
    coulomb+hysteretic, quadratic+hysteretic,
    viscous+coulomb+quadratic

A term a lab registers (:func:`~bayestribo.model.laws.base.register_term`) is a
candidate alone, with each other term and with the paper's law, with no edit
elsewhere; its registration's ``overlaps`` keeps it out of the sums it duplicates.
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import combinations

from bayestribo.model.laws.base import TERMS, Term
from bayestribo.model.laws.law import DEFAULT_LAW

__all__ = ["CANDIDATE_RULE", "candidate_laws", "overlapping"]

#: The rule in one sentence, for help texts and the comparison's record.
CANDIDATE_RULE = (
    "every registered term alone, every pair of terms, and the paper's law "
    f"({DEFAULT_LAW}) with one more term; no law holding a term and one it overlaps"
)


def overlapping(a: Term, b: Term) -> bool:
    """True when either term declares the other in its ``overlaps``."""
    return b.name in a.overlaps or a.name in b.overlaps


def candidate_laws(terms: Mapping[str, Term] | None = None) -> tuple[str, ...]:
    """The laws ``law="auto"`` compares, by the module's rule.

    Parameters
    ----------
    terms : mapping of str to Term, optional
        Terms by name, in registration order; default the registry
        :data:`~bayestribo.model.laws.base.TERMS` as it is now (a term registered
        later is a candidate from then on).

    Returns
    -------
    tuple of str
        Law names (terms joined with ``+`` in registration order), fewest terms
        first, then in the registration order of their terms.
    """
    registry = TERMS if terms is None else terms
    order = {name: i for i, name in enumerate(registry)}
    compared = [t for t in registry.values() if t.compared]
    laws: set[tuple[str, ...]] = set()

    def add(members: tuple[Term, ...]) -> None:
        if any(overlapping(a, b) for a, b in combinations(members, 2)):
            return
        laws.add(tuple(sorted({t.name for t in members}, key=order.__getitem__)))

    for term in compared:
        add((term,))
    for pair in combinations(compared, 2):
        add(pair)
    paper = [registry.get(name) for name in DEFAULT_LAW.split("+")]
    if all(t is not None and t.compared for t in paper):
        base = tuple(t for t in paper if t is not None)
        for term in compared:
            if term not in base:
                add((*base, term))
    ranked = sorted(laws, key=lambda names: (len(names), [order[n] for n in names]))
    return tuple("+".join(names) for names in ranked)
