"""The package against what a competent user would write, at equal effective sample size.

Three ways to sample the same posterior of the bundled run
``data/runs/glycerol-N0.31-r1.csv`` (10 kHz, about 0.5 s of motion; ζ, μ_k, μ_s/μ_k
and y0 with the package's default priors and its Π likelihood, the equilibrium
nuisance marginalised):

(a) the package: :func:`bayestribo.inference.fit` with its defaults (compiled closed
    form of Π, its compiled sampler step, start from a Laplace approximation, run to
    an effective sample size of 1000, at least 20 autocorrelation times, and R-hat);
(b) a competent user's code: the equation of motion y'' + 2ζy' + y = -μ_k sgn(y')
    (the package's dimensionless form, Eq. 7-8) integrated by a numba-compiled
    fixed-step RK4 with Π carried as a third state (Π' = E = (y² + y'²)/2), steps
    shortened to land on the grid points, every turning point located exactly (the
    sign change of y' inside a step, then the step length to it solved for by
    Illinois' regula falsi on the RK4 step) and the stick rule |y| <= μ_s applied
    there; the same likelihood written out in numba (increments, their variances,
    the equilibrium nuisance's 2×2 Gaussian integral, which does not depend on the
    parameters and is precomputed); plain emcee (default StretchMove, 32 walkers)
    started from a Levenberg-Marquardt least-squares optimum (:func:`scipy.optimize.
    least_squares` over ζ, μ_k, y0 and the nuisance at each μ_s/μ_k of a coarse scan,
    the best kept) with walkers drawn from its Laplace covariance (μ_s/μ_k uniform on
    its prior, a walker kept when within 10 of the best log density), run in chunks
    until the effective sample size reaches the package's. The RK4 step is the
    largest of 0.1, 0.05, 0.025, ... whose log-likelihood agrees with a step half as
    large within 0.01 on posterior draws (a user's convergence check);
(c) the same with :func:`scipy.integrate.solve_ivp` (DOP853, a terminal velocity-zero
    event per half cycle, Π as a third state read from the dense output at the grid
    points; tolerances the loosest of rtol 1e-8, 1e-9, ... whose log-likelihood agrees
    with ten times tighter within 0.01) under the same emcee: too slow to run to the
    package's ESS, so a short chain from (b)'s start is timed and the time per
    log-posterior call times (b)'s calls per effective sample times the package's ESS
    is the (extrapolated) time it would take.

The observation (Π increments, their variances, the nuisance design) is the package's
:func:`bayestribo.inference.prepare` in all three: what is compared is the forward model,
the likelihood evaluation and the sampler.

Effective sample size, the same way for all: emcee's integrated autocorrelation time τ
(``emcee.autocorr.integrated_time``, tol 0; the package re-implements it and agrees to
rounding, and takes the larger of its two ensembles'), burn-in twice the largest τ over
the parameters, ESS = steps after burn-in × walkers / τ per parameter, the smallest
reported (the package's from its diagnostics, computed that way). Log-
posterior calls: evaluations at a parameter set inside the prior's support (the
package's counted in a separate fit with its compiled sampler step off, as in
``benchmarks/fit.py``; the users' counted as they happen, all calls also reported).

Side by side: the package's fits and (b)'s runs alternate, ``--repeats`` of each, one
seed each, in one process after a warm-up of each (compilation timed apart); (c)'s short
chain runs in blocks between package fits. Reported per approach: median wall time,
calls, ESS_min, ESS per second, time per call, and the ratios to the package; the
log-likelihoods of (b) and (c) against the package's on posterior draws; (b)'s posterior
means against the package's (draws of all repeats pooled) in units of the package's
posterior sd, with the Monte Carlo standard error of that difference.

Run: ``python benchmarks/peers.py``; writes ``benchmarks/results/peers.json``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import emcee
import numba
import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

from bayestribo.inference import build_posterior, fit, prepare
from bayestribo.inference.posterior import Posterior

ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "data" / "runs" / "glycerol-N0.31-r1.csv"
NAMES = ("zeta", "mu_k", "mu_s_ratio", "y0")
#: Walkers of the users' emcee ensemble (8 per parameter; the package uses 16 × 2).
WALKERS = 32
#: A user's motion is integrated at most to this multiple of the record's τ.
CAP = 20.0
#: Tolerated |Δ log L| of a user's accuracy check.
LOGL_TOL = 0.01


# -- the observation, shared by all --------------------------------------------------
@dataclass(frozen=True)
class Problem:
    """The observed increments and everything a user's likelihood needs, as arrays."""

    grid: NDArray  # τ_0 .. τ_m
    increments: NDArray  # D_j, (m,)
    variance: NDArray  # V_j, (m,)
    design: NDArray  # ∫y, ∫τy, the noise bias's standard error per increment, (m, 3)
    a_inv: NDArray  # (XᵀWX + P⁻¹)⁻¹, (2, 2)
    loglik_const: float
    ended: bool
    yp0: float
    prior_bounds: NDArray  # [[ζ lo, hi], [μ_k lo, hi], [ratio lo, hi]]
    y0_mu: float
    y0_sigma: float
    log_prior_const: float
    posterior: Posterior  # the package's (for checks only)


