"""The start stage: the maximum a posteriori, its Laplace approximation and walkers.

:func:`find_start` takes a posterior (:mod:`bayestribo.inference.build`) and the
prepared run's decay and gives a :class:`Start`: the optimum (:func:`find_optimum`:
the maximum a posteriori, its covariance and the plausible μ_s/μ_k interval), then the
second pass of the increments' variances (:mod:`bayestribo.inference.reweight`) and
its optimum; the sample stage (:mod:`bayestribo.inference.chains`) draws its walkers
from it (:func:`initial_walkers`). How the optimum is found:

1. First guesses of ζ and μ_k: the Feeny-Liang peak decrement (Eq. 20-21) of the
   analysed window (falling back to ζ = 0.01 and a friction of 1 % of the amplitude),
   and the same decay rate put all into viscous damping or all into friction; the
   best optimum of the three is kept.
2. For the exact model, μ_s/μ_k is scanned over its prior's range: it decides at
   which turning point the model sticks, which the data pin down sharply, so the log
   density is a staircase in it. The ratio is set to the middle of the highest step
   (a plateau that often reaches the prior's upper bound), never to its edge: at the
   edge a small change of ζ or μ_k moves the stick to another turning point, and the
   optimiser stops there far below the maximum. Guesses outside a (user-narrowed)
   prior's support are moved inside it.
3. Levenberg-Marquardt least squares (MINPACK, :func:`scipy.optimize.leastsq`) of the
   standardized residuals over the continuous parameters, from which the Laplace
   covariance (JᵀJ)⁻¹ follows. Scan and least squares alternate until the log density
   stops rising or the scan leaves the ratio on its step, from each guess with the
   ratio at the middle of the highest step and at the middle of the ratio's range;
   the best optimum by log density is kept. A step across a bound of a prior's
   support is evaluated at the bound (with a residual for the excess), so that an
   optimum on the bound (a drag the data put at zero) is followed along it; where the
   log density's slope pins a coordinate to its bound, its Laplace variance is the
   exponential's, 1/g².
   For a law without a closed form with a drag (each evaluation integrates the
   motion) the starts run on a coarse model, 8 Runge-Kutta steps per half cycle (Π
   within ~1e-5 of Π(0), several times cheaper), from each guess with the ratio at the
   middle of the highest step only, each ending as soon as it comes
   within one Laplace sd of an optimum found before; the distinct optima within
   ``2 d + 10`` of the best coarse log density (``d`` the coarse model's error there)
   are each polished with the exact integrator, and the best is kept.
4. Every law nests the motion without dissipation: on a record that ends in motion
   (where that motion's Π is finite) it is evaluated, y0 at its least-squares value,
   and the least squares start from it too where it beats the best optimum
   (``_null_start``), so that no optimum is below it.
5. Walkers are drawn from that Gaussian (μ_s/μ_k uniformly over the ratios within
   0.5 of the best log density), each kept only if its log density is within
   ``d + 10`` of the best, so that every ensemble starts in the typical set.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares, leastsq

from bayestribo.errors import BayestriboError
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Normal
from bayestribo.inference.reweight import reweighted_posterior
from bayestribo.inference.surrogate import stop_ratios
from bayestribo.signal.decay import EnergyDecay

__all__ = [
    "Start",
    "better_optimum",
    "find_optimum",
    "find_start",
    "initial_walkers",
    "maximum_a_posteriori",
    "maximum_from",
    "maximum_from_starts",
    "refine",
]


def _first_guesses(decay: EnergyDecay, posterior: Posterior) -> list[dict[str, float]]:
    """Starting points: the Feeny-Liang estimate and its pure viscous / pure Coulomb ends.

    On long, lightly damped decays ζ and μ_k trade off almost perfectly (correlation
    beyond 0.999), and a local optimiser started at one end of that ridge can stop
    there; starting from both ends and from the peak estimate finds the right end.
    """
    amp = abs(posterior.likelihood.data.y0)
    zeta, mu_k = 0.01, 0.01 * amp
    try:
        from bayestribo.estimators.feeny_liang import feeny_liang

        est = feeny_liang(decay.peaks)
        if est.zeta is not None and 0.0 <= est.zeta < 0.3:
            zeta = float(est.zeta)
        friction = est.friction_displacement
        if friction is not None and friction > 0:
            mu_k = float(friction) / decay.scaling.length_scale
        elif friction is not None:
            # A decay faster than exponential at small amplitude (no friction to see):
            # start near the viscous end, not at a friction that stops the motion early.
            mu_k = 1e-6 * amp
    except (BayestriboError, ValueError, ArithmeticError):
        pass
    # The same decay per half cycle, all viscous (Eq. 34: a' = -ζa - 2μ_k/π) or all
    # Coulomb, evaluated at the mean amplitude.
    total = zeta + 2.0 * mu_k / (math.pi * max(0.5 * amp, 1e-300))
    guesses = [{"zeta": zeta, "mu_k": mu_k}]
    if posterior.friction:
        guesses.append({"zeta": min(total, 0.29), "mu_k": 1e-4 * mu_k})
        guesses.append(
            {"zeta": 1e-4 * zeta, "mu_k": min(0.5 * math.pi * total * 0.5 * amp, 0.24 * amp)}
        )
    if posterior.law.closed_form:
        return guesses
    return _law_guesses(posterior, total, amp)


def _law_guesses(posterior: Posterior, zeta_total: float, amp: float) -> list[dict[str, float]]:
    """First guesses of a law without a closed form: the whole decay in each sampled
    term in turn, and shared equally among them.

    The decay is the peak estimate's, as an equivalent damping ratio ζ at the mean
    amplitude A = |y0|/2: a dissipation per cycle ΔE(A) = 2πζA². Each term's first
    parameter scales its dissipation (every built-in term's ΔE is proportional to it),
    so the value that puts a share of ΔE(A) in that term follows from ΔE at 1; its
    other parameters start at the middle of their priors.
    """
    law = posterior.law
    lik = posterior.likelihood
    a_mid = 0.5 * amp
    target = 2.0 * math.pi * zeta_total * a_mid**2
    sampled = [t for t in law.terms if t.parameters and t.parameters[0].name in posterior.names]
    if not sampled:
        return [{}]
    base: dict[str, float] = {}
    for t in law.terms:
        for p in t.parameters[1:]:
            if p.name in posterior.names:
                low, high = _support(posterior.priors[p.name])
                base[p.name] = 0.5 * (low + high) if np.isfinite(high) else low + 1.0
    for t in sampled:
        low, high = _support(posterior.priors[t.parameters[0].name])
        start = max(low, t.parameters[0].null)  # no force: η of a friction that varies
        base[t.parameters[0].name] = start + 1e-4 * (high - start) if np.isfinite(high) else start

    def scaled(term_share: dict[str, float]) -> dict[str, float]:
        out = dict(base)
        for t, share in term_share.items():
            term = next(x for x in law.terms if x.name == t)
            first = term.parameters[0].name
            unit = dict(out, **{first: 1.0})
            values = {k: np.array([v]) for k, v in unit.items()}
            for p in term.parameters:
                values.setdefault(p.name, np.array([p.null]))
            per_unit = float(term.dissipation(a_mid, values, lik.reference_amplitude)[0])
            if per_unit > 0 and np.isfinite(per_unit):
                out[first] = share * target / per_unit
        return out

    guesses = [scaled({t.name: 1.0}) for t in sampled]
    if len(sampled) > 1:
        guesses.append(scaled({t.name: 1.0 / len(sampled) for t in sampled}))
    return guesses


def _vector(posterior: Posterior, values: dict[str, float]) -> NDArray:
    return np.array([values[n] for n in posterior.names], dtype=float)


def _support(prior: object) -> tuple[float, float]:
    """Bounds of a prior's support (infinite for unbounded priors)."""
    return float(getattr(prior, "low", -np.inf)), float(getattr(prior, "high", np.inf))


def _into_support(posterior: Posterior, values: dict[str, float]) -> dict[str, float]:
    """Move guesses inside their priors' support (a user may have narrowed a prior)."""
    out = dict(values)
    for name in posterior.names:
        low, high = _support(posterior.priors[name])
        if np.isfinite(low) and np.isfinite(high):
            margin = 1e-3 * (high - low)
            out[name] = float(np.clip(out[name], low + margin, high - margin))
    return out


def _ratio_grid(posterior: Posterior) -> NDArray:
    low, high = _support(posterior.priors["mu_s_ratio"])
    low = 1.0 if not np.isfinite(low) else max(low, 1.0)
    high = 10.0 if not np.isfinite(high) else high
    return np.linspace(low, high, 81)


def _scan_ratio(posterior: Posterior, theta: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """The log density at ``theta`` over the grid of μ_s/μ_k.

    For a law without a closed form (each evaluation integrates the motion) the
    likelihood is evaluated once per stick: Π changes with the ratio only where it
    crosses a turning point's |Y_n|/μ (:func:`bayestribo.inference.surrogate.
    stop_ratios`), and the prior's density of the ratio is added at each grid point.
    """
    i = posterior.names.index("mu_s_ratio")
    grid = _ratio_grid(posterior)
    rows = np.repeat(theta[None, :], grid.size, axis=0)
    rows[:, i] = grid
    likelihood = posterior.likelihood
    if likelihood.law.closed_form or likelihood.model != "exact":
        return rows, posterior(rows), grid
    params = posterior.physical(theta[None])["params"]
    edges = np.sort(stop_ratios(likelihood, {k: float(v[0]) for k, v in params.items()}))
    stick = np.searchsorted(edges, grid, side="right")
    first = np.unique(stick, return_index=True)[1]
    prior = posterior.priors["mu_s_ratio"]
    lp_first = posterior(rows[first])
    lp = np.empty(grid.size)
    for value, j, k in zip(lp_first, first, stick[first], strict=True):
        at = stick == k
        lp[at] = value - prior.logpdf(grid[j]) + prior.logpdf(grid[at])
    return rows, lp, grid


def _plateau_middle(posterior: Posterior, theta: NDArray) -> NDArray:
    """``theta`` with μ_s/μ_k at the middle of the highest step of its scan.

    The log density is piecewise constant in the ratio (it decides only at which
    turning point the model sticks); the middle of the contiguous run of grid ratios
    at the maximum is the point farthest from a change of the stick.
    """
    rows, lp, _ = _scan_ratio(posterior, theta)
    if not np.any(np.isfinite(lp)):
        return theta
    k = int(np.argmax(lp))
    top = lp >= lp[k] - 1e-6 * max(1.0, abs(float(lp[k])))
    low, high = k, k
    while low > 0 and top[low - 1]:
        low -= 1
    while high < lp.size - 1 and top[high + 1]:
        high += 1
    return rows[(low + high) // 2]


#: Rounds of ratio scan and least squares from one starting point.
_MAX_ROUNDS = 4
#: √ε of doubles, the relative step of the forward differences (scipy's "2-point").
_SQRT_EPS = math.sqrt(float(np.finfo(float).eps))


Optimum = tuple[NDArray, NDArray, float]


class _Joined(Exception):
    """A start came within reach of an optimum found before (:func:`_optimise`)."""

    def __init__(self, optimum: Optimum) -> None:
        super().__init__()
        self.optimum = optimum


def _joins(posterior: Posterior, found: list[Optimum]) -> Callable[[NDArray], None] | None:
    """A check for :func:`refine` that raises :class:`_Joined` at a point within one
    Laplace sd of an optimum of ``found`` in every continuous coordinate, with μ_s/μ_k
    equal (the same step): from there the least squares would end at that optimum."""
    if not found:
        return None
    ratio = posterior.names.index("mu_s_ratio") if "mu_s_ratio" in posterior.names else None
    known = [(t, np.sqrt(np.clip(np.diag(c), 0.0, None)), (t, c, lp)) for t, c, lp in found]
    known = [k for k in known if np.isfinite(k[2][2])]

    def check(theta: NDArray) -> None:
        for other, sd, optimum in known:
            if _same_optimum(theta, other, sd, ratio):
                raise _Joined(optimum)

    return check


def _optimise(
    posterior: Posterior,
    guess: dict[str, float],
    ratio: float | None = None,
    found: list[Optimum] | None = None,
) -> Optimum:
    """Optimum from one guess and its Laplace covariance and log density.

    Parameters
    ----------
    posterior : Posterior
        The posterior to maximise.
    guess : dict
        Values of ζ and μ_k (and any other sampled coordinates) to start from.
    ratio : float, optional
        Start with μ_s/μ_k here; default: the middle of the highest step of its scan
        at the guess.
    found : list, optional
        Optima found from other starts: when the least squares come within one
        Laplace sd of one of them (on the same step of μ_s/μ_k), that optimum is
        returned at once (the coarse multi-start of :func:`maximum_a_posteriori`).

    Returns
    -------
    theta : ndarray
        The optimum (μ_s/μ_k at the middle of its highest step there).
    cov : ndarray
        Laplace covariance (see :func:`refine`).
    log_density : float
        Log posterior density at ``theta``.
    """
    names = posterior.names
    values = {
        **_nulls(posterior),
        "y0": posterior.likelihood.data.y0,
        "mu_s_ratio": 1.2 if ratio is None else ratio,
        **guess,
    }
    theta = _vector(posterior, _into_support(posterior, {n: values[n] for n in names}))
    has_ratio = "mu_s_ratio" in names
    if has_ratio and ratio is None:
        theta = _plateau_middle(posterior, theta)
    near = _joins(posterior, found or [])
    try:
        return _rounds(posterior, theta, has_ratio, near)
    except _Joined as joined:
        return joined.optimum


def _nulls(posterior: Posterior) -> dict[str, float]:
    """Every law parameter at its null (no force), ζ at zero and the discrepancy
    scales negligible: what a start does not set otherwise."""
    return {
        **{p.name: p.null for p in posterior.law.parameters},
        "zeta": 0.0,
        "log10_discrepancy": -5.0,
        "log10_shape": -5.0,
    }


def _rounds(
    posterior: Posterior,
    theta: NDArray,
    has_ratio: bool,
    near: Callable[[NDArray], None] | None,
) -> Optimum:
    """Least squares and ratio scans in turn from ``theta`` (see :func:`_optimise`)."""
    names = posterior.names
    best: Optimum | None = None
    for _ in range(_MAX_ROUNDS if has_ratio else 1):
        if not np.isfinite(posterior(theta[None])[0]):
            break
        if near is not None:
            near(theta)
        opt, cov = refine(posterior, theta, near=near)
        lp = float(posterior(opt[None])[0])
        stepped = False
        if has_ratio:
            opt = _plateau_middle(posterior, opt)
            before, lp = lp, float(posterior(opt[None])[0])
            stepped = lp > before + 1e-9 * max(1.0, abs(before))
        if best is not None and not lp > best[2] + 1e-3:
            break
        best = (opt, cov, lp)
        if not stepped:
            # The ratio stayed on its step (the same sticks, the same density): the
            # least squares would start at its own optimum.
            break
        theta = opt
    if best is None:
        return theta, np.zeros((len(names), len(names))), -np.inf
    return best


#: How near a bound, in units of each coordinate's step of the least squares (1e-3 of
#: its start, at least 1e-6), an optimum is on it: the least squares' own tolerance on
#: the step, 1e-8. An optimum of μ_k at 1.7e-21 above its bound of zero (a viscous
#: seismometer record, after a change in the last digits of its increments' variances)
#: was taken off the bound: the Jacobian's column of a friction a step of 1e-14 does
#: not move made the Laplace covariance singular, and its fallback (1e-3 of each value)
#: started the walkers in a ball so small that the sampler took three times the steps.
BOUND_TOUCH = 1e-8


def refine(
    posterior: Posterior,
    theta: NDArray,
    *,
    near: Callable[[NDArray], None] | None = None,
) -> tuple[NDArray, NDArray]:
    """Least-squares MAP of the continuous coordinates from ``theta``, and its Laplace
    covariance (μ_s/μ_k and the discrepancy held at their values in ``theta``).

    Parameters
    ----------
    posterior : Posterior
        Any object with ``names``, ``priors``, ``likelihood``, a vectorised
        ``__call__`` and ``standardized_residuals`` (e.g. a posterior with some
        coordinates pinned).
    theta : ndarray
        Starting point in sampling coordinates, with a finite posterior density.
    near : callable, optional
        Called with each point (sampling coordinates) at which the residuals are
        evaluated; an exception it raises ends the least squares and propagates.

    Returns
    -------
    theta : ndarray
        The optimum.
    cov : ndarray
        Laplace covariance (zero rows and columns for the held coordinates).
    """
    names = posterior.names
    theta = np.array(theta, dtype=float)
    held = ("mu_s_ratio", "log10_discrepancy", "log10_shape")
    free = [i for i, n in enumerate(names) if n not in held]
    scale = np.array([max(abs(theta[i]), 1e-3) for i in free]) * 1e-3
    # the increments' residuals and the linear nuisances' (conditional mean over prior
    # sd: the likelihood's χ² is their sum of squares, however far a misfit pulls one)
    size = posterior.residual_size
    # Gaussian priors enter the least squares as residuals (θ - μ)/σ: a MAP, not an MLE.
    gaussian = [
        (j, posterior.priors[names[i]])
        for j, i in enumerate(free)
        if isinstance(posterior.priors[names[i]], Normal)
    ]

    low, high = _free_bounds(posterior, [names[i] for i in free])
    bounded = np.flatnonzero(np.isfinite(low) | np.isfinite(high))
    # the compiled prior where the posterior has one (it is evaluated at every point)
    log_prior = getattr(posterior, "log_prior", posterior.priors.logpdf)

    # the fixed parts of every evaluation (the least squares make a few hundred)
    at = np.asarray(free)
    start_free = theta[at]
    n_rows = size + len(gaussian) + bounded.size
    gauss_at = at[[j for j, _ in gaussian]]
    gauss_mu = np.array([p.mu for _, p in gaussian])
    gauss_sigma = np.array([p.sigma for _, p in gaussian])

    # the same rows in one compiled call where the posterior offers it
    compiled = getattr(posterior, "residual_rows", None)
    gauss_args = (gauss_at.astype(np.int64), gauss_mu.astype(float), gauss_sigma.astype(float))
    at_int = at.astype(np.int64)

    def residual_rows(u: NDArray) -> NDArray:
        """Residuals at the rows ``u`` (k, free) in one call of the posterior."""
        if compiled is not None:
            out = compiled(
                u, theta, at_int, start_free, scale, low, high, bounded, *gauss_args, size
            )
            if out is not None:
                return out
        th = np.repeat(theta[None], u.shape[0], axis=0)
        part = start_free + u * scale
        out = np.full((u.shape[0], n_rows), 1e6)
        # A step across a bound of the support is evaluated at the bound (the nearest
        # point inside), plus a residual for each coordinate beyond it: the optimiser
        # keeps moving the others along the bound where the optimum sits on it (a drag
        # piled at zero), instead of stalling at a wall of rejected steps.
        if bounded.size:
            inside = np.minimum(np.maximum(part, low), high)
            out[:, size + len(gaussian) :] = ((part - inside) / scale)[:, bounded]
            part = inside
        th[:, at] = part
        # inside the priors' support, a row whose residuals are not all finite is
        # outside the law's domain (the model cannot move there): both get 1e6. The
        # model is evaluated once per row (the law's integrator where it has no
        # closed form), not once for the density and again for the residuals.
        ok = np.isfinite(log_prior(th))
        every = bool(ok.all())
        if every or ok.any():
            resid = posterior.standardized_residuals(th if every else th[ok], nuisances=True)
            finite = np.isfinite(resid).all(axis=1)
            ok[ok] = finite
            out[ok, :size] = resid if every and finite.all() else resid[finite]
            if gaussian:
                out[ok, size : size + len(gaussian)] = (
                    th[ok][:, gauss_at] - gauss_mu
                ) / gauss_sigma
        return out

    last: list[NDArray] = []

    def residuals(u: NDArray) -> NDArray:
        u = np.array(u, dtype=float)
        if near is not None:
            point = theta.copy()
            point[at] = start_free + u * scale
            near(point)
        f = residual_rows(u[None])[0]
        last[:] = [u, f]
        return f

    def jacobian(u: NDArray, sign: NDArray | None = None) -> NDArray:
        # forward differences as scipy's "2-point" takes them (step √ε max(1, |u|)),
        # every shifted point in one call of the posterior
        u = np.asarray(u, dtype=float)
        if sign is None:
            sign = np.where(u >= 0, 1.0, -1.0)
        h = _SQRT_EPS * sign * np.maximum(1.0, abs(u))
        h = (u + h) - u
        if last and last[0].shape == u.shape and bool((last[0] == u).all()):
            f0 = last[1]
            shifted = residual_rows(u[None, :] + np.diag(h))
        else:
            both = residual_rows(np.vstack([u[None, :], u[None, :] + np.diag(h)]))
            f0, shifted = both[0], both[1:]
        return ((shifted - f0[None, :]) / h[:, None]).T

    # Levenberg-Marquardt (MINPACK) needs at least as many residuals as unknowns; it
    # follows the ζ-μ_k ridge in a few iterations where the trust-region method
    # crawls along it (two to four times the time on the bundled run).
    method = "lm" if size + len(gaussian) + bounded.size >= len(free) else "trf"
    x, fun, jac = _least_squares(residuals, jacobian, len(free), method)
    found = theta[free] + x * scale
    # within the least squares' own tolerance of a bound is on it (module constant)
    touch = BOUND_TOUCH * scale
    at_low, at_high = found <= low + touch, found >= high - touch
    on_bound = at_low | at_high
    if np.any(on_bound):
        # stopped on or beyond a bound: the optimum is on it; its Jacobian is taken
        # there, with the differences stepping into the support (the optimiser's last
        # one may be from beyond the bound, where the residuals do not change)
        found = np.where(at_low, low, np.where(at_high, high, found))
        u = (found - theta[free]) / scale
        fun = residual_rows(u[None])[0]
        jac = jacobian(u, np.where(found >= high, -1.0, 1.0))
    theta[free] = found
    # the Laplace covariance from the residuals of the data and the Gaussian priors
    rows = size + len(gaussian)
    jac, fun = jac[:rows] / scale[None, :], fun[:rows]
    try:
        cov_free = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        cov_free = np.diag((1e-3 * np.maximum(np.abs(theta[free]), 1e-6)) ** 2)
    cov_free = _pinned_by_slope(cov_free, jac, fun, on_bound, found >= high)
    cov = np.zeros((len(names), len(names)))
    cov[np.ix_(free, free)] = cov_free
    return _measured_at_bounds(posterior, theta, cov, free, low, high, jac)


def _least_squares(
    residuals: Callable[[NDArray], NDArray],
    jacobian: Callable[[NDArray], NDArray],
    n: int,
    method: str,
) -> tuple[NDArray, NDArray, NDArray]:
    """The least squares of :func:`refine` from zero: the solution, its residuals and
    their Jacobian there.

    Levenberg-Marquardt (``method="lm"``) is MINPACK's ``lmder`` called as
    :func:`scipy.optimize.least_squares` calls it (its default tolerances of 1e-8, at
    most 100 n evaluations, the steps scaled by the Jacobian's columns), through
    :func:`scipy.optimize.leastsq`, whose wrapper adds a few microseconds to each of
    the few hundred evaluations of a fit where ``least_squares``' adds tens: the same
    iterates and solution. Otherwise ``least_squares``' trust-region method.
    """
    x0 = np.zeros(n)
    if method != "lm":
        sol = least_squares(residuals, x0, jac=jacobian, x_scale="jac", method=method)
        return sol.x, sol.fun, sol.jac
    tol = 1e-8
    x, _, info, _, _ = leastsq(
        residuals,
        x0,
        Dfun=jacobian,
        full_output=True,
        ftol=tol,
        xtol=tol,
        gtol=tol,
        maxfev=100 * n,
        factor=100.0,
        diag=None,
    )
    return x, info["fvec"], jacobian(x)


#: Steps into the support at which the log density is evaluated from a bound, in units
#: of the Laplace standard deviation: 1 down to 1e-8.
_LADDER = 10.0 ** -np.arange(0, 9)


def _measured_at_bounds(
    posterior: Posterior,
    theta: NDArray,
    cov: NDArray,
    free: list[int],
    low: NDArray,
    high: NDArray,
    jac: NDArray,
) -> tuple[NDArray, NDArray]:
    """The optimum and Laplace covariance with the width of each coordinate whose
    bound lies within its Laplace reach measured on the log density itself.

    A coordinate within half a unit of log density of a bound of its support (a drag
    the data put at zero) is not described by the curvature of finite differences: the
    difference is taken a rounding error from the bound, where an integrated Π's own
    error (~1e-11 of Π) can swamp the change of a weak coordinate, and the posterior
    there is an exponential or a half-Gaussian, not a Gaussian. The log density is
    evaluated along the coordinate from the bound into the support, at
    :data:`_LADDER` times its Laplace sd, the others held; where it falls by 0.5 from
    the bound at a step w within that sd, the optimum is put on the bound and the
    coordinate gets the standard deviation 2w (the exponential's 1/g where the fall is
    linear, g = 0.5/w; twice a half-Gaussian's scale), uncorrelated with the others,
    whose covariance becomes their Laplace covariance with it held there (from the
    residuals' Jacobian ``jac`` in the free coordinates' units, rows × free).
    Elsewhere nothing changes.
    """
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    widths: dict[int, float] = {}
    for j, i in enumerate(free):
        for bound, inward in ((low[j], 1.0), (high[j], -1.0)):
            if not np.isfinite(bound) or not sd[i] > 0:
                continue
            if abs(theta[i] - bound) > 3.0 * sd[i]:
                continue
            rows = np.repeat(theta[None], _LADDER.size + 2, axis=0)
            rows[1, i] = bound
            rows[2:, i] = bound + inward * sd[i] * _LADDER
            lp = posterior(rows)
            if not np.all(np.isfinite(lp[:2])) or lp[0] > lp[1] + 0.5:
                continue  # the optimum is inside, half a unit above the bound
            fall = lp[1] - lp[2:][::-1]  # from the smallest step to the largest
            steps = (sd[i] * _LADDER)[::-1]
            if not np.all(np.isfinite(fall)) or np.any(fall < -1e-6) or fall[-1] < 0.5:
                continue  # rises into the support, or falls by less than 0.5 within sd
            k = int(np.argmax(fall >= 0.5))
            if k == 0:
                width = steps[0]
            else:
                # log-linear between the two steps that straddle a fall of 0.5
                x0, x1 = np.log(steps[k - 1]), np.log(steps[k])
                f0, f1 = fall[k - 1], fall[k]
                width = float(np.exp(x0 + (0.5 - f0) / (f1 - f0) * (x1 - x0)))
            theta = theta.copy()
            theta[i] = bound
            widths[j] = width
            break
    if not widths:
        return theta, cov
    rest = [j for j in range(len(free)) if j not in widths]
    out = np.zeros_like(cov)
    if rest:
        idx = [free[j] for j in rest]
        try:
            out[np.ix_(idx, idx)] = np.linalg.inv(jac[:, rest].T @ jac[:, rest])
        except np.linalg.LinAlgError:
            out[np.ix_(idx, idx)] = cov[np.ix_(idx, idx)]
    for j, width in widths.items():
        out[free[j], free[j]] = (2.0 * width) ** 2
    return theta, out


def _pinned_by_slope(
    cov: NDArray, jac: NDArray, fun: NDArray, on_bound: NDArray, upper: NDArray
) -> NDArray:
    """The Laplace covariance with the coordinates an optimum on a bound is pinned to
    by the slope of the log density there.

    At a bound the log density need not be flat: where it falls into the support with
    slope g (``-(Jᵀ f)``, the residuals ``fun`` and their Jacobian ``jac`` at the
    optimum), the posterior of that coordinate is an exponential of scale 1/|g|, which
    can be far narrower than the curvature's standard deviation (a drag piled at zero
    by a law that misfits: 1e-11 against 3e-7). Such a coordinate gets the variance
    1/g² and no correlation; the others their covariance with it held at the bound.
    """
    pinned = np.zeros(on_bound.size, dtype=bool)
    slope = -(jac.T @ fun)
    for k in np.flatnonzero(on_bound):
        inward = -slope[k] if upper[k] else slope[k]
        if inward < 0 and 1.0 / abs(inward) < math.sqrt(max(cov[k, k], 0.0)):
            pinned[k] = True
    if not np.any(pinned):
        return cov
    out = np.zeros_like(cov)
    rest = ~pinned
    if np.any(rest):
        try:
            out[np.ix_(rest, rest)] = np.linalg.inv(jac[:, rest].T @ jac[:, rest])
        except np.linalg.LinAlgError:
            out[np.ix_(rest, rest)] = cov[np.ix_(rest, rest)]
    out[pinned, pinned] = 1.0 / slope[pinned] ** 2
    return out


def _free_bounds(posterior: Posterior, names: list[str]) -> tuple[NDArray, NDArray]:
    """Lower and upper bounds of the priors' support of ``names`` (infinite where
    unbounded)."""
    bounds = np.array([_support(posterior.priors[n]) for n in names], dtype=float)
    bounds = bounds.reshape(len(names), 2)
    return bounds[:, 0], bounds[:, 1]


def maximum_a_posteriori(
    posterior: Posterior, decay: EnergyDecay
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """Maximum a posteriori, Laplace covariance and the plausible μ_s/μ_k interval.

    Parameters
    ----------
    posterior : Posterior
        The posterior to maximise.
    decay : EnergyDecay
        The run's energy decay (its peaks give the first guesses).

    Returns
    -------
    theta : ndarray
        The MAP in sampling coordinates, μ_s/μ_k at the middle of the highest step of
        its scan (the best of the optima from each first guess, with the ratio
        started at that step's middle and, for a law with a closed form or without
        a drag, at the middle of the ratio's range).
    cov : ndarray
        Laplace covariance of the continuous coordinates (ratio excluded: its row and
        column are zero).
    ratio_range : tuple or None
        Range of μ_s/μ_k within 0.5 of the best log density (exact model with friction).
    """
    names = posterior.names
    guesses = _first_guesses(decay, posterior)
    starts: list[tuple[dict[str, float], float | None]] = [(g, None) for g in guesses]
    coarse = _coarse(posterior)
    if "mu_s_ratio" in names and coarse is None:
        # the same guesses with the ratio at the middle of its range: a scan at a poor
        # guess can put the ratio where the optimiser cannot leave the wrong stick
        # (viscous+coulomb on filtered 100 kHz records). Not on the coarse model of a
        # law with a drag, whose guesses put the decay in each term in turn and then
        # shared: there they ended at the first guesses' optimum on every record tried
        # (the bundled and five real recordings under coulomb+power, coulomb+quadratic
        # and viscous+coulomb+quadratic, and 20 simulated records each of
        # coulomb+power and viscous+coulomb+quadratic at 10x noise: within 0.1 Laplace
        # sd, the log density within 0.002) at half the multi-start's cost
        middle = float(np.median(_ratio_grid(posterior)))
        starts += [(g, middle) for g in guesses]
    if coarse is None:
        optima = [_optimise(posterior, guess, ratio) for guess, ratio in starts]
    else:
        rough: list[Optimum] = []
        for guess, ratio in starts:
            # a start that comes within reach of an optimum found before ends there
            rough.append(_optimise(coarse, guess, ratio, found=rough))
        optima = [_polish(posterior, t) for t in _candidates(posterior, rough)]
    best_lp = max(lp for _, _, lp in optima)
    null = _null_start(posterior, best_lp)
    if null is not None:
        # from the point itself: the guesses' margin inside a prior's bounds (1e-3 of
        # its range) would put a drag at zero back at a drag of that size
        optima.append(_rounds(posterior, null, "mu_s_ratio" in names, None))
    theta, cov, _ = optima[int(np.argmax([lp for _, _, lp in optima]))]
    return theta, cov, _ratio_range(posterior, theta)


def _null_start(posterior: Posterior, best_lp: float) -> NDArray | None:
    """A start (sampling coordinates) with every term of the law at its null (no
    dissipation) and y0 at its least-squares value there, when that point's log
    density beats ``best_lp``; else None.

    Every law nests the motion without dissipation, so its optimum is at least as good
    as that motion's. The first guesses put the peaks' decay into the law's terms; on
    a record whose increments the motion without a loss fits better than any decay
    (the energy not falling, or rising, along the window: a gyroscope's record of a
    wheel still driven), the least squares from there stopped on a prior's bound far
    below it (``hysteretic`` at η = 0.45 with a log density 9·10⁴ below the null
    motion's, ``quadratic`` 2·10⁵ below). The check costs three evaluations of the
    posterior (none on a record that ends at rest); the least squares from the null
    are run only where it wins.
    """
    data = posterior.likelihood.data
    if getattr(data, "motion_ended", True):
        # a motion without dissipation never ends: its Π past a record that ends at
        # rest is infinite, never the optimum
        return None
    names = posterior.names
    values = _nulls(posterior)
    if "mu_s_ratio" in names:
        values["mu_s_ratio"] = float(np.median(_ratio_grid(posterior)))
    row = _vector(posterior, {n: values.get(n, 0.0) for n in names})
    for j, n in enumerate(names):
        # on the support, its ends included (a null is often a prior's bound)
        low, high = _support(posterior.priors[n])
        row[j] = min(max(row[j], low), high)
    if "y0" in names:
        i = names.index("y0")
        y0 = float(data.y0)
        if not (np.isfinite(y0) and y0 != 0.0):
            return None
        # Without a loss the energy is constant and the model's increments scale as
        # y0² (exactly on a linear spring): the residuals at two amplitudes give the
        # best y0² by linear least squares, the linear nuisances' rows included
        rows = np.repeat(row[None, :], 2, axis=0)
        rows[:, i] = [y0, 0.5 * y0]
        with np.errstate(invalid="ignore", over="ignore"):
            r = np.asarray(posterior.standardized_residuals(rows, nuisances=True), dtype=float)
            b = (r[0] - r[1]) / (0.25 * y0 * y0 - y0 * y0)
            a = r[0] + y0 * y0 * b
            bb = float(b @ b)
            s = float(a @ b) / bb if bb > 0 else math.nan
        if not (math.isfinite(s) and s > 0.0):
            return None
        row[i] = math.copysign(math.sqrt(s), y0)
    lp_null = float(posterior(row[None])[0])
    if not (np.isfinite(lp_null) and lp_null > best_lp):
        return None
    for t in posterior.law.terms:
        first = t.parameters[0].name if t.parameters else None
        if first in names:
            j = names.index(first)
            # a null inside the prior's support may be the edge of the law's domain
            # (η = 0 of a friction that varies with amplitude, alone), which holds a
            # least squares whose differences step outside it: a little off it, as the
            # first guesses' base (a null on the prior's bound is followed along it)
            low, high = _support(posterior.priors[first])
            if low < row[j] and np.isfinite(high):
                row[j] += 1e-4 * (high - row[j])
    return row


#: Runge-Kutta steps per half cycle of the coarse model of a law without a closed form
#: (Π within ~1e-5 of Π(0) where the exact model's per-half-cycle choice, 32 to 384
#: steps, holds it within ~2e-9): several times cheaper, with the same sticks and the
#: same optima to within a few of their widths, which the exact model then polishes.
COARSE_STEPS = 8


def _coarse(posterior: Posterior) -> Posterior | None:
    """The posterior with the law's Π from :data:`COARSE_STEPS` Runge-Kutta steps per
    half cycle, or None when the law has a closed form, no drag (its arcs need no
    Runge-Kutta steps: the coarse model would be the exact one) or the model is not the
    exact integrator: the multi-start then runs on the posterior itself."""
    lik = posterior.likelihood
    if lik.law.closed_form or lik.model != "exact" or type(lik) is not PiLikelihood:
        return None
    if not any(t.kind == "drag" for t in lik.law.terms):
        return None
    return replace(posterior, likelihood=replace(lik, steps=COARSE_STEPS))


def _candidates(posterior: Posterior, rough: list[Optimum]) -> list[NDArray]:
    """The optima of the coarse multi-start worth polishing with the exact model.

    Optima within a Laplace standard deviation of a better one in every continuous
    coordinate and on the same step of μ_s/μ_k are the same optimum. Of the distinct
    ones, those whose coarse log density is within ``2 d + 10`` of the best's are kept,
    ``d`` the coarse model's error of the log density at the best (the exact log
    density there against the coarse): an optimum further below cannot come out on top
    under the exact model.
    """
    order = sorted(range(len(rough)), key=lambda k: -rough[k][2])
    finite = [k for k in order if np.isfinite(rough[k][2])]
    if not finite:
        return [rough[order[0]][0]]
    best_theta, _, best_lp = rough[finite[0]]
    error = abs(float(posterior(best_theta[None])[0]) - best_lp)
    if not np.isfinite(error):
        error = math.inf
    ratio = posterior.names.index("mu_s_ratio") if "mu_s_ratio" in posterior.names else None
    kept: list[tuple[NDArray, NDArray]] = []
    for k in finite:
        theta, cov, lp = rough[k]
        if lp < best_lp - (2.0 * error + 10.0):
            break
        sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        if not any(_same_optimum(theta, other, other_sd, ratio) for other, other_sd in kept):
            kept.append((theta, sd))
    return [theta for theta, _ in kept]


def _same_optimum(theta: NDArray, other: NDArray, sd: NDArray, ratio: int | None) -> bool:
    """``theta`` within one Laplace sd ``sd`` of the optimum ``other`` in every
    continuous coordinate (those with sd > 0), with μ_s/μ_k equal (its column
    ``ratio``: the middle of the same step)."""
    if ratio is not None and theta[ratio] != other[ratio]:
        return False
    free = sd > 0
    return bool(np.all(np.abs(theta[free] - other[free]) <= sd[free]))


def _polish(posterior: Posterior, theta: NDArray) -> tuple[NDArray, NDArray, float]:
    """The optimum of ``posterior`` from a coarse model's optimum ``theta`` (μ_s/μ_k
    kept on its step there), with its Laplace covariance and log density."""
    start = dict(zip(posterior.names, np.asarray(theta, dtype=float).tolist(), strict=True))
    return _optimise(posterior, start, ratio=start.get("mu_s_ratio"))


def _ratio_range(posterior: Posterior, theta: NDArray) -> tuple[float, float] | None:
    """Range of μ_s/μ_k within 0.5 of the best log density of its scan at ``theta``."""
    if "mu_s_ratio" not in posterior.names:
        return None
    _, lp, grid = _scan_ratio(posterior, theta)
    top = np.max(lp)
    if not np.isfinite(top):
        return None
    good = grid[lp >= top - 0.5]
    step = grid[1] - grid[0]
    return (max(grid[0], good.min() - step), min(grid[-1], good.max() + step))


def maximum_from(
    posterior: Posterior, theta: NDArray, decay: EnergyDecay
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """Maximum a posteriori from one known starting point, e.g. the optimum of the
    same law on the run prepared in another frame (a nonlinear law's fit,
    :func:`bayestribo.inference.fitting.fit`), which moves it by far less than the
    first guesses of :func:`maximum_a_posteriori` are apart.

    Parameters
    ----------
    posterior : Posterior
        The posterior to maximise.
    theta : ndarray
        Starting point in sampling coordinates (μ_s/μ_k kept on its step there).
    decay : EnergyDecay
        The run's energy decay: the first guesses of :func:`maximum_a_posteriori`,
        which this falls back to when the log density at the optimum from ``theta``
        is not finite.

    Returns
    -------
    theta, cov, ratio_range
        As :func:`maximum_a_posteriori`.
    """
    start = dict(zip(posterior.names, np.asarray(theta, dtype=float).tolist(), strict=True))
    return maximum_from_starts(posterior, [start], decay)


def maximum_from_starts(
    posterior: Posterior, starts: Sequence[Mapping[str, float]], decay: EnergyDecay
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """Maximum a posteriori from known starting points: the best of the optima the
    least squares reach from each (μ_s/μ_k started on its step at each, then scanned
    as :func:`maximum_a_posteriori` does), e.g. a law's nested laws' optima
    (:func:`bayestribo.inference.reduction.nested_starts`).

    Parameters
    ----------
    posterior : Posterior
        The posterior to maximise.
    starts : sequence of mapping
        Starting points, each the value of every sampled coordinate by name.
    decay : EnergyDecay
        The run's energy decay: the first guesses of :func:`maximum_a_posteriori`,
        which this falls back to when the log density at every optimum is not finite.

    Returns
    -------
    theta, cov, ratio_range
        As :func:`maximum_a_posteriori`; the first start's optimum where two are as
        good.
    """
    best: Optimum | None = None
    for start in starts:
        values = {name: float(start[name]) for name in posterior.names}
        found = _optimise(posterior, values, ratio=values.get("mu_s_ratio"))
        if not np.isfinite(found[2]):
            continue  # a start whose optimum has no density leaves the others to win
        if best is None or found[2] > best[2]:
            best = found
    if best is None or not np.isfinite(best[2]):
        return maximum_a_posteriori(posterior, decay)
    return best[0], best[1], _ratio_range(posterior, best[0])


def initial_walkers(
    posterior: Posterior,
    theta: NDArray,
    cov: NDArray,
    ratio_range: tuple[float, float] | None,
    n_ensembles: int,
    n_walkers: int,
    rng: np.random.Generator,
    max_tries: int = 200,
) -> NDArray:
    """Starting positions (n_ensembles, n_walkers, d) in the typical set.

    Raises
    ------
    BayestriboError
        If no starting point with a finite posterior density is found (the data and
        the model disagree everywhere near the optimum).
    """
    names = posterior.names
    d = len(names)
    best = posterior(theta[None])[0]
    if not np.isfinite(best):
        raise BayestriboError(
            "the posterior density is zero at the optimum: the model cannot reproduce "
            "this record with the given priors"
        )
    need = n_ensembles * n_walkers
    kept: list[NDArray] = []
    jitter = np.sqrt(np.maximum(np.diag(cov), 0.0))
    for attempt in range(max_tries):
        if attempt and attempt % 20 == 0 and len(kept) < need:
            # The Laplace covariance overstates the spread where the law misfits the
            # record (the log density is far steeper than its quadratic approximation
            # suggests, beyond a few widths): draw closer to the optimum.
            cov = 0.25 * cov
            jitter = 0.5 * jitter
        draws = rng.multivariate_normal(theta, cov, size=2 * need, method="eigh")
        for i, name in enumerate(names):
            if name == "mu_s_ratio" and ratio_range is not None:
                draws[:, i] = rng.uniform(*ratio_range, size=draws.shape[0])
            elif name in ("log10_discrepancy", "log10_shape"):
                draws[:, i] = theta[i] + rng.normal(0.0, 0.5, size=draws.shape[0])
            elif jitter[i] == 0.0:
                draws[:, i] = theta[i] * (1.0 + 1e-6 * rng.standard_normal(draws.shape[0]))
        lp = posterior(draws)
        kept.extend(draws[np.isfinite(lp) & (lp >= best - (d + 10.0))])
        if len(kept) >= need:
            break
    if len(kept) < need:
        # No Gaussian about the optimum holds enough of the typical set (the optimum of
        # a law that misfits, on a corner of the support or a step of μ_s/μ_k): the
        # rest start in a tiny ball about the optimum itself, and the burn-in spreads
        # them (the sampler's checks say whether it did).
        ball = theta * (1.0 + 1e-8 * rng.standard_normal((4 * need, d)))
        ball = np.where(theta == 0.0, 0.0, ball)
        lp = posterior(ball)
        kept.extend(ball[np.isfinite(lp)][: need - len(kept)])
    if len(kept) < need:
        raise BayestriboError(
            f"found only {len(kept)} of {need} starting points near the optimum; the "
            "posterior may be multimodal or the priors too narrow"
        )
    return np.asarray(kept[:need]).reshape(n_ensembles, n_walkers, d)


def find_optimum(
    posterior: Posterior,
    decay: EnergyDecay,
    also_start_at: Mapping[str, float] | None = None,
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """The maximum a posteriori of step 3, its Laplace covariance and the plausible
    μ_s/μ_k interval (:func:`bayestribo.inference.start.maximum_a_posteriori`), with a
    second starting point of the optimiser kept if its optimum is better.

    Parameters
    ----------
    posterior : Posterior
        From :func:`build_posterior`.
    decay : EnergyDecay
        The run's energy decay (its peaks give the first guesses of the optimiser).
    also_start_at : mapping, optional
        Values of the sampled coordinates to start the optimiser from as well (e.g.
        the optimum of a nested law).

    Returns
    -------
    theta : ndarray
        The optimum in sampling coordinates.
    cov : ndarray
        Its Laplace covariance.
    ratio_range : tuple or None
        The plausible μ_s/μ_k interval (None for a law without static friction).
    """
    return better_optimum(posterior, maximum_a_posteriori(posterior, decay), also_start_at)


def better_optimum(
    posterior: Posterior,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None],
    also_start_at: Mapping[str, float] | None,
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """``optimum``, or the optimum refined from ``also_start_at`` when its posterior
    density is higher (the μ_s/μ_k interval kept)."""
    theta, cov, ratio_range = optimum
    if also_start_at is not None:
        start = np.array([also_start_at[n] for n in posterior.names], dtype=float)
        if np.isfinite(posterior(start[None])[0]):
            alt, alt_cov = refine(posterior, start)
            if posterior(alt[None])[0] > posterior(theta[None])[0]:
                theta, cov = alt, alt_cov
    return theta, cov, ratio_range


@dataclass(frozen=True)
class Start:
    """Where the sampler starts: the posterior it samples and that posterior's optimum.

    Attributes
    ----------
    posterior : Posterior
        The posterior to sample (the second pass's, :mod:`bayestribo.inference.reweight`,
        where it was made).
    theta : ndarray
        Its maximum a posteriori in sampling coordinates.
    cov : ndarray
        Its Laplace covariance.
    ratio_range : tuple or None
        The plausible μ_s/μ_k interval (None for a law without static friction).
    """

    posterior: Posterior
    theta: NDArray
    cov: NDArray
    ratio_range: tuple[float, float] | None


def find_start(
    posterior: Posterior,
    decay: EnergyDecay,
    *,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None] | None = None,
    also_start_at: Mapping[str, float] | None = None,
    reweight: bool = True,
) -> Start:
    """The start stage: the optimum, then the second pass and its optimum.

    Parameters
    ----------
    posterior : Posterior
        From :func:`bayestribo.inference.build.build_posterior`.
    decay : EnergyDecay
        The run's energy decay (its peaks give the first guesses of the optimiser).
    optimum : tuple, optional
        The maximum a posteriori, its Laplace covariance and the plausible μ_s/μ_k
        interval when they are known already (:func:`maximum_from`, a nonlinear law's
        fit in the frame of its own turning times): the optimiser does not run from the
        first guesses again.
    also_start_at : mapping, optional
        A second starting point of the optimiser (values of the sampled coordinates,
        e.g. the optimum of a nested law), kept if its optimum is better.
    reweight : bool
        The second pass (the default): the increments' variances computed again from
        the law's motion at the optimum, and the optimum of that posterior, which is
        the one sampled (:mod:`bayestribo.inference.reweight`; the observed channels'
        variances are too large below the noise, and share its sign). False: start
        from ``posterior`` as it is.

    Returns
    -------
    Start
    """
    if optimum is None:
        optimum = find_optimum(posterior, decay)
    theta, cov, ratio_range = better_optimum(posterior, optimum, also_start_at)
    if reweight:
        second = reweighted_posterior(posterior, decay, theta)
        if second is not None:
            posterior = second
            theta, cov, ratio_range = maximum_from(posterior, theta, decay)
    return Start(posterior, theta, cov, ratio_range)
