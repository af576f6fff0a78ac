"""The laws ``law="auto"`` compares come from the registry by one rule."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from bayestribo.inference.comparison import auto_laws
from bayestribo.model.laws import TERMS, Parameter, Term, register_term
from bayestribo.model.laws.candidates import candidate_laws, overlapping

#: What the rule gives with the built-in terms (the module notes list it).
BUILT_IN = (
    "viscous",
    "coulomb",
    "quadratic",
    "power",
    "hysteretic",
    "viscous+coulomb",
    "viscous+quadratic",
    "coulomb+quadratic",
    "coulomb+power",
    "coulomb+hysteretic",
    "quadratic+hysteretic",
    "viscous+coulomb+quadratic",
)
#: The hand list law="auto" compared before the rule.
HAND_LIST = (
    "viscous",
    "coulomb",
    "hysteretic",
    "viscous+coulomb",
    "viscous+quadratic",
    "viscous+coulomb+quadratic",
    "coulomb+hysteretic",
    "coulomb+power",
)


@numba.njit(cache=True)
def _force(w: float, c: np.ndarray) -> float:
    return c[0] * w**4


def _term(name: str, kind: str = "drag", overlaps: tuple[str, ...] = ()) -> Term:
    """A lab's term, as a module of its own would register it."""
    param = Parameter(f"{name}_c", "c", "-", 0.0, 1.0, "a coefficient", lambda a: {})
    return Term(
        name=name,
        kind=kind,
        parameters=(param,),
        n_coefficients=1,
        force=_force,
        coefficients=lambda values, reference: [np.asarray(values[param.name], dtype=float)],
        dissipation=lambda a, values, reference: np.zeros_like(np.asarray(a, dtype=float)),
        physical=lambda values, reference, scale: {},
        description="a test drag",
        overlaps=overlaps,
    )


@pytest.fixture
def lab_term():
    """A term registered for the test and taken out of the registry after it."""
    term = register_term(_term("quartic_test", overlaps=("quadratic",)))
    try:
        yield term
    finally:
        TERMS.remove(term.name)


def test_the_built_in_terms_make_the_documented_candidates():
    assert candidate_laws() == BUILT_IN
    assert auto_laws() == BUILT_IN
    # every law of the old hand list is still compared, and quadratic drag with
    # Coulomb friction now is (a quadratic + Coulomb record came back coulomb+power)
    assert set(HAND_LIST) <= set(BUILT_IN)
    assert "coulomb+quadratic" in BUILT_IN


def test_overlapping_terms_never_share_a_law():
    for law in candidate_laws():
        terms = [TERMS[name] for name in law.split("+")]
        assert not any(overlapping(a, b) for i, a in enumerate(terms) for b in terms[i + 1 :])
    assert "viscous+power" not in BUILT_IN and "viscous+hysteretic" not in BUILT_IN
    assert not any("cubic" in law.split("+") for law in BUILT_IN)  # compared=False


def test_a_registered_term_is_a_candidate_with_no_edit_elsewhere(lab_term):
    laws = auto_laws()
    assert "quartic_test" in laws
    assert {"viscous+quartic_test", "coulomb+quartic_test", "hysteretic+quartic_test"} <= set(laws)
    assert "viscous+coulomb+quartic_test" in laws
    # its registration keeps it out of the sums it duplicates
    assert "quadratic+quartic_test" not in laws
    assert laws.index("quartic_test") < laws.index("viscous+coulomb")  # fewest terms first


def test_an_overlap_declared_by_either_term_leaves_the_pair_out():
    terms = {
        "viscous": TERMS["viscous"],
        "coulomb": TERMS["coulomb"],
        "a": _term("a", overlaps=("viscous",)),
        "b": _term("b", kind="friction"),
    }
    terms["c"] = _term("c")
    terms["b_over"] = _term("b_over", kind="friction", overlaps=("c",))
    laws = candidate_laws(terms)
    assert "viscous+a" not in laws and "viscous+coulomb+a" not in laws
    assert "c+b_over" not in laws
    assert {"a", "b", "viscous+b", "coulomb+a", "viscous+coulomb+b"} <= set(laws)
    assert all(len(law.split("+")) <= 3 for law in laws)


def test_a_term_may_not_overlap_itself():
    with pytest.raises(ValueError, match="overlap itself"):
        _term("selfish", overlaps=("selfish",))