def problem() -> Problem:
    """The package's observation and priors of the bundled run, as a user's arrays."""
    prepared = prepare(RUN)
    post = build_posterior(prepared.data)
    lik = post.likelihood
    data = lik.data
    if list(post.priors.names) != list(NAMES):
        raise RuntimeError(f"unexpected parameters {post.priors.names}")
    var = np.asarray(data.variance, dtype=float)
    x = np.asarray(data.offset_design, dtype=float)
    a = (x.T / var) @ x
    a[0, 0] += lik.offset_sd**-2
    a[1, 1] += lik.drift_sd**-2
    a[2, 2] += 1.0  # the noise level's error, standard normal
    const = -0.5 * (
        np.sum(np.log(2.0 * math.pi * var))
        + np.linalg.slogdet(a)[1]
        + 2.0 * math.log(lik.offset_sd)
        + 2.0 * math.log(lik.drift_sd)
    )
    specs = post.priors.to_spec()
    bounds = np.array([[specs[n]["low"], specs[n]["high"]] for n in NAMES[:3]], dtype=float)
    if specs["y0"]["type"] != "Normal" or any(specs[n]["type"] != "Uniform" for n in NAMES[:3]):
        raise RuntimeError(f"unexpected priors {specs}")
    sigma = float(specs["y0"]["sigma"])
    return Problem(
        grid=np.asarray(data.tau_grid, dtype=float),
        increments=np.asarray(data.increments, dtype=float),
        variance=var,
        design=np.ascontiguousarray(x),
        a_inv=np.linalg.inv(a),
        loglik_const=float(const),
        ended=bool(data.motion_ended),
        yp0=float(data.yp0),
        prior_bounds=bounds,
        y0_mu=float(specs["y0"]["mu"]),
        y0_sigma=sigma,
        log_prior_const=float(
            -np.sum(np.log(bounds[:, 1] - bounds[:, 0])) - math.log(sigma * math.sqrt(2 * math.pi))
        ),
        posterior=post,
    )


# -- (b) a user's compiled fixed-step integrator ---------------------------------------
@numba.njit(cache=False)
def _rk4(y, v, p, h, zeta, force):
    """One RK4 step of y' = v, v' = -2ζv - y - force, Π' = (y² + v²)/2."""
    k1y = v
    k1v = -2.0 * zeta * v - y - force
    k1p = 0.5 * (y * y + v * v)
    y2 = y + 0.5 * h * k1y
    v2 = v + 0.5 * h * k1v
    k2y = v2
    k2v = -2.0 * zeta * v2 - y2 - force
    k2p = 0.5 * (y2 * y2 + v2 * v2)
    y3 = y + 0.5 * h * k2y
    v3 = v + 0.5 * h * k2v
    k3y = v3
    k3v = -2.0 * zeta * v3 - y3 - force
    k3p = 0.5 * (y3 * y3 + v3 * v3)
    y4 = y + h * k3y
    v4 = v + h * k3v
    k4y = v4
    k4v = -2.0 * zeta * v4 - y4 - force
    k4p = 0.5 * (y4 * y4 + v4 * v4)
    s = h / 6.0
    return (
        y + s * (k1y + 2.0 * k2y + 2.0 * k3y + k4y),
        v + s * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        p + s * (k1p + 2.0 * k2p + 2.0 * k3p + k4p),
    )


