r"""emcee's differential-evolution moves for independent ensembles in one sampler.

:func:`~bayestribo.inference.sampling.run_ensembles` runs several independent
ensembles so that R-hat compares independent chains. Run as separate
:class:`emcee.EnsembleSampler` objects, each ensemble pays emcee's per-step Python
work (choosing a move, copying the random state, splitting, the acceptance loop)
and evaluates its few walkers per call. Here the G ensembles of W walkers are the
walkers of **one** sampler, walker ``g·W + i`` belonging to ensemble g, and the moves
update each ensemble only from its own walkers:

* :class:`GroupedDEMove` is emcee's :class:`~emcee.moves.DEMove` (Nelson et al. 2013,
  ter Braak 2006) per ensemble: the ensemble is split at random into two halves;
  each walker of one half proposes ``q = x + γ (x_b − x_a)`` for an ordered pair
  a ≠ b drawn uniformly from the other half of the *same* ensemble, with
  ``γ = γ₀ (1 + σ n)``, n standard normal, γ₀ = 2.38/√(2d), σ = 1e-5;
* :class:`GroupedDESnookerMove` is the snooker move of ter Braak & Vrugt (2008)
  (:class:`DESnookerMove`, emcee's :class:`~emcee.moves.DESnookerMove` corrected, see
  below) per ensemble: four splits; each walker x of one split draws one walker from
  each of the three others (same ensemble), in random order z, z₁, z₂, and proposes
  ``q = x + γ_s u (u·z₁ − u·z₂)`` with the unit vector ``u = (x − z)/|x − z|`` and
  γ_s = 1.7, accepted with the extra log factor ``(d − 1) log(|q − z|/|x − z|)``.

**emcee's snooker move is not a valid Metropolis-Hastings move** (emcee 3.1.6, fixed
upstream after that release, dfm/emcee#531): it takes ``u = (x − z)/√|x − z|``, so the
step along the line through z is ``r·γ_s (e·(z₁ − z₂))`` at a distance r from z (e the
unit vector), a stretch by ``1 + γ_s e·(z₁ − z₂)``, a number with the parameters'
units, which swapping z₁ and z₂ does not undo, and it accepts with half the Jacobian,
``((d − 1)/2) log(|q − z|/|x − z|)``. Its stationary distribution is not the target:
on a 4-D target of a correlated Gaussian pair (sd 1e-5, 4e-5: ζ and μ_k), a uniform
on [1, 3] (μ_s/μ_k) and a narrow Gaussian (y0), the mix with DE (80/20) gave standard
deviations 4.5-5 % too small; on the paper's rig the single-run fit's sd of ζ and μ_k
were 4-5 % below the Fisher information's (with μ_s/μ_k fixed, or with the stretch
move, they agree within 1 %). The corrected move, with the unit vector and the full
Jacobian (d − 1), is ter Braak & Vrugt's: it moves x along the line through z by
``γ_s e·(z₁ − z₂)`` and is undone by swapping z₁ and z₂ (the tests check both).

The random numbers of all ensembles' proposals and Metropolis decisions are drawn at
once from the sampler's random state, the proposals computed by a compiled loop
(numba), and the log-probability evaluated for all their walkers in one vectorised
call.

**Compiled step.** A log-probability may offer the whole update compiled: an
attribute ``grouped_step(kind, coords, log_prob, order, uniform, gamma, log_u,
accepted) -> int`` that runs the splits of move ``kind`` (:data:`DE` or
:data:`SNOOKER`) in order, with the numbers this module drew (``uniform`` and
``gamma`` per split as the move's ``_draw`` gives them, ``log_u`` the log Metropolis
uniforms), the same proposal loops and the same acceptance rule, updating ``coords``,
``log_prob`` and ``accepted`` in place, and returns the number of splits it completed.
It stops before a split whose proposals are not finite or whose log-probability it
cannot give (NaN, or a point its compiled form does not cover); that split and the
rest then run here, where the errors are raised. Chains are bit-identical with and
without it (tests); :meth:`bayestribo.inference.posterior.Posterior.grouped_step` is
the single-run fit's (:mod:`bayestribo.inference.fused_step`).

The distribution of every proposal is that of the corresponding one-ensemble move,
emcee's ``DEMove`` and :class:`DESnookerMove` (the tests compare them with those
moves' own ``get_proposal`` and sample known targets with both); the ensembles share the
sampler's random stream but never each other's walkers, so they are independent
chains. emcee runs the chain (its sampler, state, backend and random state);
emcee's own moves, one sampler per ensemble, stay available as the reference
(``SamplerSettings(moves="emcee")``).
"""

