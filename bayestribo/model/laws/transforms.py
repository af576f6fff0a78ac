r"""Sampling transforms: coordinates in which a law's posterior is sampled.

Some laws hold terms whose parameters trade against each other along a curved ridge
of the posterior: Coulomb friction beside a power-law drag |v|^α makes an L (either
the drag is ~0 and α free, or α ~ 0 and the drag a friction that shares the loss with
μ_k), which an ensemble sampler crosses in thousands of steps. In other coordinates
the same posterior is a near-rectangle. A *sampling transform* declares them: a
smooth bijection u ↦ θ from its sampling coordinates to some of the law's parameters
(the others are sampled as they are), with the log of its Jacobian determinant, so
that the density sampled in u is the posterior carried through the change of
variables,

.. math::

    p_u(u) = p_θ(θ(u))\,\left|\det \frac{∂θ}{∂u}\right|,

the law's own prior included. The draws are mapped back to θ: what a fit reports
is in the law's own parameters, of the same posterior.

A transform belongs to a set of terms (:func:`register_transform`); a law that holds
them, with their parameters all sampled, is sampled in its coordinates
(:func:`transform_for`). One protocol, one registry: the sampler knows no law.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol, runtime_checkable

from numpy.typing import NDArray

__all__ = [
    "TRANSFORMS",
    "SamplingTransform",
    "TransformFactory",
    "register_transform",
    "transform_for",
]


@runtime_checkable
class SamplingTransform(Protocol):
    """A bijection from sampling coordinates u to some of a law's parameters θ.

    Attributes
    ----------
    law_names : tuple of str
        The law's parameters it replaces, in the order of the columns of θ.
    names : tuple of str
        Its sampling coordinates, as many, in the order of the columns of u (names no
        law parameter takes).
    """

    law_names: tuple[str, ...]
    names: tuple[str, ...]

    def to_law(self, u: NDArray) -> NDArray:
        """θ of rows ``u`` (n, k) -> (n, k); anywhere in R^k (a θ outside the law's
        prior has density 0 there)."""
        ...

    def from_law(self, theta: NDArray) -> NDArray:
        """u of rows ``theta`` (n, k) inside the prior's support -> (n, k), finite
        (the inverse of :meth:`to_law`; a θ on a bound where u is infinite is moved
        inside by a negligible amount)."""
        ...

    def log_jacobian(self, u: NDArray) -> NDArray:
        """log |det ∂θ/∂u| of rows ``u`` (n, k) -> (n,)."""
        ...


#: ``factory(reference, lowest, ended) -> SamplingTransform``: a transform for one
#: record, from the reference amplitude of the law's parameters, the smallest amplitude
#: of the record (both dimensionless, lowest <= reference) and whether the record
#: holds the motion's end (its last turning point stuck, or decayed into the noise).
TransformFactory = Callable[[float, float, bool], SamplingTransform]

#: The registered transforms, by the set of terms they belong to.
TRANSFORMS: dict[frozenset[str], TransformFactory] = {}


def register_transform(terms: Sequence[str], factory: TransformFactory) -> TransformFactory:
    """Register the sampling transform of a set of terms.

    Parameters
    ----------
    terms : sequence of str
        The terms whose parameters it replaces (a law with all of them is sampled in
        its coordinates).
    factory : callable
        ``factory(reference, lowest, ended) -> SamplingTransform``.

    Returns
    -------
    callable
        ``factory``.

    Raises
    ------
    ValueError
        If these terms already have a transform.
    """
    key = frozenset(terms)
    if key in TRANSFORMS:
        raise ValueError(f"terms {sorted(key)} already have a sampling transform")
    TRANSFORMS[key] = factory
    return factory


def transform_for(
    term_names: Sequence[str],
    sampled: Sequence[str],
    reference: float,
    lowest: float,
    ended: bool = True,
) -> SamplingTransform | None:
    """The sampling transform of a law, or None where it has none.

    Parameters
    ----------
    term_names : sequence of str
        The law's terms.
    sampled : sequence of str
        The names of the sampled coordinates (a transform applies only where every
        parameter it replaces is sampled, none fixed).
    reference, lowest : float
        The reference amplitude of the law's parameters and the record's smallest
        amplitude (dimensionless).
    ended : bool
        Whether the record holds the end of the motion.

    Returns
    -------
    SamplingTransform or None
        The first registered transform whose terms the law holds and whose
        parameters are all sampled.
    """
    have = set(term_names)
    for terms, factory in TRANSFORMS.items():
        if terms <= have:
            transform = factory(float(reference), float(lowest), bool(ended))
            if set(transform.law_names) <= set(sampled):
                return transform
    return None