@numba.njit(cache=False)
def rk4_increments(zeta, mu_k, mu_s, y0, yp0, grid, ended, h, cap):
    """Model increments M_j of Π on ``grid`` by fixed-step RK4 with exact turning points.

    M_j = ∫ E over [τ_j, τ_{j+1}]; the last runs to the model's end of motion when the
    record holds it (``ended``), otherwise to τ_m; nothing after the model sticks.
    """
    m = grid.size - 1
    nodes = np.empty(m)  # Π's running integral ∫_0^τ E at τ_0 .. τ_{m-1}
    t, y, v, p = 0.0, y0, yp0, 0.0
    t_end = cap if ended else grid[m]
    k = 0
    while k < m and grid[k] <= t:
        nodes[k] = p
        k += 1
    moving = True
    if v > 0.0:
        d = 1.0
    elif v < 0.0:
        d = -1.0
    else:
        moving = abs(y) > mu_s
        d = -1.0 if y > 0.0 else 1.0
    while moving and t < t_end:
        target = t_end
        if k < m and grid[k] < target:
            target = grid[k]
        hs = min(h, target - t)
        y1, v1, p1 = _rk4(y, v, p, hs, zeta, mu_k * d)
        if v1 * d > 0.0:
            y, v, p = y1, v1, p1
            t = target if hs == target - t else t + hs
        else:
            # The velocity reaches zero inside the step: the step length to it.
            a, fa, b, fb = 0.0, v * d, hs, v1 * d
            s, ys, vs, ps = hs, y1, v1, p1
            side = 0
            for _ in range(100):
                s = (a * fb - b * fa) / (fb - fa)
                ys, vs, ps = _rk4(y, v, p, s, zeta, mu_k * d)
                fs = vs * d
                if fs == 0.0 or b - a < 1e-15 * (1.0 + t):
                    break
                if fs > 0.0:
                    a, fa = s, fs
                    if side == -1:
                        fb *= 0.5
                    side = -1
                else:
                    b, fb = s, fs
                    if side == 1:
                        fa *= 0.5
                    side = 1
            y, v, p = ys, 0.0, ps
            t = target if s == hs and hs == target - t else t + s
            if abs(y) <= mu_s:
                moving = False
            else:
                d = -1.0 if y > 0.0 else 1.0
        while k < m and grid[k] <= t:
            nodes[k] = p
            k += 1
    for j in range(k, m):
        nodes[j] = p
    out = np.empty(m)
    for j in range(m - 1):
        out[j] = nodes[j + 1] - nodes[j]
    out[m - 1] = p - nodes[m - 1]
    return out


@numba.njit(cache=False)
def _gaussian_loglik(model, data, var, x, a_inv, const):
    """The package's likelihood: Gaussian increments, the linear nuisances (equilibrium
    offset and drift, noise level) integrated out."""
    q = x.shape[1]
    chi2 = 0.0
    b = np.zeros(q)
    for j in range(model.size):
        r = data[j] - model[j]
        wr = r / var[j]
        chi2 += r * wr
        for k in range(q):
            b[k] += x[j, k] * wr
    explained = 0.0
    for k in range(q):
        for i in range(q):
            explained += b[k] * a_inv[k, i] * b[i]
    return const - 0.5 * (chi2 - explained)


@numba.njit(cache=False)
def _log_prior(theta, bounds, y0_mu, y0_sigma, const):
    for i in range(3):
        if not (bounds[i, 0] <= theta[i] <= bounds[i, 1]):
            return -np.inf
    z = (theta[3] - y0_mu) / y0_sigma
    return const - 0.5 * z * z


@numba.njit(cache=False)
def rk4_loglik(theta, grid, ended, yp0, h, cap, data, var, x, a_inv, const):
    """Log-likelihood of one parameter set (ζ, μ_k, μ_s/μ_k, y0) with the RK4 model."""
    model = rk4_increments(
        theta[0], theta[1], theta[1] * theta[2], theta[3], yp0, grid, ended, h, cap
    )
    return _gaussian_loglik(model, data, var, x, a_inv, const)


@numba.njit(cache=False)
def rk4_log_posterior(
    theta,
    bounds,
    y0_mu,
    y0_sigma,
    prior_const,
    grid,
    ended,
    yp0,
    h,
    cap,
    data,
    var,
    x,
    a_inv,
    const,
):
    """Log posterior density of one parameter set, compiled whole."""
    lp = _log_prior(theta, bounds, y0_mu, y0_sigma, prior_const)
    if not np.isfinite(lp):
        return lp
    return lp + rk4_loglik(theta, grid, ended, yp0, h, cap, data, var, x, a_inv, const)


# -- (c) a user's solve_ivp ------------------------------------------------------------
def ivp_increments(
    zeta: float, mu_k: float, mu_s: float, y0: float, pb: Problem, rtol: float, atol: float
) -> NDArray:
    """Model increments M_j with ``solve_ivp`` (DOP853) half cycle by half cycle."""
    grid = pb.grid
    m = grid.size - 1
    t_end = CAP * grid[-1] if pb.ended else grid[-1]
    nodes = np.full(m, np.nan)
    nodes[0] = 0.0
    t, state = 0.0, np.array([y0, pb.yp0, 0.0])
    half = math.pi / math.sqrt(max(1.0 - zeta * zeta, 1e-12))
    while t < t_end:
        if state[1] == 0.0:
            if abs(state[0]) <= mu_s:
                break
            d = -math.copysign(1.0, state[0])
        else:
            d = math.copysign(1.0, state[1])
        force = mu_k * d

        def rhs(_t: float, s: NDArray, force: float = force) -> list[float]:
            return [s[1], -2.0 * zeta * s[1] - s[0] - force, 0.5 * (s[0] * s[0] + s[1] * s[1])]

        def turning(_t: float, s: NDArray) -> float:
            return s[1]

        turning.terminal = True  # type: ignore[attr-defined]
        turning.direction = -d  # type: ignore[attr-defined]
        span = min(t + 1.5 * half + 1.0, t_end)
        sol = solve_ivp(
            rhs,
            (t, span),
            state,
            method="DOP853",
            events=turning,
            rtol=rtol,
            atol=atol,
            dense_output=True,
        )
        if sol.t_events[0].size:
            t1 = float(sol.t_events[0][0])
            new = np.array([sol.y_events[0][0][0], 0.0, sol.y_events[0][0][2]])
        else:
            t1 = float(sol.t[-1])
            new = sol.y[:, -1].copy()
        inside = (grid[:m] > t) & (grid[:m] <= t1)
        if np.any(inside):
            nodes[inside] = sol.sol(grid[:m][inside])[2]
        t, state = t1, new
        if t1 >= t_end:
            break
    nodes[np.isnan(nodes)] = state[2]
    out = np.empty(m)
    out[:-1] = np.diff(nodes)
    out[-1] = state[2] - nodes[-1]
    return out


