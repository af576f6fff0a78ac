r"""A quadratic surrogate of the model Π for laws without a closed form, checked.

The posterior of a law without a closed form needs its compiled half-cycle integrator
(:mod:`bayestribo.model.laws.integrator`) for every walker at every step: some 100 µs a
parameter set against 1.6 µs for the closed form, and the sampler asks for tens of
thousands. The data pin the parameters down to a small region, though (relative
widths of 1e-4 to 1e-2), over which Π is a smooth function of them. Inside it

.. math::

    Π(θ) ≈ Π_c + \sum_a g_a u_a + \sum_{a \le b} h_{ab} u_a u_b,
    \qquad u_a = (θ_a - c_a) / s_a,

with ``c`` the centre (the maximum a posteriori), ``s`` the scales (twice the Laplace
standard deviations) and one (m,) coefficient row per monomial, fitted by least
squares to the exact Π at the nodes of a central composite design: the centre, each
coordinate alone at two levels, and every corner of the levels (``1 + 2p + 2^p``
evaluations, p the coordinates Π depends on: the law's sampled parameters and y0).
The corners in all four quadrants of each pair keep the cubic terms out of the cross
terms; the error left is of third order in ``u``.

Where μ_s/μ_k is sampled, Π is piecewise in it (:class:`QuadraticPi`) and the edges of
the pieces move with the other coordinates: each node's Π of a piece is computed at a
ratio inside that piece at that node, and each piece's quadratic is fitted to the
nodes where the piece meets the prior's support (a motion that stops one turning
point later at one node is another piece's, and mixing the two misfits the quadratic
by some 0.03 noise sd, which a misfitting law's large residuals turn into
importance weights far from 1).

The surrogate is never trusted on this argument alone. :func:`check` evaluates the
exact log posterior at a seeded sample of the surrogate posterior's draws and
computes the importance weights w = p(θ)/p̃(θ): by Cauchy-Schwarz, any posterior mean
under the exact posterior differs from the surrogate's by at most
``cv(w) × sd`` (cv the coefficient of variation of the weights, sd the posterior
standard deviation of the quantity). The fit keeps the surrogate's draws only when
cv(w) is below :data:`MAX_WEIGHT_CV`; otherwise it builds the surrogate again, up to
:data:`ATTEMPTS` times, and then samples the exact posterior
(:func:`bayestribo.inference.chains.sample`); a surrogate built again that misses the
check by a little has its draws resampled to the exact posterior by their importance
weights instead (:mod:`bayestribo.inference.correction`; once one has come near that
reach, up to :data:`~bayestribo.inference.correction.CORRECTING_ATTEMPTS` surrogates
are built before the exact posterior is sampled). The Laplace scales about the maximum a
posteriori describe a posterior that is nearly Gaussian; one that is not (a
parameter whose optimum is on its prior's bound, with its mass a few tenths of the
prior's width inside, as α of ``coulomb+power`` at 3 on the AppStat records: a
Laplace sd of 0.02 against a posterior sd of 0.3) is covered poorly by the nodes of
the design, and the check fails. The surrogate is then fitted again by least squares
to the exact Π at :data:`REFIT_DRAWS` draws of the failed surrogate's posterior
(:func:`regressed_pi`; piecewise in μ_s/μ_k as the design's), which lie where the
exact posterior's mass is to within the failed surrogate's error: the quadratic is
fitted where it is used, and its centre follows the posterior's mass where the
optimiser stopped short of the optimum of a law that misfits. Where the draws do not
determine it, it is built again from a design about the checked draw of highest
exact density with the surrogate posterior's spread.

Where the law cannot move on one side of a coordinate inside its prior's support (η
of ``quadratic+hysteretic`` below zero, a friction ηA < 0), the nodes on that side
have no Π and the design cannot be fitted: the surrogate's uniform prior of that
coordinate then ends at the edge of the law's domain, where the exact posterior ends
too (its likelihood is zero beyond), and the design takes the coordinate's other side.

Where the posterior depends on Π discontinuously (a law with static friction whose
motion ends inside the record: one turning point more or less before the pin sticks),
the quadratic cannot follow, the check fails and the exact posterior is sampled.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.likelihood import Params, PiLikelihood
from bayestribo.inference.piece_pi import TOLERANCE, longest_motion_pi, piece_rows, stop_times
from bayestribo.inference.priors import PriorSet, Uniform

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior
    from bayestribo.model.laws import Law

__all__ = [
    "ATTEMPTS",
    "MAX_WEIGHT_CV",
    "REFIT_DRAWS",
    "CoefficientLayout",
    "ForceColumns",
    "QuadraticPi",
    "SurrogateCheck",
    "SurrogateLikelihood",
    "check",
    "quadratic_pi",
    "regressed_pi",
    "regressed_posterior",
    "stop_ratios",
    "surrogate_posterior",
]

#: Whether the coordinates' values (by name) are inside the priors' support.
Inside = Callable[[Mapping[str, float]], bool]
#: Largest coefficient of variation of the importance weights at which the surrogate
#: posterior's draws are kept: posterior means within 0.05 posterior sd of the exact.
MAX_WEIGHT_CV = 0.05
#: Draws of the surrogate posterior at which the exact log posterior is evaluated.
CHECK_DRAWS = 128
#: Surrogates built and checked before the exact posterior is sampled instead.
ATTEMPTS = 3
#: Draws of a failed surrogate's posterior at which the exact Π is evaluated to fit
#: the next surrogate by least squares (:func:`regressed_pi`): at least this many, and
#: at least four per coefficient of the quadratic.
REFIT_DRAWS = 128
#: Scales of the nodes of the fit, in Laplace standard deviations.
NODE_SCALE = 2.0
#: Smallest relative change of Π at a node (see :func:`quadratic_pi`).
MIN_CHANGE = 1e-7
#: Coordinates up to which the nodes hold every corner of the design (2^p of them).
_MAX_FACTORIAL = 6
#: Halvings of a node distance whose nodes fall outside the support on both sides.
_NARROWINGS = 20
#: Node distances tried per coordinate, in factors of 4 from the given scale.
_PROBES = 16
#: Coordinates of the sampled vector that never enter Π.
_NOT_IN_PI = ("log10_discrepancy", "log10_shape")
#: The static to kinetic friction ratio, on which Π depends piecewise.
_RATIO = "mu_s_ratio"


@dataclass(frozen=True)
class ForceColumns:
    """One compiled force of a law and the columns of its coefficients.

    Attributes
    ----------
    force : callable
        ``force(x, coefficients) -> float``, the term's compiled force
        (:attr:`bayestribo.model.laws.Term.force`).
    columns : slice
        Its coefficients' columns in a row of :meth:`bayestribo.model.laws.Law.
        coefficients`.
    """

    force: Callable[[float, NDArray], float]
    columns: slice


@dataclass(frozen=True)
class CoefficientLayout:
    """Which columns of a law's coefficient rows each of its compiled forces reads.

    :meth:`bayestribo.model.laws.Law.coefficients` gives the drags' coefficients, then
    the frictions', each term's in the law's order and as many as it declares
    (``n_coefficients``).

    Attributes
    ----------
    drags, frictions : tuple of ForceColumns
        The drag terms' and the friction terms' forces and columns.
    width : int
        The columns of a row.
    """

    drags: tuple[ForceColumns, ...]
    frictions: tuple[ForceColumns, ...]
    width: int

    @classmethod
    def of(cls, law: Law) -> CoefficientLayout:
        """The layout of ``law``'s coefficient rows."""
        slots: dict[str, list[ForceColumns]] = {"drag": [], "friction": []}
        start = 0
        for kind in ("drag", "friction"):
            for term in (t for t in law.terms if t.kind == kind):
                stop = start + int(term.n_coefficients)
                slots[kind].append(ForceColumns(term.force, slice(start, stop)))
                start = stop
        return cls(tuple(slots["drag"]), tuple(slots["friction"]), start)


@dataclass(frozen=True)
class QuadraticPi:
    """Π on the likelihood's grid as a quadratic in the coordinates it depends on,
    piecewise in μ_s/μ_k.

    Π depends on μ_s/μ_k only through the turning point at which the motion stops (the
    first whose spring force the static friction holds): it is constant between the
    ratios at which one more or one fewer half cycle is made, and jumps there. Each
    such piece has its own quadratic in the other coordinates.

    Attributes
    ----------
    names : tuple of str
        The coordinates (the law's sampled parameters but μ_s/μ_k, and ``y0``), p.
    centre, scale : ndarray
        Shape (p,): the expansion point ``c`` and the unit ``s`` of ``u = (θ - c)/s``.
    table : ndarray
        Shape (K R, m), R = 1 + p + p(p+1)/2: for each of the K pieces, Π_c, the linear
        rows g_a, then the quadratic rows h_ab for a <= b in row-major order.
    ratio : str or None
        The name of μ_s/μ_k when it is sampled (None: one piece).
    thresholds : ndarray
        Shape (K - 1, R): the ratios where the pieces meet, each a quadratic in ``u``
        (the same monomials; its first column is the value at the centre), increasing
        along the first axis: piece k where ``thresholds[k-1](u) <= ratio <
        thresholds[k](u)``. A threshold is ``|Y_n|/μ(|Y_n|)`` for a turning point Y_n
        of the motion, which moves with the other parameters.
    """

    names: tuple[str, ...]
    centre: NDArray
    scale: NDArray
    table: NDArray
    ratio: str | None = None
    thresholds: NDArray = field(default_factory=lambda: np.zeros((0, 1)))

    @property
    def n_coordinates(self) -> int:
        """p, the number of coordinates."""
        return len(self.names)

    @property
    def n_pieces(self) -> int:
        """K, the number of pieces in μ_s/μ_k."""
        return int(self.thresholds.shape[0]) + 1

    @property
    def rows_per_piece(self) -> int:
        """R, the monomials of one piece."""
        p = self.n_coordinates
        return 1 + p + p * (p + 1) // 2

    def piece_rows(self, piece: int) -> slice:
        """The rows of :attr:`table` holding piece ``piece``'s coefficients."""
        r = self.rows_per_piece
        return slice(piece * r, (piece + 1) * r)

    def monomials(self, u: NDArray) -> NDArray:
        """The monomials 1, u_a, u_a u_b (a <= b) of rows ``u`` (n, p), shape (n, R)."""
        u = np.atleast_2d(u)
        p = u.shape[1]
        cols = [np.ones(u.shape[0]), *(u[:, a] for a in range(p))]
        cols += [u[:, a] * u[:, b] for a in range(p) for b in range(a, p)]
        return np.column_stack(cols)

    def piece(self, ratio: NDArray, basis: NDArray) -> NDArray:
        """The piece of each value of μ_s/μ_k, (n,) int, given the monomials of the
        other coordinates (n, R)."""
        edges = basis @ self.thresholds.T  # (n, K - 1)
        return np.sum(edges <= np.ravel(ratio)[:, None], axis=1)

    def __call__(self, params: Params) -> NDArray:
        """Surrogate Π at the grid points for ``params`` (by name, each (n,)), (n, m)."""
        u = np.column_stack(
            [
                (np.ravel(np.asarray(params[name], dtype=float)) - c) / s
                for name, c, s in zip(self.names, self.centre, self.scale, strict=True)
            ]
        )
        basis = self.monomials(u)
        if self.ratio is None:
            return basis @ self.table[self.piece_rows(0)]
        pieces = self.piece(np.asarray(params[self.ratio], dtype=float), basis)
        out = np.empty((basis.shape[0], self.table.shape[1]))
        for k in np.unique(pieces):
            rows = pieces == k
            out[rows] = basis[rows] @ self.table[self.piece_rows(int(k))]
        return out


def _nodes(p: int, sides: NDArray) -> NDArray:
    """Nodes in u of a central composite design: the centre, each coordinate alone at
    its two levels (±1, or 1 and 2 on its allowed side), and every corner of the
    levels (a quadratic's cross terms from all four quadrants of each pair, which
    cancels the cubic terms' share that one corner per pair would leave in them); up
    to :data:`_MAX_FACTORIAL` coordinates, beyond that one corner per pair."""
    levels = np.where(
        sides[:, None] == 0, np.array([-1.0, 1.0]), sides[:, None] * np.array([1.0, 2.0])
    )
    rows = [np.zeros(p)]
    for a in range(p):
        for value in levels[a]:
            row = np.zeros(p)
            row[a] = value
            rows.append(row)
    if p <= _MAX_FACTORIAL:
        rows.extend(np.array(corner) for corner in itertools.product(*levels))
    else:
        for a in range(p):
            for b in range(a + 1, p):
                row = np.zeros(p)
                row[a], row[b] = levels[a, 1], levels[b, 1]
                rows.append(row)
    return np.array(rows)


def _fit(basis: NDArray, values: NDArray, valid: NDArray | None = None) -> NDArray | None:
    """Least-squares coefficients (R, m) of the monomials ``basis`` (n, R) to
    ``values`` (n, m) over the ``valid`` nodes (all by default); None when those do
    not determine every coefficient."""
    rows = np.ones(basis.shape[0], dtype=bool) if valid is None else np.asarray(valid)
    design = basis[rows]
    if design.shape[0] < design.shape[1] or np.linalg.matrix_rank(design) < design.shape[1]:
        return None
    coef, *_ = np.linalg.lstsq(design, values[rows], rcond=None)
    return coef


def _evaluate(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    theta: NDArray,
    fixed_params: Mapping[str, float],
) -> NDArray:
    """Exact Π at rows ``theta`` (n, p) of the coordinates ``names``, (n, m)."""
    n = theta.shape[0]
    params: dict[str, NDArray] = {k: np.full(n, float(v)) for k, v in fixed_params.items()}
    params.update({name: theta[:, a] for a, name in enumerate(names)})
    return PiLikelihood.model_pi(likelihood, params)


def _node_distances(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    c: NDArray,
    scale: NDArray,
    fixed_params: Mapping[str, float],
    inside: Inside,
) -> NDArray:
    """Each coordinate's node distance: ``scale``, raised where Π changes there by less
    than :data:`MIN_CHANGE` of Π(0) to the first of ``scale × 4^k`` where it does (the
    fit's differences then stand well above rounding: a Laplace scale of a
    parameter piled at a bound can be 1e-6 of its posterior width). The given scales
    are tried first, all in one evaluation; only the coordinates they fail are probed
    further."""
    p = len(names)
    base = np.where(np.isfinite(scale) & (scale > 0), scale, 1e-12 * np.maximum(np.abs(c), 1e-3))
    out = base.copy()
    pi0 = _evaluate(likelihood, names, c[None], fixed_params)[0]
    reference = max(float(np.max(np.abs(pi0))), 1e-300)

    def first_inside(a: int, step: float) -> NDArray | None:
        for sign in (1.0, -1.0):
            row = c.copy()
            row[a] += sign * 2.0 * step
            if inside(dict(zip(names, row, strict=True))):
                return row
        return None

    pending = list(range(p))
    for k in range(_PROBES):
        rows, owners = [], []
        for a in pending:
            row = first_inside(a, base[a] * 4.0**k)
            if row is not None:
                rows.append(row)
                owners.append(a)
        if not rows:
            break
        pi = _evaluate(likelihood, names, np.array(rows), fixed_params)
        change = np.max(np.abs(pi - pi0), axis=1) / reference
        for a, ch in zip(owners, change, strict=True):
            if ch >= MIN_CHANGE:
                out[a] = base[a] * 4.0**k
                pending.remove(a)
        if not pending:
            break
    return out


def stop_ratios(likelihood: PiLikelihood, values: Mapping[str, float]) -> NDArray:
    """``|Y_n|/μ(|Y_n|)`` at each turning point Y_n of one motion (with μ_s = μ_k, so
    that it runs longest): the motion stops at Y_n when μ_s/μ_k is at least this, and
    Π changes with μ_s/μ_k only where it crosses one of them. The stop ratios of
    :func:`turning_stops`.
    """
    return turning_stops(likelihood, values)[1]


def turning_stops(likelihood: PiLikelihood, values: Mapping[str, float]) -> tuple[NDArray, NDArray]:
    """The turning times τ_n of one motion (with μ_s = μ_k, so that it runs longest)
    and the stop ratios ``|Y_n|/μ(|Y_n|)`` of its turning points Y_n (:func:`stop_ratios`).

    Parameters
    ----------
    likelihood : PiLikelihood
        The likelihood (its law, initial velocity, record end and reference amplitude).
    values : mapping
        The law's parameters and ``y0`` by name (scalars).

    Returns
    -------
    times, ratios : ndarray
        One value per turning point, in their order (a ratio inf where the friction is
        zero). A motion whose friction terms are all off (their coefficients zero:
        μ_k = 0) never sticks: every ratio is inf, given for the turning points up to
        the record's end only.
    """
    law = likelihood.law
    data = likelihood.data
    reference = likelihood.reference_amplitude
    law_values = {n: float(values[n]) for n in law.parameter_names}
    if "mu_s_ratio" in law_values:
        law_values["mu_s_ratio"] = 1.0
    coef = law.coefficients({n: np.array([v]) for n, v in law_values.items()}, reference)[0]
    frictions = CoefficientLayout.of(law).frictions
    # the model's Π runs to the end of motion when the record holds it (past the
    # record's end, if the model moves longer), else to the record's end. A motion no
    # friction stops has no stop ratio to find past the record: to its end of motion
    # its drag alone takes up to 100,000 half cycles (a viscous+coulomb+quadratic start
    # at μ_k = 0 on a sticking record, 1.2 s a scan of μ_s/μ_k)
    frictionless = not any(np.any(coef[f.columns] != 0.0) for f in frictions)
    times, turns = law.turning_points(
        law_values,
        float(values["y0"]),
        float(data.yp0),
        tau_max=math.inf if data.motion_ended and not frictionless else float(data.tau_end),
        reference=reference,
    )
    a = np.abs(np.asarray(turns, dtype=float))
    mu = np.zeros(a.size)
    for friction in frictions:
        mu += np.array([friction.force(float(x), coef[friction.columns]) for x in a])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(times, dtype=float), np.where(mu > 0, a / mu, np.inf)


def _turning_stops_at(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    nodes: NDArray,
    fixed_params: Mapping[str, float],
) -> list[tuple[NDArray, NDArray]]:
    """:func:`turning_stops` at each node (rows of ``nodes``, the first the centre)."""
    return [
        turning_stops(likelihood, {**fixed_params, **dict(zip(names, node, strict=True))})
        for node in nodes
    ]


def _piece_ratios(
    ratios: list[NDArray],
    order: NDArray,
    k: int,
    value: float,
    bounds: tuple[float, float],
) -> tuple[NDArray, NDArray]:
    """A value of μ_s/μ_k inside piece ``k`` at every node, ``value`` at the centre,
    and whether the piece is known there.

    The piece lies between two stop ratios of the centre's motion: those of the
    turning points ``order[k - 1]`` and ``order[k]`` (``order`` lists the turning
    points whose stop ratio at the centre is inside ``bounds``, in increasing stop
    ratio); below the first, between the nearest stop ratio under ``bounds[0]`` (or
    0) and the first; above the last, from the last up. Each node's value sits at
    the same fraction of its own edges as ``value`` at the centre's (shifted by the
    same distance above the last edge). An edge whose turning point a node does not
    reach keeps its centre value there, and the piece is not known there; nor where
    it does not meet ``bounds`` (the motion of a ratio outside the prior's support).
    """
    centre = ratios[0]
    low, high = bounds
    finite = np.flatnonzero(np.isfinite(centre))
    if k > 0:
        below: int | None = int(order[k - 1])
    else:
        under = finite[centre[finite] <= low]
        below = int(under[np.argmax(centre[under])]) if under.size else None
    if k < order.size:
        above: int | None = int(order[k])
    else:
        over = finite[centre[finite] >= high]
        above = int(over[np.argmin(centre[over])]) if over.size else None

    def edge(index: int | None, default: float) -> tuple[float, NDArray, NDArray]:
        n = len(ratios)
        if index is None:
            return default, np.full(n, default), np.ones(n, dtype=bool)
        known = np.array([r.size > index and np.isfinite(r[index]) for r in ratios])
        pairs = zip(ratios, known, strict=True)
        at = np.array([r[index] if ok else centre[index] for r, ok in pairs])
        return float(centre[index]), at, known

    lo_c, lo, lo_known = edge(below, 0.0)
    hi_c, hi, hi_known = edge(above, math.inf)
    valid = lo_known & hi_known & (lo < hi) & (hi > low) & (lo < high)
    if math.isfinite(hi_c):
        return lo + (value - lo_c) / (hi_c - lo_c) * (hi - lo), valid
    return lo + (value - lo_c), valid


def quadratic_pi(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    centre: Mapping[str, float],
    scale: NDArray,
    fixed_params: Mapping[str, float],
    inside: Inside,
    ratio: str | None = None,
    ratio_bounds: tuple[float, float] | None = None,
) -> QuadraticPi | None:
    """Fit a quadratic about ``centre`` to the exact Π of ``likelihood``.

    Parameters
    ----------
    likelihood : PiLikelihood
        The exact likelihood (its law's compiled integrator gives Π).
    names : tuple of str
        The coordinates of the expansion (sampled, entering Π smoothly).
    centre : mapping
        Their values at the expansion point.
    scale : ndarray
        Shape (p,): their units (positive).
    fixed_params : mapping
        The law's other parameters and their values (fixed, null, or for ``ratio`` its
        value at the expansion point).
    inside : callable
        ``inside(values) -> bool`` for a mapping of the coordinates' values: whether a
        node is inside the priors' support; a coordinate whose node on one side is
        outside takes both nodes on the other side.
    ratio : str, optional
        The name of a sampled μ_s/μ_k: Π is fitted piecewise in it (see
        :class:`QuadraticPi`), its pieces found in ``ratio_bounds`` at the centre.
    ratio_bounds : tuple of float, optional
        The support of μ_s/μ_k's prior.

    Returns
    -------
    QuadraticPi or None
        None when the nodes where Π is finite (the law can move) do not determine the
        quadratic, or a coordinate's nodes fall outside the support on both sides.
    """
    p = len(names)
    c = np.array([float(centre[n]) for n in names])
    s = _node_distances(likelihood, names, c, np.asarray(scale, dtype=float), fixed_params, inside)
    sides = np.zeros(p)
    for a in range(p):
        # a spread wider than the prior's support (a parameter the data leave free)
        # is narrowed until the nodes on one side fit in it
        for _ in range(_NARROWINGS):
            ok = []
            for sign in (-1.0, 1.0):
                values = dict(zip(names, c, strict=True))
                values[names[a]] = c[a] + sign * 2.0 * s[a]
                ok.append(bool(inside(values)))
            if ok[0] or ok[1]:
                break
            s[a] *= 0.5
        if ok[0] and ok[1]:
            continue
        if not (ok[0] or ok[1]):
            return None
        sides[a] = 1.0 if ok[1] else -1.0
    return _fit_pieces(likelihood, names, c, s, _nodes(p, sides), fixed_params, ratio, ratio_bounds)


def _fit_pieces(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    c: NDArray,
    s: NDArray,
    u: NDArray,
    fixed_params: Mapping[str, float],
    ratio: str | None,
    ratio_bounds: tuple[float, float] | None,
) -> QuadraticPi | None:
    """The quadratic of :func:`quadratic_pi` fitted by least squares to the exact Π at
    the points ``c + u s`` (rows of ``u``, the first the centre, ``u = 0``): the nodes
    of a design, or draws (:func:`regressed_pi`); piecewise in ``ratio`` as there."""
    shell = QuadraticPi(tuple(names), c, s, np.zeros((0, 1)))
    basis = shell.monomials(u)
    thresholds = np.zeros((0, basis.shape[1]))
    values = [None]
    if ratio is not None and ratio_bounds is not None:
        low, high = ratio_bounds
        # the ratios where the stick moves to another turning point: each turning
        # point's |Y_n|/μ inside the prior's support at the centre, fitted as Π is
        # over the nodes whose motion reaches that turning point
        turning = _turning_stops_at(likelihood, names, c + u * s, fixed_params)
        ratios = [stops for _, stops in turning]
        centre_ratios = ratios[0]
        inside_support = np.flatnonzero(
            np.isfinite(centre_ratios) & (centre_ratios > low) & (centre_ratios < high)
        )
        order = inside_support[np.argsort(centre_ratios[inside_support])]
        at_centre = centre_ratios[order]
        edges = np.concatenate([[low], at_centre, [high]])
        values = list(0.5 * (edges[:-1] + edges[1:]))
        thresholds = np.zeros((at_centre.size, basis.shape[1]))
        thresholds[:, 0] = at_centre
        for k, n in enumerate(order):
            # over the nodes whose motion reaches the turning point (a smooth function
            # of the coordinates there); constant where those are too few
            reached = np.array([r.size > n and np.isfinite(r[n]) for r in ratios])
            pairs = zip(ratios, reached, strict=True)
            at_nodes = np.array([r[n] if ok else np.nan for r, ok in pairs])
            coef = _fit(basis, at_nodes[:, None], reached)
            if coef is not None:
                thresholds[k] = coef[:, 0]
    pieces = None
    shared = None
    if ratio is not None and ratio_bounds is not None:
        # each node's Π of each piece: at a ratio inside the piece at that node, whose
        # edges move with the other coordinates (a ratio fixed at the centre's midpoint
        # falls in the next piece at nodes where an edge has moved past it, and the
        # piece's quadratic then fits two motions); all pieces from one integration of
        # each node's longest motion where that agrees with the direct one
        pieces = [_piece_ratios(ratios, order, k, v, (low, high)) for k, v in enumerate(values)]
        shared = _pieces_from_longest(
            likelihood, names, ratio, c + u * s, [r for r, _ in pieces], fixed_params, turning
        )
    tables = []
    for k, value in enumerate(values):
        if value is None or pieces is None:
            pi = _evaluate(likelihood, names, c + u * s, fixed_params)
        else:
            at_nodes, valid = pieces[k]
            if shared is not None:
                pi = shared[k]
            else:
                rows = np.column_stack([c + u * s, at_nodes])
                pi = _evaluate(likelihood, (*names, ratio), rows, fixed_params)
            # where the piece leaves the support at a node, or an edge's turning point
            # is not reached there, its motion is not the piece's: the quadratic is
            # fitted to the other nodes (it serves only where the piece exists)
            coef = _fit(basis, pi, valid & np.all(np.isfinite(pi), axis=1))
            if coef is not None:
                tables.append(coef)
                continue
        # a node where the law cannot move (an arc too damped to turn) is left out
        coef = _fit(basis, pi, np.all(np.isfinite(pi), axis=1))
        if coef is None:
            return None
        tables.append(coef)
    return QuadraticPi(tuple(names), c, s, np.vstack(tables), ratio, thresholds)


def _pieces_from_longest(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    ratio: str,
    points: NDArray,
    piece_ratios: list[NDArray],
    fixed_params: Mapping[str, float],
    turning: list[tuple[NDArray, NDArray]],
) -> list[NDArray] | None:
    """Each piece's Π at the points (rows of ``points``, the first the centre), each
    (n, m), from one integration of each point's longest motion
    (:mod:`bayestribo.inference.piece_pi`); None where that does not agree with the
    direct integration at the centre within :data:`~bayestribo.inference.piece_pi.
    TOLERANCE` of Π(0) (the caller integrates each piece directly). A point whose
    longest motion cannot be integrated has its pieces integrated directly."""
    grid = np.asarray(likelihood.data.tau_grid[:-1], dtype=float)
    times = [t for t, _ in turning]
    stops = [r for _, r in turning]
    ends = [stop_times(times, stops, np.asarray(r, dtype=float)) for r in piece_ratios]
    needed = np.concatenate([e[np.isfinite(e)] for e in ends])
    at = np.unique(np.concatenate([grid, needed]))
    n = points.shape[0]
    params: dict[str, NDArray] = {k: np.full(n, float(v)) for k, v in fixed_params.items()}
    params.update({name: points[:, a] for a, name in enumerate(names)})
    params[ratio] = np.ones(n)
    longest = longest_motion_pi(likelihood, params, at)
    moved = np.all(np.isfinite(longest), axis=1)
    if not moved[0]:
        return None
    out = [piece_rows(longest, at, grid, e) for e in ends]
    centre = np.array([[*points[0], float(r[0])] for r in piece_ratios])
    direct = _evaluate(likelihood, (*names, ratio), centre, fixed_params)
    scale = max(float(np.nanmax(np.abs(direct))), float(np.max(np.abs(longest[0]))))
    for k, pi in enumerate(out):
        if not np.allclose(pi[0], direct[k], rtol=0.0, atol=TOLERANCE * scale, equal_nan=False):
            return None
        pi[0] = direct[k]
    if not moved.all():
        rows = np.flatnonzero(~moved)
        for k, r in enumerate(piece_ratios):
            at_rows = np.column_stack([points[rows], np.asarray(r, dtype=float)[rows]])
            out[k][rows] = _evaluate(likelihood, (*names, ratio), at_rows, fixed_params)
    return out


@dataclass(frozen=True)
class SurrogateLikelihood(PiLikelihood):
    """:class:`~bayestribo.inference.likelihood.PiLikelihood` whose model Π is a
    :class:`QuadraticPi` (the compiled log posterior evaluates the same quadratic,
    :mod:`bayestribo.inference.fused`)."""

    surrogate: QuadraticPi | None = field(default=None)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.surrogate is None:
            raise ValueError("surrogate: a QuadraticPi is required")

    def model_pi(self, params: Params) -> NDArray:
        """Surrogate Π at the grid points, shape (n, m)."""
        return self.surrogate(params)  # type: ignore[misc]


@dataclass(frozen=True)
class SurrogateCheck:
    """The exact posterior against the surrogate's at the surrogate's draws.

    Attributes
    ----------
    draws : int
        Draws at which the exact log posterior was evaluated.
    weight_cv : float
        Coefficient of variation of the importance weights exact/surrogate (inf when
        a draw has zero exact density, NaN when nothing was checked).
    log_weight_sd : float
        Standard deviation of the log weights.
    attempt : int
        1 for the surrogate about the maximum a posteriori, 2 and more for those built
        again about the best draw checked.
    best : ndarray or None
        The checked draw of highest exact log posterior (the next centre when the
        check fails).
    corrected : bool
        The surrogate's draws were resampled to the exact posterior by their
        importance weights (:mod:`bayestribo.inference.correction`); ``draws``,
        ``weight_cv`` and ``log_weight_sd`` are then those of every draw weighted.
    weights : ndarray or None
        Where the check failed and the run was kept for a caller that weights its
        draws (:func:`bayestribo.inference.chains.sample_from` with ``weighted``): the
        importance weights of those draws (:func:`bayestribo.inference.correction.
        weights_at` of :func:`~bayestribo.inference.correction.evenly_spaced`), so that
        the caller need not evaluate the exact posterior there again.
    """

    draws: int
    weight_cv: float
    log_weight_sd: float
    attempt: int
    best: NDArray | None = field(default=None, repr=False, compare=False)
    corrected: bool = False
    weights: NDArray | None = field(default=None, repr=False, compare=False)

    @property
    def passed(self) -> bool:
        """True when the chains kept stand for the exact posterior's: the surrogate's
        draws as they are, or corrected by their importance weights."""
        return bool(self.corrected or self.weight_cv <= MAX_WEIGHT_CV)

    def to_dict(self) -> dict[str, float | int | bool]:
        """Plain values for the fit's JSON."""
        return {
            "draws_checked": self.draws,
            "weight_cv": self.weight_cv,
            "log_weight_sd": self.log_weight_sd,
            "attempt": self.attempt,
            "passed": self.passed,
            "max_weight_cv": MAX_WEIGHT_CV,
            "corrected": self.corrected,
        }


def check(
    exact: Callable[[NDArray], NDArray],
    surrogate: Callable[[NDArray], NDArray],
    draws: NDArray,
    rng: np.random.Generator,
    attempt: int = 1,
    n: int = CHECK_DRAWS,
) -> SurrogateCheck:
    """Importance weights of the exact log posterior over the surrogate's.

    Parameters
    ----------
    exact, surrogate : callable
        Log posterior densities of rows (k, d), each (k,).
    draws : ndarray
        Draws of the surrogate posterior, (N, d).
    rng : Generator
        Picks the ``n`` draws checked (all when N <= n).
    attempt : int
        Recorded in the result.

    Returns
    -------
    SurrogateCheck
    """
    draws = np.atleast_2d(draws)
    pick = draws if draws.shape[0] <= n else draws[rng.choice(draws.shape[0], n, replace=False)]
    if pick.shape[0] < 2:
        return SurrogateCheck(int(pick.shape[0]), math.nan, math.nan, attempt)
    lp = np.asarray(exact(pick), dtype=float)
    best = pick[int(np.argmax(lp))].copy() if np.isfinite(lp).any() else None
    log_w = lp - np.asarray(surrogate(pick), dtype=float)
    if not np.all(np.isfinite(log_w)):
        return SurrogateCheck(int(pick.shape[0]), math.inf, math.inf, attempt, best)
    w = np.exp(log_w - log_w.max())
    cv = float(np.std(w) / np.mean(w))
    return SurrogateCheck(int(pick.shape[0]), cv, float(np.std(log_w)), attempt, best)


def surrogate_posterior(posterior: Posterior, centre: NDArray, scale: NDArray) -> Posterior | None:
    """The posterior of ``posterior``'s priors with a :class:`QuadraticPi` of its Π.

    Parameters
    ----------
    posterior : Posterior
        The exact posterior (a law without a closed form).
    centre : ndarray
        Shape (d,): the expansion point in sampling coordinates.
    scale : ndarray
        Shape (d,): the node distances in sampling coordinates (only those of the
        coordinates Π depends on are used; a zero or non-finite one is replaced by
        1e-6 of the centre's magnitude, or 1e-12).

    Returns
    -------
    Posterior or None
        None when the quadratic cannot be built (the law cannot move at a node on
        either side of the centre, or the centre is outside the priors' support).
    """
    centre = np.asarray(centre, dtype=float)
    scale = np.asarray(scale, dtype=float)
    ratio = _RATIO if _RATIO in posterior.names else None
    names = tuple(n for n in posterior.names if n not in _NOT_IN_PI and n != ratio)
    index = [posterior.names.index(n) for n in names]
    s = scale[index].copy()
    c = centre[index]
    bad = ~(np.isfinite(s) & (s > 0))
    s[bad] = np.maximum(1e-6 * np.abs(c[bad]), 1e-12)
    if not np.isfinite(posterior.priors.logpdf(centre[None])[0]):
        return None

    def inside(values: Mapping[str, float]) -> bool:
        row = centre.copy()
        for name, value in values.items():
            row[posterior.names.index(name)] = value
        # the posterior of this scope: narrowed to the law's domain below, if at all
        return bool(np.isfinite(posterior.priors.logpdf(row[None])[0]))

    law_values = posterior.law_draws(centre[None])
    others = {k: float(v[0]) for k, v in law_values.items() if k not in names}
    if "y0" not in names:
        others["y0"] = float(posterior.values(centre[None])["y0"][0])
    exact = posterior.likelihood
    bounds = None
    if ratio is not None:
        prior = posterior.priors[ratio]
        bounds = (float(getattr(prior, "low", math.nan)), float(getattr(prior, "high", math.nan)))
        if not all(math.isfinite(b) for b in bounds):
            return None  # a prior without bounds: its pieces cannot be listed
    quadratic = quadratic_pi(
        exact, names, dict(zip(names, c, strict=True)), s, others, inside, ratio, bounds
    )
    if quadratic is None:
        # the law cannot move on one side of a coordinate inside its prior's support:
        # the surrogate's prior ends at the edge of the law's domain, where the exact
        # posterior's density does, and its design takes that coordinate's other side
        narrowed = _domain_priors(posterior, names, c, s, others)
        if narrowed is None:
            return None
        posterior = replace(posterior, priors=narrowed)
        quadratic = quadratic_pi(
            exact, names, dict(zip(names, c, strict=True)), s, others, inside, ratio, bounds
        )
        if quadratic is None:
            return None
    fields = {f: getattr(exact, f) for f in ("data", "model", "offset_sd", "drift_sd", "law")}
    likelihood = SurrogateLikelihood(**fields, surrogate=quadratic)
    return replace(posterior, likelihood=likelihood)


#: Rounds of the search for the edge of a law's domain along one coordinate
#: (:func:`_domain_priors`), each narrowing it by a factor of :data:`_EDGE_POINTS`.
_EDGE_ROUNDS = 3
#: Points of Π evaluated per round of that search (one call of the integrator).
_EDGE_POINTS = 32


def _domain_priors(
    posterior: Posterior,
    names: tuple[str, ...],
    c: NDArray,
    s: NDArray,
    fixed_params: Mapping[str, float],
) -> PriorSet | None:
    """The priors with each uniform prior of a coordinate on one side of which the law
    cannot move (Π not finite at ``c - s`` or ``c + s`` alone, finite on the other
    side) ending at the edge of the law's domain along it.

    The exact posterior is zero beyond the edge (the law's likelihood is), so the
    posterior is the same under the narrowed prior; the surrogate's quadratic, which
    does not know the domain, is zero there too (η of ``quadratic+hysteretic``, a
    friction per unit amplitude, below zero: μ(A) < 0 on the AppStat HarmOsc1
    record, where its posterior lies within 1.3 sd of zero). The edge is searched
    between the last node outside and the centre in :data:`_EDGE_ROUNDS` rounds of
    :data:`_EDGE_POINTS` points; the bound is the first point found inside the domain
    (at most ``s / 32768`` inside it). An edge that moves with the other coordinates is
    not what this finds: the check then fails (an exact density of zero at a draw),
    as it would have without it.

    Returns
    -------
    PriorSet or None
        None when no coordinate has such an edge inside a uniform prior.
    """
    likelihood = posterior.likelihood
    p = len(names)
    rows = np.repeat(c[None], 2 * p, axis=0)
    rows[np.arange(p) * 2, np.arange(p)] -= s
    rows[np.arange(p) * 2 + 1, np.arange(p)] += s
    finite = np.all(np.isfinite(_evaluate(likelihood, names, rows, fixed_params)), axis=1)
    narrowed: dict[str, Uniform] = {}
    for a, name in enumerate(names):
        below, above = bool(finite[2 * a]), bool(finite[2 * a + 1])
        prior = posterior.priors[name] if name in posterior.names else None
        if below == above or not isinstance(prior, Uniform):
            continue
        outside, inner = (c[a] - s[a], c[a]) if above else (c[a] + s[a], c[a])
        for _ in range(_EDGE_ROUNDS):
            line = np.linspace(outside, inner, _EDGE_POINTS)
            probe = np.repeat(c[None], _EDGE_POINTS, axis=0)
            probe[:, a] = line
            ok = np.all(np.isfinite(_evaluate(likelihood, names, probe, fixed_params)), axis=1)
            first = int(np.argmax(ok))  # the last point, the centre, is inside
            outside, inner = line[max(first - 1, 0)], line[first]
        low, high = (inner, prior.high) if above else (prior.low, inner)
        if low < high:
            narrowed[name] = Uniform(float(low), float(high))
    return posterior.priors.replace(**narrowed) if narrowed else None


def regressed_pi(
    likelihood: PiLikelihood,
    names: tuple[str, ...],
    points: NDArray,
    fixed_params: Mapping[str, float],
    ratio: str | None = None,
    ratio_bounds: tuple[float, float] | None = None,
) -> QuadraticPi | None:
    """The quadratic of :func:`quadratic_pi` fitted by least squares to the exact Π at
    given points instead of the nodes of a design.

    Parameters
    ----------
    likelihood : PiLikelihood
        The exact likelihood (its law's compiled integrator gives Π).
    names : tuple of str
        The coordinates of the quadratic (those Π depends on smoothly).
    points : ndarray
        Their values at the points, (n, p): draws of a surrogate posterior. The
        expansion point is their mean, the unit :data:`NODE_SCALE` times their
        standard deviation.
    fixed_params : mapping
        The law's other parameters and their values (and ``y0`` when it is not a
        coordinate), as in :func:`quadratic_pi`.
    ratio, ratio_bounds : optional
        A sampled μ_s/μ_k and its prior's support: Π is fitted piecewise in it, the
        pieces found at the expansion point, as in :func:`quadratic_pi`.

    Returns
    -------
    QuadraticPi or None
        None when the points where Π is finite do not determine the quadratic (a
        coordinate without spread among them, or too few points).
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    c = points.mean(axis=0)
    s = NODE_SCALE * points.std(axis=0)
    if not np.all(np.isfinite(s) & (s > 0)):
        return None
    u = np.vstack([np.zeros((1, c.size)), (points - c) / s])
    return _fit_pieces(likelihood, names, c, s, u, fixed_params, ratio, ratio_bounds)


def regressed_posterior(
    posterior: Posterior,
    failed: Posterior,
    draws: NDArray,
    rng: np.random.Generator,
    n: int = REFIT_DRAWS,
) -> Posterior | None:
    """The surrogate posterior fitted again at draws of a surrogate that failed its check.

    Parameters
    ----------
    posterior : Posterior
        The exact posterior.
    failed : Posterior
        The surrogate posterior whose check failed (its likelihood a
        :class:`SurrogateLikelihood`).
    draws : ndarray
        Its draws, (N, d) in sampling coordinates.
    rng : Generator
        Picks the draws (``max(n, 4 R)`` of them, R the quadratic's coefficients; all
        when there are fewer).
    n : int
        The fewest draws picked.

    Returns
    -------
    Posterior or None
        With :func:`regressed_pi` of the draws in place of the failed quadratic; None
        when the draws do not determine the quadratic.
    """
    previous = getattr(failed.likelihood, "surrogate", None)
    if not isinstance(previous, QuadraticPi):
        return None
    draws = np.atleast_2d(np.asarray(draws, dtype=float))
    want = max(int(n), 4 * previous.rows_per_piece)
    if draws.shape[0] > want:
        draws = draws[rng.choice(draws.shape[0], want, replace=False)]
    names = previous.names
    points = draws[:, [posterior.names.index(name) for name in names]]
    centre = np.asarray(draws.mean(axis=0))
    law_values = posterior.law_draws(centre[None])
    others = {k: float(v[0]) for k, v in law_values.items() if k not in names}
    if "y0" not in names:
        others["y0"] = float(posterior.values(centre[None])["y0"][0])
    bounds = None
    if previous.ratio is not None:
        prior = posterior.priors[previous.ratio]
        bounds = (float(getattr(prior, "low", math.nan)), float(getattr(prior, "high", math.nan)))
        if not all(math.isfinite(b) for b in bounds):
            return None  # a prior without bounds: its pieces cannot be listed
    quadratic = regressed_pi(posterior.likelihood, names, points, others, previous.ratio, bounds)
    if quadratic is None:
        return None
    return replace(failed, likelihood=replace(failed.likelihood, surrogate=quadratic))
