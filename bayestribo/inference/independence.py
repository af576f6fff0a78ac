r"""An independence Metropolis-Hastings move for stacked independent ensembles.

:func:`~bayestribo.inference.sampling.run_ensembles` may mix this move with the
differential-evolution moves of :mod:`bayestribo.inference.moves` (``SamplerSettings``
``independence``, the move's weight in the mix). Each walker x of ensemble g draws a
proposal y from a fixed density q_g that does not depend on x, and moves there with
probability

    min(1, π(y) q_g(x) / (π(x) q_g(y))),

the Metropolis-Hastings rule for a proposal independent of the current point
(Tierney 1994). Where q_g is close to the posterior π, y is nearly an independent
draw of π, accepted most of the time: the chain forgets its past in a step or two,
where a DE move on a 4-parameter posterior needs an autocorrelation time of about 15
steps. Where q_g is far from π (a ridge, a bound, a shape a Student-t does not fit),
the move is rarely accepted and the DE moves it is mixed with do the work.

**The proposal** of ensemble g is a multivariate Student-t (:class:`StudentProposal`)
whose location and scale matrix are the mean and the covariance (times
``scale²``) of that ensemble's own walkers over the second half of an adaptation
phase (the sampler's first ``adapt_steps`` steps, DE moves alone), fitted once at the
end of that phase and **held fixed** afterwards; a coordinate whose draws look
bounded and flat (the ratio μ_s/μ_k) is proposed on its own, uniform on their range
with a Cauchy defence (:class:`StudentProposal`). The t's tails, heavier than a
Gaussian's, and the defence keep π/q bounded where π is near-Gaussian or flat and
bounded, which makes the independence sampler uniformly ergodic there (Mengersen &
Tweedie 1996).

**Its weight in the mix** is fixed at the same time: ``SamplerSettings.independence``
where the expected acceptance of the move (:func:`expected_acceptance`, from the
phase's draws and one pilot proposal per walker, evaluated outside any chain) is at
least :data:`FULL_ACCEPTANCE` in every ensemble, less below, none under
:data:`NO_ACCEPTANCE` (:func:`mix_weight`): a move that is rarely accepted does not
take the DE moves' steps.

**Why the chain after the adaptation phase is valid.** From the end of the phase
on, every move of the mix is a Markov kernel that leaves the product of the
posterior over an ensemble's walkers invariant: the DE moves as before, and this
move because each walker's update is a Metropolis-Hastings step with a fixed
proposal, independent of the other walkers. The kernels do not change with the
chain after that step (the proposal is a function of the phase's draws only, which
are past), so the chain after it is a time-homogeneous Markov chain with the target
as its stationary distribution, started from wherever the phase left the walkers.
The phase itself (whose moves did not know the proposal yet, but whose draws fixed
it) is discarded as burn-in: the sampler's burn-in is at least ``adapt_steps``.

**Why ensembles stay independent.** Ensemble g's proposal is fitted from ensemble g's
walkers alone, and its walkers' proposals are drawn from it alone, so the ensembles
share no walker and no proposal, only the sampler's random stream and its choice of
the move at each step, as with the DE moves, and the one weight of the move in the
mix (the least expected acceptance of the ensembles'). Given the phase, each
ensemble's chain is its own valid chain: the shared weight sets how fast they mix,
never where they go, so two ensembles that disagree still show it in R-hat.

The log-probability is evaluated for every walker of every ensemble in one
vectorised call (no split: a proposal does not depend on the other walkers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import emcee
import numba
import numpy as np
from emcee.state import State
from numpy.typing import NDArray
from scipy.special import gammaln

from bayestribo.errors import BayestriboError
from bayestribo.inference.moves import _log_prob

__all__ = [
    "DEFENSIVE",
    "FLAT_CORRELATION",
    "FLAT_KURTOSIS",
    "FULL_ACCEPTANCE",
    "NO_ACCEPTANCE",
    "PROPOSAL_DF",
    "PROPOSAL_SCALE",
    "GroupedIndependenceMove",
    "StudentProposal",
    "expected_acceptance",
    "mix_weight",
    "mixing_tau",
]

#: Degrees of freedom of the fitted Student-t proposal (tails heavier than a
#: Gaussian's: π/q stays bounded where the covariance is estimated a little small).
PROPOSAL_DF = 5.0
#: Factor on the walkers' standard deviations in the proposal's scale matrix.
PROPOSAL_SCALE = 1.0
#: A coordinate is proposed as flat (bounded uniform) where its draws' excess kurtosis
#: is below this (a uniform's is −1.2, a Gaussian's 0) ...
FLAT_KURTOSIS = -0.8
#: ... and its correlation with every other coordinate below this in magnitude.
FLAT_CORRELATION = 0.3
#: Weight of the Cauchy defence in a flat coordinate's proposal (its support is then
#: the whole line, however narrow the draws' range).
DEFENSIVE = 0.1


@dataclass(frozen=True)
class StudentProposal:
    """The independence proposal of one ensemble: a multivariate Student-t in the
    near-Gaussian coordinates, times, for each flat coordinate, a uniform on the
    draws' range mixed with a Cauchy defence.

    A posterior with a coordinate bounded on both sides and flat between (μ_s/μ_k,
    whose posterior is the interval the sticking allows) is proposed poorly by a
    t: its density at the ends of the range is a quarter of its centre's, so a walker
    there waits about four times as long to move. Such a coordinate (excess kurtosis
    below :data:`FLAT_KURTOSIS`, correlation with every other coordinate below
    :data:`FLAT_CORRELATION`) is proposed on its own, from
    ``(1 − ε) U(low, high) + ε Cauchy(centre, half range)``, ε = :data:`DEFENSIVE`.

    Attributes
    ----------
    location : ndarray
        Centre of the t, shape (d,), in the sampled coordinates' units (a flat
        coordinate's entry is unused).
    chol : ndarray
        Lower Cholesky factor L of the t's scale matrix over the coordinates that are
        not flat, embedded in (d, d): a flat coordinate's row and column are those of
        the identity (unused).
    df : float
        Degrees of freedom ν (> 0).
    flat : ndarray
        Which coordinates are flat, shape (d,), bool.
    low, high : ndarray
        The uniform's ends for flat coordinates, shape (d,) (unused elsewhere).
    """

    location: NDArray
    chol: NDArray
    df: float
    flat: NDArray
    low: NDArray
    high: NDArray

    @classmethod
    def fitted(
        cls, draws: NDArray, scale: float = PROPOSAL_SCALE, df: float = PROPOSAL_DF
    ) -> StudentProposal:
        """The proposal of draws (n, d): flat coordinates found as the class notes say,
        each with the draws' range widened by 2 % on either side; the t's location
        and scale matrix the mean and covariance (times ``scale²``) of the others.

        A coordinate whose draws do not vary (or a singular covariance) gets a scale
        of 1e-12 of its magnitude on the diagonal, so that the factor exists; the
        move is then rarely accepted along it and the other moves do the work.

        Parameters
        ----------
        draws : ndarray
            Shape (n, d), n > d, finite.
        scale : float
            Factor on the draws' standard deviations [dimensionless].
        df : float
            Degrees of freedom ν.

        Raises
        ------
        BayestriboError
            If the draws are not (n, d) with n > d, or not finite.
        """
        draws = np.asarray(draws, dtype=float)
        if draws.ndim != 2 or draws.shape[0] <= draws.shape[1]:
            raise BayestriboError(
                f"draws: expected shape (n, d) with n > d to fit a proposal, got {draws.shape}"
            )
        if not np.all(np.isfinite(draws)):
            raise BayestriboError("draws: a proposal is fitted to finite draws only")
        d = draws.shape[1]
        location = draws.mean(axis=0)
        flat = _flat_coordinates(draws)
        margin = 0.02 * (draws.max(axis=0) - draws.min(axis=0))
        low = np.where(flat, draws.min(axis=0) - margin, 0.0)
        high = np.where(flat, draws.max(axis=0) + margin, 1.0)
        keep = ~flat
        chol = np.eye(d)
        if keep.any():
            sub = np.atleast_2d(np.cov(draws[:, keep], rowvar=False)) * scale**2
            chol[np.ix_(keep, keep)] = _cholesky(sub, location[keep])
        return cls(location, chol, float(df), flat, low, high)

    @property
    def ndim(self) -> int:
        """Number of coordinates d."""
        return int(self.location.size)

    def numbers(self, random, n: int) -> tuple[NDArray, NDArray, NDArray]:
        """The random numbers of n draws, in the order drawn from ``random`` (a
        ``RandomState``): standard normals (n, d), χ²_ν (n,) as
        2 × Gamma(ν/2), uniforms (n, d, 2) (a flat coordinate's component and value)."""
        z = random.standard_normal((n, self.ndim))
        w = 2.0 * random.standard_gamma(0.5 * self.df, n)
        u = random.random_sample((n, self.ndim, 2))
        return z, w, u

    def draw(self, random, n: int) -> NDArray:
        """n draws, shape (n, d), from ``random`` (:meth:`numbers`)."""
        z, w, u = self.numbers(random, n)
        return _draws(self.location, self.chol, self.df, self.flat, self.low, self.high, z, w, u)

    def log_density(self, x: NDArray) -> NDArray:
        """Normalised log density of rows x (n, d), shape (n,)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        d = int(np.count_nonzero(~self.flat))
        nu = self.df
        const = (
            gammaln(0.5 * (nu + d))
            - gammaln(0.5 * nu)
            - 0.5 * d * math.log(nu * math.pi)
            - float(np.sum(np.log(np.diag(self.chol)[~self.flat])))
        )
        return const + _log_q(x, self.location, self.chol, self.df, self.flat, self.low, self.high)


def _cholesky(cov: NDArray, location: NDArray) -> NDArray:
    """Lower Cholesky factor of ``cov``, with a diagonal of 1e-12 of ``location``'s
    magnitudes (growing until it works) where ``cov`` is singular."""
    floor = (1e-12 * np.maximum(np.abs(location), 1e-300)) ** 2
    for attempt in range(8):
        try:
            return np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            cov = cov + np.diag(floor * 10.0 ** (2 * attempt))
    return np.diag(np.sqrt(np.maximum(np.diag(cov), floor)))  # pragma: no cover


def _flat_coordinates(draws: NDArray) -> NDArray:
    """Coordinates of ``draws`` (n, d) that look bounded and flat: excess kurtosis
    below :data:`FLAT_KURTOSIS` and |correlation| with every other coordinate below
    :data:`FLAT_CORRELATION`."""
    centred = draws - draws.mean(axis=0)
    var = np.mean(centred**2, axis=0)
    moving = var > 0
    flat = np.zeros(draws.shape[1], dtype=bool)
    if not moving.any():
        return flat
    kurtosis = np.full(draws.shape[1], np.inf)
    kurtosis[moving] = np.mean(centred[:, moving] ** 4, axis=0) / var[moving] ** 2 - 3.0
    sd = np.sqrt(np.where(moving, var, 1.0))
    corr = (centred.T @ centred) / draws.shape[0] / np.outer(sd, sd)
    np.fill_diagonal(corr, 0.0)
    corr[~moving, :] = corr[:, ~moving] = 0.0
    flat = moving & (kurtosis < FLAT_KURTOSIS) & np.all(np.abs(corr) < FLAT_CORRELATION, axis=1)
    return flat


@numba.njit(cache=True, error_model="numpy")
def _draws(location, chol, df, flat, low, high, z, w, u):
    """Draws of the proposal from its numbers (:meth:`StudentProposal.numbers`)."""
    n, d = z.shape
    q = np.empty((n, d))
    for i in range(n):
        stretch = math.sqrt(df / w[i])
        for j in range(d):
            if flat[j]:
                if u[i, j, 0] < DEFENSIVE:
                    centre = 0.5 * (low[j] + high[j])
                    q[i, j] = centre + 0.5 * (high[j] - low[j]) * math.tan(
                        math.pi * (u[i, j, 1] - 0.5)
                    )
                else:
                    q[i, j] = low[j] + (high[j] - low[j]) * u[i, j, 1]
            else:
                acc = 0.0
                for k in range(j + 1):
                    if not flat[k]:
                        acc += chol[j, k] * z[i, k]
                q[i, j] = location[j] + acc * stretch
    return q


@numba.njit(cache=True, error_model="numpy")
def _log_q_row(x, location, chol, df, flat, low, high, u):
    """Log density of one row x, up to the t's normalising constant; ``u`` (d,) is
    work space."""
    d = x.size
    maha = 0.0
    free = 0
    out = 0.0
    for j in range(d):
        if flat[j]:
            half = 0.5 * (high[j] - low[j])
            r = (x[j] - 0.5 * (low[j] + high[j])) / half
            density = DEFENSIVE / (math.pi * half * (1.0 + r * r))
            if low[j] <= x[j] <= high[j]:
                density += (1.0 - DEFENSIVE) / (high[j] - low[j])
            out += math.log(density)
            u[j] = 0.0
        else:
            free += 1
            acc = x[j] - location[j]
            for k in range(j):
                if not flat[k]:
                    acc -= chol[j, k] * u[k]
            u[j] = acc / chol[j, j]
            maha += u[j] * u[j]
    if free:
        out -= 0.5 * (df + free) * math.log1p(maha / df)
    return out


@numba.njit(cache=True, error_model="numpy")
def _log_q(x, location, chol, df, flat, low, high):
    """:func:`_log_q_row` of each row of x (n, d)."""
    n, d = x.shape
    out = np.empty(n)
    u = np.empty(d)
    for i in range(n):
        out[i] = _log_q_row(x[i], location, chol, df, flat, low, high, u)
    return out


def expected_acceptance(
    proposals,
    draws: NDArray,
    log_prob: NDArray,
    proposed: NDArray,
    proposed_log_prob: NDArray,
) -> NDArray:
    """Each ensemble's expected acceptance of an independence step at stationarity.

    E[min(1, w(y)/w(x))] over x ~ π and y ~ q, w = π/q (the posterior's density up
    to its constant), estimated over every pair of an ensemble's draws ``draws`` (the
    adaptation phase's, from π) and its proposals ``proposed`` (from q).

    Parameters
    ----------
    proposals : sequence of StudentProposal
        One per ensemble.
    draws : ndarray
        Shape (ensembles, n, d), with their log-probabilities ``log_prob`` (ensembles, n).
    proposed : ndarray
        Shape (ensembles, m, d), drawn from ``proposals``, with their log-probabilities
        ``proposed_log_prob`` (ensembles, m) (−inf outside the support).

    Returns
    -------
    ndarray
        Expected acceptance per ensemble, in [0, 1].
    """
    out = np.empty(len(proposals))
    for e, proposal in enumerate(proposals):
        log_w_x = log_prob[e] - proposal.log_density(draws[e])
        log_w_y = proposed_log_prob[e] - proposal.log_density(proposed[e])
        with np.errstate(invalid="ignore", over="ignore"):
            ratio = np.exp(np.minimum(log_w_y[:, None] - log_w_x[None, :], 0.0))
        out[e] = float(np.mean(np.nan_to_num(ratio, nan=0.0)))
    return out


#: Expected acceptance (:func:`expected_acceptance`, the least of the ensembles') from
#: which the move has its full weight in the mix, and up to which it is left out
#: (linear between): a move accepted less often than about one step in twenty does
#: less than the DE steps it would replace.
FULL_ACCEPTANCE, NO_ACCEPTANCE = 0.2, 0.05


def mix_weight(acceptance: float, weight: float) -> float:
    """The move's weight in the mix for an expected acceptance ``acceptance``:
    ``weight`` from :data:`FULL_ACCEPTANCE` on, 0 up to :data:`NO_ACCEPTANCE`, linear
    between."""
    share = (acceptance - NO_ACCEPTANCE) / (FULL_ACCEPTANCE - NO_ACCEPTANCE)
    return float(weight * min(1.0, max(0.0, share)))


def mixing_tau(acceptance: float, weight: float) -> float:
    """The autocorrelation time the move alone gives a chain where its proposal
    covers the posterior: (2 − p)/p steps, p = ``weight`` × ``acceptance``.

    At each step a walker jumps with probability p to a proposal that, where the
    proposal is close to the posterior, is nearly an independent draw of it; its
    autocorrelation then falls as (1 − p)^t, whose integrated time is (2 − p)/p (the
    DE moves in the mix only shorten it). A chain whose measured τ is several times
    this has posterior mass the proposal does not reach (a ridge, a tail, a bound
    the adaptation phase did not see), where the move is rejected and the DE moves,
    left a share 1 − ``weight`` of the steps, do the work alone
    (:func:`bayestribo.inference.sampling.run_ensembles` then takes the move out).

    Parameters
    ----------
    acceptance : float
        Expected acceptance of the move (:func:`expected_acceptance`), in [0, 1].
    weight : float
        The move's weight in the mix, in [0, 1).

    Returns
    -------
    float
        τ [steps]; infinite where p is 0.
    """
    p = float(weight) * float(acceptance)
    return (2.0 - p) / p if p > 0 else math.inf


class GroupedIndependenceMove(emcee.moves.Move):
    """Independence Metropolis-Hastings for ``n_groups`` ensembles stacked in one
    sampler, each with its own fixed proposal (see the module notes).

    The sampler must be made with ``vectorize=True`` and a log-probability that
    returns one value per walker and no blobs (as for the grouped DE moves).

    Parameters
    ----------
    proposals : sequence of StudentProposal
        One per ensemble, in the order of the walkers' blocks (walker ``g·W + i``
        belongs to ensemble g).
    """

    def __init__(self, proposals) -> None:
        self.proposals = tuple(proposals)
        if not self.proposals:
            raise BayestriboError("proposals: expected one per ensemble, got none")

    @classmethod
    def fitted(
        cls,
        chains: NDArray,
        scale: float = PROPOSAL_SCALE,
        df: float = PROPOSAL_DF,
    ) -> GroupedIndependenceMove:
        """The move whose proposal for each ensemble is fitted to that ensemble's
        draws alone (:meth:`StudentProposal.fitted`).

        Parameters
        ----------
        chains : ndarray
            Each ensemble's draws, shape (ensembles, steps, walkers, d).
        scale, df : float
            As :meth:`StudentProposal.fitted`.
        """
        chains = np.asarray(chains, dtype=float)
        if chains.ndim != 4:
            raise BayestriboError(
                f"chains: expected shape (ensembles, steps, walkers, d), got {chains.shape}"
            )
        d = chains.shape[-1]
        return cls(StudentProposal.fitted(c.reshape(-1, d), scale, df) for c in chains)

    def _stacked(self) -> tuple[NDArray, ...]:
        """Every proposal's arrays stacked once for the compiled update: location
        (g, d), Cholesky factor (g, d, d), ν (g,), flat (g, d), low and high (g, d)."""
        stacked = getattr(self, "_stack", None)
        if stacked is None:
            p = self.proposals
            stacked = (
                np.stack([x.location for x in p]),
                np.stack([x.chol for x in p]),
                np.array([x.df for x in p]),
                np.stack([x.flat for x in p]),
                np.stack([x.low for x in p]),
                np.stack([x.high for x in p]),
            )
            self._stack = stacked
        return stacked

    def propose(self, model, state: State) -> tuple[State, NDArray]:
        """One update of every walker (emcee's ``Move`` interface).

        The step's random numbers are drawn from the sampler's random state in this
        order: the standard normals of every walker's proposal (walker-major), the
        χ² of each (as 2 × Gamma(ν/2), ν of the first proposal: the fitted ones share
        it), the uniforms of the flat coordinates, the Metropolis uniforms; a
        compiled loop makes the proposals and the proposal's side of the Hastings
        ratio, and the log-probability of all walkers is one vectorised call, or,
        where the log-probability offers it (:func:`_compiled_step`), the log
        posterior and the acceptance are one compiled call
        (:func:`bayestribo.inference.fused_step.independence_step`).
        """
        nwalkers, ndim = state.coords.shape
        g = len(self.proposals)
        if nwalkers % g or self.proposals[0].ndim != ndim:
            raise BayestriboError(
                f"{type(self).__name__}: {nwalkers} walkers of {ndim} parameters do not "
                f"form {g} ensembles of the proposals' {self.proposals[0].ndim} parameters"
            )
        random = model.random
        z, w, u = self.proposals[0].numbers(random, nwalkers)
        log_u = np.log(random.random_sample(nwalkers))
        coords = np.array(state.coords, dtype=np.float64)
        log_prob = np.array(state.log_prob, dtype=np.float64)
        q, factors = _proposals(coords, *self._stacked(), z, w, u)
        accepted = np.zeros(nwalkers, dtype=bool)
        step = _compiled_step(model)
        if step is None or not step(coords, log_prob, q, factors, log_u, accepted):
            new_log_prob = _log_prob(model, q)
            accepted = factors + new_log_prob - log_prob > log_u
            coords[accepted] = q[accepted]
            log_prob[accepted] = new_log_prob[accepted]
        state.coords = coords
        state.log_prob = log_prob
        return state, accepted


def _compiled_step(model):
    """The compiled independence step the sampler's log-probability offers (its
    ``independence_step`` attribute: ``step(coords, log_prob, q, factors, log_u,
    accepted) -> bool``, updating the first and last three in place by the rule of
    :meth:`GroupedIndependenceMove.propose`, False where it did nothing), or None."""
    function = getattr(model.log_prob_fn, "f", model.log_prob_fn)  # emcee's wrapper
    return getattr(function, "independence_step", None)


@numba.njit(cache=True, error_model="numpy")
def _proposals(coords, location, chol, df, flat, low, high, z, w, u):
    """Each walker's proposal from its ensemble's proposal (the walkers in blocks of
    equal size, one block an ensemble) and log q(x) − log q(y) (the t's normalising
    constant cancels)."""
    n, d = coords.shape
    g = location.shape[0]
    per = n // g
    q = np.empty((n, d))
    factors = np.empty(n)
    work = np.empty(d)
    for e in range(g):
        block = slice(e * per, (e + 1) * per)
        args = (location[e], chol[e], df[e], flat[e], low[e], high[e])
        q[block] = _draws(*args, z[block], w[block], u[block])
        for i in range(e * per, (e + 1) * per):
            factors[i] = _log_q_row(coords[i], *args, work) - _log_q_row(q[i], *args, work)
    return q, factors