def ivp_log_posterior(theta: NDArray, pb: Problem, rtol: float, atol: float) -> float:
    """Log posterior density of one parameter set with the solve_ivp model."""
    lp = _log_prior(theta, pb.prior_bounds, pb.y0_mu, pb.y0_sigma, pb.log_prior_const)
    if not np.isfinite(lp):
        return lp
    z, mu, ratio, y0 = (float(v) for v in theta)
    model = ivp_increments(z, mu, mu * ratio, y0, pb, rtol, atol)
    return lp + _gaussian_loglik(
        model, pb.increments, pb.variance, pb.design, pb.a_inv, pb.loglik_const
    )


# -- a user's log posterior with a call counter ------------------------------------------
class UserPosterior:
    """The log posterior emcee calls, one parameter set at a time, counting calls."""

    def __init__(self, pb: Problem, kind: str, setting: tuple[float, ...]) -> None:
        self.pb, self.kind, self.setting = pb, kind, setting
        self.calls = 0
        self.inside = 0

    def __call__(self, theta: NDArray) -> float:
        self.calls += 1
        pb = self.pb
        if self.kind == "rk4":
            lp = rk4_log_posterior(
                np.asarray(theta, dtype=float),
                pb.prior_bounds,
                pb.y0_mu,
                pb.y0_sigma,
                pb.log_prior_const,
                pb.grid,
                pb.ended,
                pb.yp0,
                self.setting[0],
                CAP * pb.grid[-1],
                pb.increments,
                pb.variance,
                pb.design,
                pb.a_inv,
                pb.loglik_const,
            )
        else:
            lp = ivp_log_posterior(np.asarray(theta, dtype=float), pb, *self.setting)
        if np.isfinite(lp):
            self.inside += 1
        return float(lp)

    def increments(self, zeta: float, mu_k: float, mu_s: float, y0: float) -> NDArray:
        """The model's increments M_j."""
        pb = self.pb
        if self.kind == "rk4":
            return rk4_increments(
                zeta, mu_k, mu_s, y0, pb.yp0, pb.grid, pb.ended, self.setting[0], CAP * pb.grid[-1]
            )
        return ivp_increments(zeta, mu_k, mu_s, y0, pb, *self.setting)

    def loglik(self, theta: NDArray) -> float:
        """Log-likelihood alone (for the checks against the package)."""
        pb = self.pb
        theta = np.asarray(theta, dtype=float)
        if self.kind == "rk4":
            return float(
                rk4_loglik(
                    theta,
                    pb.grid,
                    pb.ended,
                    pb.yp0,
                    self.setting[0],
                    CAP * pb.grid[-1],
                    pb.increments,
                    pb.variance,
                    pb.design,
                    pb.a_inv,
                    pb.loglik_const,
                )
            )
        lp = ivp_log_posterior(theta, pb, *self.setting)
        return float(
            lp - _log_prior(theta, pb.prior_bounds, pb.y0_mu, pb.y0_sigma, pb.log_prior_const)
        )


def package_loglik(pb: Problem, draws: NDArray) -> NDArray:
    """The package's log-likelihood of parameter rows (ζ, μ_k, μ_s/μ_k, y0)."""
    return np.asarray(pb.posterior.log_likelihood(np.asarray(draws, dtype=float)))