from __future__ import annotations

import math

import emcee
import numba
import numpy as np
from emcee.state import State
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError

__all__ = [
    "DE",
    "SNOOKER",
    "DESnookerMove",
    "GroupedDEMove",
    "GroupedDESnookerMove",
    "grouped_moves",
]

#: Move codes passed to a compiled step (see the module notes).
DE, SNOOKER = 0, 1


def _compiled_step(model):
    """The compiled step the sampler's log-probability offers (its ``grouped_step``
    attribute, see the module notes), or None."""
    function = getattr(model.log_prob_fn, "f", model.log_prob_fn)  # emcee's wrapper
    return getattr(function, "grouped_step", None)


def _log_prob(model, q: NDArray) -> NDArray:
    """Log-probability of proposals ``q`` (n, d) by the sampler's vectorised function.

    emcee's ``compute_log_prob`` without its per-walker handling of blobs (a Python
    loop over the walkers): the grouped moves need a sampler made with
    ``vectorize=True`` whose function returns one value per row and no blobs. emcee's
    checks are kept: non-finite coordinates and a NaN log-probability raise
    ``ValueError``.
    """
    if not np.isfinite(q).all():
        raise ValueError("At least one parameter value was infinite or NaN")
    log_prob = np.asarray(model.log_prob_fn(q), dtype=float)
    if log_prob.shape != (q.shape[0],):
        raise BayestriboError(
            "the grouped moves need a vectorised log-probability (vectorize=True) that "
            f"returns one value per walker and no blobs; got shape {log_prob.shape} for "
            f"{q.shape[0]} walkers"
        )
    if np.isnan(log_prob).any():
        raise ValueError("Probability function returned NaN")
    return log_prob


class DESnookerMove(emcee.moves.DESnookerMove):
    """emcee's ``DESnookerMove`` with ter Braak & Vrugt's (2008) proposal and Jacobian.

    ``q = x + γ_s u (u·z₁ − u·z₂)``, ``u = (x − z)/|x − z|``, accepted with the extra
    log factor ``(d − 1) log(|q − z|/|x − z|)`` (emcee 3.1.6 divides by √|x − z| and
    takes half the factor: see the module notes). The one-ensemble reference of
    :class:`GroupedDESnookerMove`, used by ``SamplerSettings(moves="emcee")``.

    Parameters
    ----------
    gammas : float
        Mean stretch of the snooker update (default 1.7, ter Braak & Vrugt 2008).
    """

    def get_proposal(
        self, s: NDArray, c: list[NDArray], random: np.random.RandomState
    ) -> tuple[NDArray, NDArray]:
        """Proposals for walkers ``s`` (n, d) from the three other splits ``c``, and
        their log Metropolis-Hastings factors (emcee's random draws, in its order)."""
        ns = len(s)
        nc = list(map(len, c))
        ndim = s.shape[1]
        q = np.empty_like(s)
        metropolis = np.empty(ns, dtype=np.float64)
        for i in range(ns):
            w = np.array([c[j][random.randint(nc[j])] for j in range(3)])
            random.shuffle(w)
            z, z1, z2 = w
            delta = s[i] - z
            norm = np.linalg.norm(delta)
            u = delta / norm
            q[i] = s[i] + u * self.gammas * (np.dot(u, z1) - np.dot(u, z2))
            metropolis[i] = np.log(np.linalg.norm(q[i] - z)) - np.log(norm)
        return q, (ndim - 1.0) * metropolis


class _GroupedRedBlueMove(emcee.moves.Move):
    """Red-blue update of ``n_groups`` independent ensembles stacked in one sampler.

    The sampler must be made with ``vectorize=True`` and a log-probability that
    returns one value per walker and no blobs (see :func:`_log_prob`).

    Parameters
    ----------
    n_groups : int
        Independent ensembles; the sampler's walkers are ``n_groups`` blocks of equal
        size, each a multiple of ``nsplits``.
    nsplits : int
        Sub-ensembles of each ensemble (each updated from the others in turn).
    """

    def __init__(self, n_groups: int, nsplits: int) -> None:
        self.n_groups = int(n_groups)
        self.nsplits = int(nsplits)

    def _shape(self, nwalkers: int, ndim: int) -> int:
        if getattr(self, "_checked", None) == (nwalkers, ndim):
            return nwalkers // self.n_groups
        per, rest = divmod(nwalkers, self.n_groups)
        if rest or per % self.nsplits or per < 2 * ndim:
            raise BayestriboError(
                f"{type(self).__name__}: {nwalkers} walkers do not form {self.n_groups} "
                f"ensembles of a multiple of {self.nsplits} walkers, at least {2 * ndim} each"
            )
        self._checked = (nwalkers, ndim)
        return per

    #: Move code of the compiled step (:data:`DE` or :data:`SNOOKER`).
    kind: int
    #: Uniform numbers per proposal (``_draw``).
    n_uniform: int
    #: Normal numbers per proposal (``_draw``, after its uniform ones).
    n_normal: int

    def _draw(
        self, random: np.random.RandomState, g: int, size: int, ndim: int
    ) -> tuple[NDArray, NDArray]:  # pragma: no cover - interface
        """The random numbers of one split's proposals: ``uniform`` (g, size, k) and
        the stretches ``gamma`` (g, size), drawn from ``random`` in emcee's order."""
        raise NotImplementedError

    def _split_proposal(
        self, coords: NDArray, order: NDArray, split: int, uniform: NDArray, gamma: NDArray
    ) -> tuple[NDArray, NDArray]:  # pragma: no cover - interface
        """Proposals (G·size, d) and log factors (G·size,) for split ``split`` of the
        walkers ``order`` (G, nsplits·size) of ``coords`` (one row per walker), from
        the numbers ``_draw`` gave."""
        raise NotImplementedError

    def get_proposal(
        self, s: NDArray, c: list[NDArray], random: np.random.RandomState
    ) -> tuple[NDArray, NDArray]:
        """Proposals for walkers ``s`` (G, n, d) from the other splits ``c`` (each
        (G, n, d)), and the log Metropolis-Hastings factors (G, n): emcee's
        ``get_proposal`` for G ensembles at once (the same computation as
        :meth:`propose`)."""
        g, ns, ndim = s.shape
        coords = np.concatenate([s, *c], axis=1).reshape(-1, ndim)
        order = np.arange(coords.shape[0]).reshape(g, -1)
        uniform, gamma = self._draw(random, g, ns, ndim)
        q, factors = self._split_proposal(coords, order, 0, uniform, gamma)
        return q.reshape(g, ns, ndim), factors.reshape(g, ns)

    def _numbers(
        self, random: np.random.RandomState, g: int, per: int, ndim: int
    ) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Every random number of one step, in emcee's order: each ensemble's split
        (``rand(g, per)``), then split by split its proposal numbers (``_draw``) and
        its Metropolis uniforms (``rand(g·size)``).

        The uniform numbers that follow one another in that order are drawn in one
        call (the generator gives ``rand(a)`` then ``rand(b)`` as ``rand(a + b)``), so
        the numbers are those of drawing them one by one; one compiled call
        (:func:`_arrange`) lays them out.

        Returns
        -------
        order : ndarray
            Each ensemble's walkers in split order, (g, per), int64.
        uniform, gamma, log_u : ndarray
            As the compiled step takes them (see the module notes).
        """
        size = per // self.nsplits
        n_prop, n_acc = g * size * self.n_uniform, g * size
        # random_sample(n) and standard_normal(n) are what rand(n) and randn(n) call
        if self.n_normal == 0:
            uniforms = random.random_sample(g * per + self.nsplits * (n_prop + n_acc))
            normals = _NO_NORMALS
        else:
            # a normal draw (γ) sits between the proposal and Metropolis uniforms
            drawn = [random.random_sample(g * per + n_prop)]
            normal = []
            for split in range(self.nsplits):
                normal.append(random.standard_normal(n_acc * self.n_normal))
                last = split + 1 == self.nsplits
                drawn.append(random.random_sample(n_acc if last else n_acc + n_prop))
            uniforms = np.concatenate(drawn)
            normals = np.concatenate(normal)
        g0, sigma = self._stretch_of(ndim)
        order, uniform, gamma, log_u = self._layout(g, per)
        _arrange(uniforms, normals, g0, sigma, order, uniform, gamma, log_u)
        np.log(log_u, out=log_u)
        return order, uniform, gamma, log_u

    def _layout(self, g: int, per: int) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """The arrays of one step's numbers (:meth:`_numbers`), made once per shape
        and filled anew at every step (a step reads them only while it runs)."""
        layout = getattr(self, "_layout_cache", None)
        if layout is None or layout[0].shape != (g, per):
            size = per // self.nsplits
            layout = (
                np.empty((g, per), dtype=np.int64),
                np.empty((self.nsplits, g, size, self.n_uniform)),
                np.empty((self.nsplits, g, size)),
                np.empty((self.nsplits, g * size)),
            )
            self._layout_cache = layout
        return layout

    def _stretch_of(self, ndim: int) -> tuple[float, float]:
        """γ₀ and σ of the stretch γ = γ₀ (1 + σ n) (σ unused by a move without normal
        numbers, whose γ is γ₀)."""
        raise NotImplementedError  # pragma: no cover - interface

    def propose(self, model, state: State) -> tuple[State, NDArray]:
        """One update of every walker of every ensemble (emcee's ``Move`` interface).

        Every random number of the step is drawn first, in the order of the splits
        (each split's proposal numbers, then its Metropolis uniforms; :meth:`_numbers`);
        the splits then run in the log-probability's compiled step if it offers one
        (see the module notes), else, or from the split where that step stops, here.
        """
        nwalkers, ndim = state.coords.shape
        per = self._shape(nwalkers, ndim)
        g = self.n_groups
        order, uniforms, gammas, log_u = self._numbers(model.random, g, per, ndim)
        size = per // self.nsplits
        coords = np.ascontiguousarray(state.coords, dtype=np.float64)
        log_prob = np.ascontiguousarray(state.log_prob, dtype=np.float64)
        accepted = np.zeros(nwalkers, dtype=bool)
        step = _compiled_step(model)
        done = 0
        if step is not None:
            done = step(self.kind, coords, log_prob, order, uniforms, gammas, log_u, accepted)
        for split in range(done, self.nsplits):
            flat = order[:, split * size : (split + 1) * size].ravel()
            q, factors = self._split_proposal(coords, order, split, uniforms[split], gammas[split])
            new_log_prob = _log_prob(model, q)
            take = factors + new_log_prob - log_prob[flat] > log_u[split]
            idx = flat[take]
            coords[idx] = q[take]
            log_prob[idx] = new_log_prob[take]
            accepted[idx] = True
        state.coords = coords
        state.log_prob = log_prob
        return state, accepted


class GroupedDEMove(_GroupedRedBlueMove):
    """emcee's ``DEMove`` applied to each of ``n_groups`` independent ensembles.

    Parameters
    ----------
    n_groups : int
        Independent ensembles stacked in the sampler.
    sigma : float
        Relative standard deviation of the stretch γ (emcee's default 1e-5).
    gamma0 : float, optional
        Mean stretch; default 2.38/√(2d) (ter Braak 2006).
    """

    def __init__(self, n_groups: int, sigma: float = 1.0e-5, gamma0: float | None = None) -> None:
        super().__init__(n_groups, nsplits=2)
        self.sigma = sigma
        self.gamma0 = gamma0

    kind = DE
    n_uniform = 2
    n_normal = 1

    def _draw(
        self, random: np.random.RandomState, g: int, size: int, ndim: int
    ) -> tuple[NDArray, NDArray]:
        """Two uniform numbers per walker (the pair) and its stretch γ."""
        g0, sigma = self._stretch_of(ndim)
        uniform = random.rand(g, size, 2)
        return uniform, g0 * (1 + sigma * random.randn(g, size))

    def _stretch_of(self, ndim: int) -> tuple[float, float]:
        """γ₀ (default 2.38/√(2d)) and σ."""
        g0 = 2.38 / math.sqrt(2 * ndim) if self.gamma0 is None else self.gamma0
        return float(g0), float(self.sigma)

    def _split_proposal(
        self, coords: NDArray, order: NDArray, split: int, uniform: NDArray, gamma: NDArray
    ) -> tuple[NDArray, NDArray]:
        """DE proposals: ``x + γ (x_b − x_a)``, (a, b) a uniform ordered pair of
        distinct walkers of the other half of the same ensemble."""
        q = _de_proposals(coords, order, split, uniform, gamma)
        return q, np.zeros(q.shape[0])


class GroupedDESnookerMove(_GroupedRedBlueMove):
    """:class:`DESnookerMove` applied to each of ``n_groups`` independent ensembles.

    Parameters
    ----------
    n_groups : int
        Independent ensembles stacked in the sampler.
    gammas : float
        Mean stretch of the snooker update (emcee's default 1.7, ter Braak & Vrugt
        2008).
    """

    def __init__(self, n_groups: int, gammas: float = 1.7) -> None:
        super().__init__(n_groups, nsplits=4)
        self.gammas = gammas

    kind = SNOOKER
    n_uniform = 4
    n_normal = 0

    def _draw(
        self, random: np.random.RandomState, g: int, size: int, ndim: int
    ) -> tuple[NDArray, NDArray]:
        """Four uniform numbers per walker (three walkers and their order); the
        stretch is the constant ``gammas``."""
        return random.rand(g, size, 4), np.full((g, size), self.gammas)

    def _stretch_of(self, ndim: int) -> tuple[float, float]:
        """The constant stretch ``gammas`` (no normal numbers)."""
        return float(self.gammas), 0.0

    def _split_proposal(
        self, coords: NDArray, order: NDArray, split: int, uniform: NDArray, gamma: NDArray
    ) -> tuple[NDArray, NDArray]:
        """Snooker proposals along x − z, one walker from each other split in random
        order as z, z₁, z₂; log factor (d − 1) log(|q − z|/|x − z|)."""
        q, metropolis = _snooker_proposals(coords, order, split, uniform, self.gammas)
        return q, (coords.shape[1] - 1.0) * metropolis


#: The six orders of three walkers (z, z₁, z₂), drawn uniformly.
_ORDERS = np.array([[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]])


@numba.njit(cache=True, error_model="numpy")
def _de_proposals(
    coords: NDArray, order: NDArray, split: int, uniform: NDArray, gamma: NDArray
) -> NDArray:
    """x + γ (c_b − c_a), (a, b) = a uniform ordered pair of distinct walkers of the
    other half of the same ensemble, from two uniform numbers per walker."""
    g, per = order.shape
    size = per // 2
    ndim = coords.shape[1]
    own = split * size
    other = (1 - split) * size
    q = np.empty((g * size, ndim))
    for e in range(g):
        for i in range(size):
            a = min(int(uniform[e, i, 0] * size), size - 1)
            b = min(int(uniform[e, i, 1] * (size - 1)), size - 2)
            if b >= a:
                b += 1
            x = order[e, own + i]
            ca = order[e, other + a]
            cb = order[e, other + b]
            for j in range(ndim):
                q[e * size + i, j] = coords[x, j] + gamma[e, i] * (coords[cb, j] - coords[ca, j])
    return q


@numba.njit(cache=True, error_model="numpy")
def _snooker_proposals(
    coords: NDArray, order: NDArray, split: int, uniform: NDArray, gammas: float
) -> tuple[NDArray, NDArray]:
    """Snooker proposals (ter Braak & Vrugt's, :class:`DESnookerMove`) and
    log(|q − z|/|x − z|), with one walker of each of the three other splits in a
    uniformly random order as z, z₁, z₂."""
    g, per = order.shape
    size = per // 4
    ndim = coords.shape[1]
    q = np.empty((g * size, ndim))
    metropolis = np.empty(g * size)
    picked = np.empty(3, dtype=np.int64)
    for e in range(g):
        for i in range(size):
            x = order[e, split * size + i]
            rank = _ORDERS[min(int(uniform[e, i, 3] * 6), 5)]
            slot = 0
            for other in range(4):
                if other == split:
                    continue
                w = min(int(uniform[e, i, slot] * size), size - 1)
                picked[rank[slot]] = order[e, other * size + w]
                slot += 1
            z = coords[picked[0]]
            z1 = coords[picked[1]]
            z2 = coords[picked[2]]
            norm = 0.0
            for j in range(ndim):
                norm += (coords[x, j] - z[j]) ** 2
            norm = math.sqrt(norm)
            proj = 0.0
            for j in range(ndim):
                u = (coords[x, j] - z[j]) / norm
                proj += u * z1[j] - u * z2[j]
            dist = 0.0
            row = e * size + i
            for j in range(ndim):
                u = (coords[x, j] - z[j]) / norm
                q[row, j] = coords[x, j] + u * gammas * proj
                dist += (q[row, j] - z[j]) ** 2
            metropolis[row] = math.log(math.sqrt(dist)) - math.log(norm)
    return q, metropolis


#: The normal numbers of a move that draws none.
_NO_NORMALS = np.empty(0)


@numba.njit(cache=True, error_model="numpy")
def _arrange(
    uniforms: NDArray,
    normals: NDArray,
    g0: float,
    sigma: float,
    order: NDArray,
    uniform: NDArray,
    gamma: NDArray,
    log_u: NDArray,
) -> None:
    """A step's numbers laid out for the splits (:meth:`_GroupedRedBlueMove._numbers`).

    ``uniforms`` in the order drawn: the keys of each ensemble's split (g·per), then per
    split its proposal numbers (g·size·k) and Metropolis uniforms (g·size);
    ``normals``: per split g·size normal numbers n (none: γ = γ₀). Fills ``order``
    (g, per) with each ensemble's walkers sorted by their keys, ``uniform`` (splits,
    g, size, k) with the proposal numbers, ``gamma`` (splits, g, size) with the
    stretches γ₀ (1 + σ n) and ``log_u`` (splits, g·size) with the Metropolis
    uniforms, not yet logged.
    """
    nsplits, g, size, k = uniform.shape
    per = order.shape[1]
    for e in range(g):
        order[e] = np.argsort(uniforms[e * per : (e + 1) * per]) + e * per
    at = g * per
    for split in range(nsplits):
        for e in range(g):
            for i in range(size):
                for j in range(k):
                    uniform[split, e, i, j] = uniforms[at]
                    at += 1
        for row in range(g * size):
            log_u[split, row] = uniforms[at]
            at += 1
        for e in range(g):
            for i in range(size):
                if normals.size:
                    gamma[split, e, i] = g0 * (1 + sigma * normals[(split * g + e) * size + i])
                else:
                    gamma[split, e, i] = g0


def grouped_moves(n_groups: int) -> list[tuple[emcee.moves.Move, float]]:
    """The package's move mix (DE 80 %, DE snooker 20 %) for ``n_groups`` stacked
    independent ensembles."""
    return [(GroupedDEMove(n_groups), 0.8), (GroupedDESnookerMove(n_groups), 0.2)]