# -- a user's start: least squares, a ratio scan, a Laplace ball -------------------------
def _user_start(
    logp: UserPosterior, pb: Problem, rng: np.random.Generator
) -> tuple[NDArray, dict[str, Any]]:
    """Walkers around a Levenberg-Marquardt optimum, as a competent user would start.

    Least squares over (ζ, μ_k, y0, δ₀, δ₁) of the whitened residuals with the
    nuisance's and y0's Gaussian priors as extra residuals (its optimum in θ is the
    maximum of the marginal posterior) at a fixed μ_s/μ_k, from a decay-rate guess of
    ζ with little friction and from half that ζ with more; μ_s/μ_k then set to the
    best of a scan over its prior, and least squares again; the best optimum kept.
    """
    lik = pb.posterior.likelihood
    sd = np.sqrt(pb.variance)

    def residuals(q: NDArray, ratio: float) -> NDArray:
        logp.calls += 1
        logp.inside += 1
        z, mu, y0, d0, d1 = q
        model = logp.increments(z, mu, mu * ratio, y0)
        r = (pb.increments - model - pb.design[:, :2] @ np.array([d0, d1])) / sd
        extra = [d0 / lik.offset_sd, d1 / lik.drift_sd, (y0 - pb.y0_mu) / pb.y0_sigma]
        return np.concatenate([r, extra])

    mid = 0.5 * (pb.grid[:-1] + pb.grid[1:])
    half = slice(0, max(3, mid.size // 2))
    slope = np.polyfit(mid[half], np.log(np.maximum(pb.increments[half], 1e-300)), 1)[0]
    z_guess = float(np.clip(-0.5 * slope, 1e-4, 0.29))
    ratios = np.linspace(1.0, pb.prior_bounds[2, 1], 37)
    best: tuple[float, NDArray, NDArray] | None = None
    for z, mu in ((z_guess, 1e-3 * pb.y0_mu), (0.5 * z_guess, 0.5 * z_guess * pb.y0_mu)):
        q = np.array([z, mu, pb.y0_mu, 0.0, 0.0])
        ratio = 2.0
        for _ in range(2):
            sol = least_squares(residuals, q, args=(ratio,), method="lm", x_scale="jac")
            q = sol.x
            scan = [logp(np.array([q[0], q[1], r, q[2]])) for r in ratios]
            ratio = float(ratios[int(np.argmax(scan))])
        sol = least_squares(residuals, q, args=(ratio,), method="lm", x_scale="jac")
        theta = np.array([sol.x[0], sol.x[1], ratio, sol.x[2]])
        lp = logp(theta)
        if best is None or lp > best[0]:
            jac = sol.jac
            cov = np.linalg.inv(jac.T @ jac)[np.ix_([0, 1, 2], [0, 1, 2])]
            best = (lp, theta, cov)
    assert best is not None
    lp_best, theta, cov = best
    walkers: list[NDArray] = []
    drawn = 0
    while len(walkers) < WALKERS:
        drawn += 1
        zmy = rng.multivariate_normal(theta[[0, 1, 3]], cov)
        cand = np.array([zmy[0], zmy[1], rng.uniform(*pb.prior_bounds[2]), zmy[2]])
        if logp(cand) >= lp_best - 10.0:
            walkers.append(cand)
    return np.array(walkers), {"map": theta.tolist(), "log_density": lp_best, "drawn": drawn}


def _ess(chain: NDArray) -> tuple[NDArray, NDArray, int]:
    """τ per parameter (burn-in 2τ discarded), ESS per parameter and the burn-in."""
    steps = chain.shape[0]
    tau = emcee.autocorr.integrated_time(chain[steps // 3 :], tol=0)
    burn = min(math.ceil(2.0 * np.max(tau)), steps - 1)
    tau = emcee.autocorr.integrated_time(chain[burn:], tol=0)
    burn = min(math.ceil(2.0 * np.max(tau)), steps - 1)
    return tau, (steps - burn) * chain.shape[1] / tau, burn


class UserChain:
    """A user's fit: the start, then plain emcee advanced a chunk at a time."""

    def __init__(self, pb: Problem, kind: str, setting: tuple[float, ...], seed: int) -> None:
        self.logp = UserPosterior(pb, kind, setting)
        self.seed = seed
        self.seconds = 0.0
        self.n_steps = 0
        clock = time.perf_counter()
        self.p0, self.start_info = _user_start(self.logp, pb, np.random.default_rng(seed))
        self.start_calls = self.logp.calls
        self.sampler = emcee.EnsembleSampler(WALKERS, len(NAMES), self.logp)
        self.sampler.random_state = np.random.RandomState(seed).get_state()
        self.state: Any = self.p0
        self.seconds += time.perf_counter() - clock
        self.start_seconds = self.seconds

    def advance(self, steps: int) -> None:
        clock = time.perf_counter()
        self.state = self.sampler.run_mcmc(self.state, steps, progress=False)
        self.n_steps += steps
        self.seconds += time.perf_counter() - clock

    def summary(self) -> dict[str, Any]:
        return {
            "seed": self.seed,
            "seconds": self.seconds,
            "start_seconds": self.start_seconds,
            "n_steps": self.n_steps,
            "calls": self.logp.calls,
            "calls_inside_prior": self.logp.inside,
            "start_calls": self.start_calls,
            "start": self.start_info,
            "acceptance_fraction": float(np.mean(self.sampler.acceptance_fraction)),
            "seconds_per_call": self.seconds / self.logp.inside,
        }


def user_run(
    pb: Problem, setting: tuple[float, ...], seed: int, target_ess: float, max_steps: int = 40_000
) -> dict[str, Any]:
    """(b): the RK4 user's fit, sampled until ESS_min >= ``target_ess``. The time
    includes the ESS checks (emcee's autocorrelation time every chunk)."""
    load = list(os.getloadavg())
    clock = time.perf_counter()
    chain = UserChain(pb, "rk4", setting, seed)
    chunk = 200
    while True:
        chain.advance(chunk)
        tau, ess, burn = _ess(chain.sampler.get_chain())
        if np.min(ess) >= target_ess or chain.n_steps >= max_steps:
            break
        need = burn + target_ess * np.max(tau) / WALKERS
        chunk = int(
            min(max(100, math.ceil(1.05 * need) - chain.n_steps), max_steps - chain.n_steps)
        )
    seconds = time.perf_counter() - clock
    out = chain.summary()
    out.update(
        {
            "seconds": seconds,
            "seconds_per_call": seconds / chain.logp.inside,
            "burn": burn,
            "autocorr_time": dict(zip(NAMES, tau.tolist(), strict=True)),
            "ess": dict(zip(NAMES, ess.tolist(), strict=True)),
            "ess_min": float(np.min(ess)),
            "ess_per_second": float(np.min(ess)) / seconds,
            "calls_per_effective_sample": chain.logp.inside / float(np.min(ess)),
            "reached_target": bool(np.min(ess) >= target_ess),
            "load_before": load,
            "draws": chain.sampler.get_chain(discard=burn, flat=True),
        }
    )
    return out


def package_run(seed: int) -> dict[str, Any]:
    """The package's fit with its defaults."""
    load = list(os.getloadavg())
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(RUN, seed=seed)
    seconds = time.perf_counter() - start
    d = result.diagnostics
    return {
        "seed": seed,
        "seconds": seconds,
        "converged": result.converged,
        "n_steps": d["n_steps"],
        "burn": d["burn"],
        "autocorr_time": d["autocorr_time"],
        "ess": d["ess"],
        "ess_min": d["ess_min"],
        "ess_per_second": d["ess_min"] / seconds,
        "acceptance_fraction": d["acceptance_fraction"],
        "load_before": load,
        "draws": np.column_stack([result.samples(n) for n in NAMES]),
    }


def count_package_calls(seed: int) -> int:
    """Log-posterior evaluations inside the prior's support in one package fit."""
    import fit as fit_benchmark  # benchmarks/fit.py

    return int(fit_benchmark.count_evaluations(seed))


# -- accuracy settings by a user's convergence check ---------------------------------------
def _max_dloglik(
    pb: Problem, kind: str, a: tuple[float, ...], b: tuple[float, ...], draws: NDArray
) -> float:
    la = np.array([UserPosterior(pb, kind, a).loglik(d) for d in draws])
    lb = np.array([UserPosterior(pb, kind, b).loglik(d) for d in draws])
    return float(np.max(np.abs(la - lb)))


def choose_settings(pb: Problem, draws: NDArray) -> dict[str, Any]:
    """The RK4 step and the solve_ivp tolerances by step halving / tightening."""
    checks: dict[str, Any] = {"rk4": [], "ivp": []}
    h = 0.1
    while True:
        diff = _max_dloglik(pb, "rk4", (h,), (h / 2,), draws)
        checks["rk4"].append({"h": h, "max_abs_dloglik_vs_half": diff})
        if diff <= LOGL_TOL or h < 1e-3:
            break
        h /= 2
    rtol = 1e-8
    few = draws[: max(8, draws.shape[0] // 4)]
    while True:
        diff = _max_dloglik(pb, "ivp", (rtol, 1e-2 * rtol), (0.1 * rtol, 1e-3 * rtol), few)
        checks["ivp"].append({"rtol": rtol, "max_abs_dloglik_vs_10x_tighter": diff})
        if diff <= LOGL_TOL or rtol < 1e-12:
            break
        rtol /= 10
    return {"rk4": (h,), "ivp": (rtol, 1e-2 * rtol), "checks": checks}


# -- the benchmark ------------------------------------------------------------------------
def _agreement(pkg: list[dict[str, Any]], user: list[dict[str, Any]]) -> dict[str, Any]:
    """(b)'s posterior means against the package's, pooled over the repeats."""
    a = np.concatenate([f["draws"] for f in pkg])
    b = np.concatenate([f["draws"] for f in user])
    ess_a = sum(f["ess_min"] for f in pkg)
    ess_b = sum(f["ess_min"] for f in user)
    out = {}
    for i, name in enumerate(NAMES):
        sd_a, sd_b = float(np.std(a[:, i])), float(np.std(b[:, i]))
        diff = float(np.mean(b[:, i]) - np.mean(a[:, i]))
        out[name] = {
            "package_mean": float(np.mean(a[:, i])),
            "package_sd": sd_a,
            "user_mean": float(np.mean(b[:, i])),
            "user_sd": sd_b,
            "mean_difference_in_sd": diff / sd_a,
            "monte_carlo_se_in_sd": math.sqrt(1.0 / ess_a + (sd_b / sd_a) ** 2 / ess_b),
            "sd_ratio": sd_b / sd_a,
        }
    return out


def _summary(rows: list[dict[str, Any]], calls: float | None = None) -> dict[str, Any]:
    seconds = float(np.median([r["seconds"] for r in rows]))
    n_calls = float(np.median([r["calls_inside_prior"] for r in rows])) if calls is None else calls
    return {
        "median_seconds": seconds,
        "min_seconds": float(np.min([r["seconds"] for r in rows])),
        "max_seconds": float(np.max([r["seconds"] for r in rows])),
        "median_ess_min": float(np.median([r["ess_min"] for r in rows])),
        "median_ess_per_second": float(np.median([r["ess_per_second"] for r in rows])),
        "median_steps": float(np.median([r["n_steps"] for r in rows])),
        "log_posterior_calls": n_calls,
        "seconds_per_call": seconds / n_calls,
        "median_load_1min": float(np.median([r["load_before"][0] for r in rows])),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="package fits and (b) runs each")
    parser.add_argument("--ivp-steps", type=int, default=8, help="(c) emcee steps per round")
    parser.add_argument("--output", default="peers", help="results/<output>.json")
    args = parser.parse_args(argv)
    load_start = list(os.getloadavg())
    pb = problem()

    print("warm-up: package fit (imports, compilation) ...", flush=True)
    clock = time.perf_counter()
    warm = package_run(0)
    package_first = time.perf_counter() - clock
    target = float(warm["ess_min"])
    clock = time.perf_counter()
    UserPosterior(pb, "rk4", (0.025,))(np.array(warm["draws"][0]))
    user_compile = time.perf_counter() - clock
    prep = []
    for _ in range(3):
        clock = time.perf_counter()
        prepare(RUN)
        prep.append(time.perf_counter() - clock)

    pick = np.linspace(0, warm["draws"].shape[0] - 1, 32).round().astype(int)
    draws = warm["draws"][pick]
    print("accuracy settings by the users' convergence checks ...", flush=True)
    settings = choose_settings(pb, draws)
    reference = package_loglik(pb, draws)
    rk4 = UserPosterior(pb, "rk4", settings["rk4"])
    ivp = UserPosterior(pb, "ivp", settings["ivp"])
    few = slice(0, 8)
    vs_package = {
        "rk4_max_abs_dloglik": float(np.max(np.abs([rk4.loglik(d) for d in draws] - reference))),
        "ivp_max_abs_dloglik": float(
            np.max(np.abs([ivp.loglik(d) for d in draws[few]] - reference[few]))
        ),
        "draws": int(draws.shape[0]),
        "ivp_draws": 8,
    }
    print(
        f"  RK4 step {settings['rk4'][0]:g}, solve_ivp rtol {settings['ivp'][0]:g}; "
        f"max |Δ log L| vs the package {vs_package['rk4_max_abs_dloglik']:.2e} (RK4), "
        f"{vs_package['ivp_max_abs_dloglik']:.2e} (solve_ivp)",
        flush=True,
    )
    package_calls = count_package_calls(1)
    user_run(pb, settings["rk4"], 0, min(target, 200.0))  # warm-up of (b)'s path

    print(f"side by side, {args.repeats} rounds (target ESS_min {target:.0f}):", flush=True)
    pkg: list[dict[str, Any]] = []
    user: list[dict[str, Any]] = []
    slow: UserChain | None = None
    for i in range(1, args.repeats + 1):
        for who in ("package", "user") if i % 2 else ("user", "package"):
            if who == "package":
                pkg.append(package_run(i))
            else:
                user.append(user_run(pb, settings["rk4"], i, target))
            r = (pkg if who == "package" else user)[-1]
            print(
                f"  round {i} {who:8s} {r['seconds']:7.2f} s  ESS_min {r['ess_min']:6.0f}  "
                f"steps {r['n_steps']:5d}  load {r['load_before'][0]:.2f}",
                flush=True,
            )
        if slow is None:
            slow = UserChain(pb, "ivp", settings["ivp"], 1)
        slow.advance(args.ivp_steps)
        print(
            f"  round {i} solve_ivp {slow.n_steps:3d} steps, {slow.logp.calls:5d} calls, "
            f"{slow.seconds:7.1f} s",
            flush=True,
        )
    assert slow is not None

    s_pkg = _summary(pkg, calls=float(package_calls))
    s_user = _summary(user)
    s_user["median_calls_all"] = float(np.median([r["calls"] for r in user]))
    s_user["median_calls_per_effective_sample"] = float(
        np.median([r["calls_per_effective_sample"] for r in user])
    )
    s_user["all_reached_target"] = all(r["reached_target"] for r in user)
    ess_pkg = s_pkg["median_ess_min"]
    c = slow.summary()
    c_seconds = c["seconds_per_call"] * s_user["median_calls_per_effective_sample"] * ess_pkg
    s_ivp = {
        "short_chain": c,
        "seconds_per_call": c["seconds_per_call"],
        "extrapolated": True,
        "extrapolated_calls": s_user["median_calls_per_effective_sample"] * ess_pkg,
        "extrapolated_seconds": c_seconds,
        "extrapolated_ess_min": ess_pkg,
        "extrapolated_ess_per_second": ess_pkg / c_seconds,
    }
    per_second = s_pkg["median_ess_per_second"]
    ratios = {
        "user_rk4_time_at_equal_ess": per_second / s_user["median_ess_per_second"],
        "user_rk4_median_seconds": s_user["median_seconds"] / s_pkg["median_seconds"],
        "user_rk4_time_per_call": s_user["seconds_per_call"] / s_pkg["seconds_per_call"],
        "user_rk4_calls": s_user["log_posterior_calls"] / s_pkg["log_posterior_calls"],
        "solve_ivp_time_at_equal_ess": per_second / s_ivp["extrapolated_ess_per_second"],
        "solve_ivp_time_per_call": s_ivp["seconds_per_call"] / s_pkg["seconds_per_call"],
    }
    agreement = _agreement(pkg, user)

    print()
    head = f"{'approach':34s} {'seconds':>9s} {'calls':>8s} {'ESS_min':>8s} {'ESS/s':>8s} "
    print(head + f"{'µs/call':>9s} {'× package (equal ESS)':>22s}")
    rows = [
        (
            "(a) package fit",
            s_pkg["median_seconds"],
            s_pkg["log_posterior_calls"],
            ess_pkg,
            per_second,
            s_pkg["seconds_per_call"],
            1.0,
        ),
        (
            "(b) numba RK4 + plain emcee",
            s_user["median_seconds"],
            s_user["log_posterior_calls"],
            s_user["median_ess_min"],
            s_user["median_ess_per_second"],
            s_user["seconds_per_call"],
            ratios["user_rk4_time_at_equal_ess"],
        ),
        (
            "(c) solve_ivp + emcee, extrapolated",
            c_seconds,
            s_ivp["extrapolated_calls"],
            ess_pkg,
            s_ivp["extrapolated_ess_per_second"],
            s_ivp["seconds_per_call"],
            ratios["solve_ivp_time_at_equal_ess"],
        ),
    ]
    for name, sec, calls, ess, eps, per, ratio in rows:
        print(
            f"{name:34s} {sec:9.2f} {calls:8.0f} {ess:8.0f} {eps:8.0f} {1e6 * per:9.1f} "
            f"{ratio:21.0f}×"
        )
    print(
        f"time per call: (b) {ratios['user_rk4_time_per_call']:.1f}×, (c) "
        f"{ratios['solve_ivp_time_per_call']:.0f}× the package's"
    )
    print("(b)'s posterior means − the package's, in package posterior sd (± MC se):")
    for name, v in agreement.items():
        print(
            f"  {name:11s} {v['mean_difference_in_sd']:+.3f} ± {v['monte_carlo_se_in_sd']:.3f}"
            f"  (sd ratio {v['sd_ratio']:.3f})"
        )

    for r in pkg + user:
        r.pop("draws")
    results = {
        "benchmark": "peers",
        "description": __doc__.split("\n\n", 1)[1].rsplit("\n\nRun:", 1)[0],
        "command": "python benchmarks/peers.py",
        "run": str(RUN.relative_to(ROOT)),
        "load_average_at_start": load_start,
        "load_average_at_end": list(os.getloadavg()),
        "versions": {"emcee": emcee.__version__, "numba": numba.__version__},
        "walkers_user": WALKERS,
        "target_ess_min": target,
        "settings": {
            "rk4_step": settings["rk4"][0],
            "solve_ivp_rtol": settings["ivp"][0],
            "solve_ivp_atol": settings["ivp"][1],
            "checks": settings["checks"],
        },
        "loglik_vs_package": vs_package,
        "first_call_seconds": {"package": package_first, "user_rk4_compile": user_compile},
        "prepare_seconds_median": float(np.median(prep)),
        "package": {"summary": s_pkg, "fits": pkg},
        "user_rk4": {"summary": s_user, "runs": user},
        "user_solve_ivp": s_ivp,
        "ratios_to_package": ratios,
        "posterior_agreement": agreement,
        "notes": (
            "2 shared cores (other engineers' jobs running; load averages recorded per "
            "run): ratios are of medians measured alternately in this one run. The "
            "package's wall time includes reading and preparing the record (energy "
            "decay, noise model, increments: prepare_seconds_median) and its reporting "
            "(derived quantities, predictive draws, mode check); the users' start from "
            "the prepared increments, which favours them. (c) is extrapolated: its "
            "time per call measured on a short chain, times (b)'s calls per effective "
            "sample (the same sampler on the same posterior), times the package's ESS."
        ),
    }
    path = write_results(args.output, results)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
