"""Sampler honesty: separated modes found and weighed, never averaged silently; a
failed sampler reported, never a crash.

R-hat compares independent ensembles; when every ensemble starts from the same
optimum and visits the same far-off region (or leaves it at the same time), R-hat
stays near 1 while the draws hold two populations, and a mean, sd or interval over
them describes neither. :func:`find_modes` looks for such populations in the joint
draws of a :class:`~bayestribo.inference.sampling.SamplerRun` and reports each with
its weight, the mean of every parameter and its mean log-posterior.

The rule (documented, tested on known targets in ``tests/test_inference_modes.py``):

1. **Coordinates.** Each sampled parameter is centred on its median and scaled by
   its robust sd (1.4826 × MAD, the sd when the MAD is 0); constant parameters are
   left out.
2. **Split.** The draws are split in two by k-means (k = 2, started at the median
   and at the draw farthest from it), and projected on the Fisher discriminant
   direction of the two groups (their pooled within-group covariance, with a small
   ridge so that a stuck walker's repeated point does not make it singular).
3. **Gap.** Along that projection the draws are counted in bins of a fifth of the
   larger group's robust sd (wider if need be, so that the smaller group averages
   ten draws a bin), summed over three neighbouring bins. The groups are
   *separated modes* when the lowest count between the two groups' highest counts
   (the valley) is at most a quarter of the smaller of those two peaks **and** the
   dip is beyond counting noise (peak − valley ≥ 3 √peak). Along a line, a
   log-concave density (a Gaussian, most posteriors near their mode) has no valley
   between two of its points, so the k-means halves of one mode (k-means always
   splits) do not pass; a heavy tail has no dip either (no false mode in 1800
   samples of six unimodal laws, ``benchmarks/modes.py``).
4. **Recursion.** Each mode found is split again the same way (at most
   :data:`MAX_MODES` modes); a group of fewer than :data:`MIN_DRAWS` draws is not
   split off.
5. **Weight that matters.** A minor mode *matters* when its weight is at least
   :data:`MIN_WEIGHT` (1 %: the tail of a 95 % interval is 2.5 %) or when it
   shifts the mean of any parameter by at least :data:`MIN_SHIFT` (0.1) of the main
   mode's sd (weight × distance / sd: a small, far mode). A fit whose draws hold a
   minor mode that matters is not converged, with a reason naming the modes.
6. **Transient, stuck walkers or mode.** A minor mode visited only in the first half
   of the kept steps and never after is a *transient*: the walkers started there and
   left it (burn-in too short), so its draws are not from the posterior at all. A
   minor mode whose draws (90 % or more) come from walkers that spend 90 % or more
   of the run in it, or that at most a tenth of the walkers ever visit, holds
   *stuck walkers*: they do not mix with the others, and its weight is their
   number and how long they stayed, not a posterior probability. Otherwise it is a
   *mode* the walkers cross to and from; its weight is the sampler's estimate. The reason
   says which, with the mode's mean log-posterior against the main mode's (a region
   hundreds below holds no posterior mass).

A failed sampler is the sample stage's to report
(:func:`bayestribo.inference.chains.run_or_failure`).
:func:`bayestribo.inference.checks.check` calls :func:`mode_check`;
:func:`bayestribo.inference.sampling.run_ensembles` calls :func:`transient_steps` to keep
its burn-in past a transient.

References
----------
MacQueen, J. (1967). Some methods for classification and analysis of multivariate
observations (k-means). Fisher, R. A. (1936). The use of multiple measurements in
taxonomic problems (the discriminant direction).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.rhat import rhat

__all__ = [
    "MAX_MODES",
    "MIN_DRAWS",
    "MIN_SHIFT",
    "MIN_WEIGHT",
    "Mode",
    "ModeReport",
    "find_modes",
    "mode_check",
    "transient_steps",
]

#: Smallest group of draws split off as a mode of its own.
MIN_DRAWS = 20
#: Weight from which a minor mode makes a fit not converged (fraction of the draws).
MIN_WEIGHT = 0.01
#: Shift of a parameter's mean by a minor mode, in sd of the main mode, from which it
#: makes a fit not converged whatever its weight.
MIN_SHIFT = 0.1
#: Most modes reported.
MAX_MODES = 4
#: Valley at most this fraction of the smaller peak: the groups are separated.
VALLEY_RATIO = 0.25
#: Bins per robust sd of the larger group along the discriminant direction.
BINS_PER_SD = 5
#: A minor mode whose last visit is before this fraction of the kept steps is a transient.
TRANSIENT_BEFORE = 0.5
#: A walker spending at least this fraction of its kept steps in a minor mode is stuck
#: there; a mode whose draws come this much from stuck walkers holds stuck walkers.
STUCK_FRACTION = 0.9
#: A minor mode visited by at most this fraction of the walkers (at least one) holds
#: stuck walkers too: the others never go there.
FEW_WALKERS = 0.1


@dataclass(frozen=True)
class Mode:
    """One population of the draws.

    Attributes
    ----------
    weight : float
        Fraction of the draws in it.
    mean : dict of str to float
        Mean of each sampled parameter over its draws (sampling coordinates).
    sd : dict of str to float
        Standard deviation of each sampled parameter over its draws.
    log_prob : float
        Mean log-posterior of its draws.
    n_draws : int
        Number of draws.
    steps : tuple of float
        First and last kept step it holds a draw at, as fractions of the kept steps
        (0 the first, 1 the last).
    kind : str
        ``"main"`` (the heaviest), ``"mode"`` (the walkers cross to and from it),
        ``"transient"`` (visited only at the start and left: burn-in too short) or
        ``"stuck"`` (a few walkers that stay in it, the others never go there).
    walkers : int
        Walkers (over all ensembles) with a draw in it.
    stuck_walkers : int
        Walkers that spend at least :data:`STUCK_FRACTION` of the run in it.
    """

    weight: float
    mean: dict[str, float]
    sd: dict[str, float]
    log_prob: float
    n_draws: int
    steps: tuple[float, float]
    kind: str
    walkers: int = 0
    stuck_walkers: int = 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "weight": self.weight,
            "mean": dict(self.mean),
            "sd": dict(self.sd),
            "log_prob": self.log_prob,
            "n_draws": self.n_draws,
            "steps": list(self.steps),
            "kind": self.kind,
            "walkers": self.walkers,
            "stuck_walkers": self.stuck_walkers,
        }


@dataclass(frozen=True)
class ModeReport:
    """The modes of a sampler run, heaviest first.

    Attributes
    ----------
    modes : list of Mode
        One entry for a unimodal posterior.
    names : tuple of str
        Parameter names.
    matters : bool
        A minor mode carries weight that matters (rule 5 of the module notes): the
        draws must not be summarised as one population.
    reason : str
        The non-convergence reason naming the modes ("" when nothing matters).
    dropped_steps : int
        Sampler steps added to the burn-in to drop a transient (the walkers' way to
        the posterior from where they started) that the autocorrelation's burn-in did
        not cover (:func:`mode_check`); 0 when none was.
    """

    modes: list[Mode]
    names: tuple[str, ...]
    matters: bool
    reason: str = ""
    dropped_steps: int = 0
    rule: dict[str, float] = field(
        default_factory=lambda: {
            "min_weight": MIN_WEIGHT,
            "min_shift_sd": MIN_SHIFT,
            "valley_ratio": VALLEY_RATIO,
            "min_draws": MIN_DRAWS,
        }
    )

    @property
    def n_modes(self) -> int:
        """Number of modes found (1 for a unimodal posterior)."""
        return len(self.modes)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (stored in a fit's ``diagnostics["modes"]``)."""
        return {
            "n_modes": self.n_modes,
            "matters": self.matters,
            "reason": self.reason,
            "dropped_steps": self.dropped_steps,
            "rule": dict(self.rule),
            "modes": [m.to_dict() for m in self.modes],
        }


def _robust_sd(x: NDArray) -> float:
    mad = float(np.median(np.abs(x - np.median(x))))
    return 1.4826 * mad if mad > 0.0 else float(np.std(x))


def _standardised(draws: NDArray) -> NDArray:
    cols = []
    for j in range(draws.shape[1]):
        x = draws[:, j]
        s = _robust_sd(x)
        if s > 0.0 and math.isfinite(s):
            cols.append((x - np.median(x)) / s)
    return np.column_stack(cols) if cols else np.zeros((draws.shape[0], 0))


def _kmeans2(z: NDArray, iterations: int = 50) -> NDArray:
    """Labels (0/1) of a two-means split started at the median and the farthest draw."""
    c0 = np.median(z, axis=0)
    far = z[int(np.argmax(np.sum((z - c0) ** 2, axis=1)))]
    return _lloyd(np.ascontiguousarray(z, dtype=float), np.vstack([c0, far]), iterations)


@numba.njit(cache=True, error_model="numpy")
def _lloyd(z: NDArray, centres: NDArray, iterations: int) -> NDArray:
    """Lloyd's iterations of two means from ``centres`` (2, d), updated in place: each
    draw to the nearer centre (the first on a tie), each centre to its draws' mean,
    until the labels stop changing (after one update at least) or ``iterations``.
    The squared distances and the means are summed in numpy's order (the distances
    along a row, the means row after row), so the labels are numpy's."""
    n, d = z.shape
    labels = np.zeros(n, dtype=np.int64)
    sums = np.empty((2, d))
    counts = np.empty(2, dtype=np.int64)
    for it in range(iterations):
        changed = False
        for i in range(n):
            d0 = 0.0
            d1 = 0.0
            for j in range(d):
                a = z[i, j] - centres[0, j]
                b = z[i, j] - centres[1, j]
                d0 += a * a
                d1 += b * b
            new = 1 if d1 < d0 else 0
            if new != labels[i]:
                labels[i] = new
                changed = True
        if not changed and it > 0:
            break
        sums[:] = 0.0
        counts[:] = 0
        for i in range(n):
            k = labels[i]
            counts[k] += 1
            for j in range(d):
                sums[k, j] += z[i, j]
        for k in range(2):
            if counts[k] > 0:
                for j in range(d):
                    centres[k, j] = sums[k, j] / counts[k]
    return labels


def _separated(z: NDArray, labels: NDArray) -> bool:
    """The two groups are separated by a valley along their discriminant direction."""
    a, b = z[labels == 0], z[labels == 1]
    if min(a.shape[0], b.shape[0]) < MIN_DRAWS:
        return False
    ridge = 1e-6 * np.eye(z.shape[1])
    within = (np.atleast_2d(np.cov(a.T)) * (a.shape[0] - 1)) + (
        np.atleast_2d(np.cov(b.T)) * (b.shape[0] - 1)
    )
    within = within / (z.shape[0] - 2) + ridge
    direction = np.linalg.solve(within, b.mean(axis=0) - a.mean(axis=0))
    norm = float(np.linalg.norm(direction))
    if not math.isfinite(norm) or norm == 0.0:
        return False
    p = z @ (direction / norm)
    pa, pb = p[labels == 0], p[labels == 1]
    big, small = (pa, pb) if pa.size >= pb.size else (pb, pa)
    # Bins of a fifth of the larger group's sd, but wide enough that the smaller group
    # averages 10 draws a bin: a sparse tail is not read as peaks and valleys.
    width = max(_robust_sd(big) / BINS_PER_SD, float(np.ptp(small)) / (small.size / 10.0))
    span = float(p.max() - p.min())
    if not width > 0.0:
        width = span / 1000.0
    width = max(width, span / 20_000.0)
    if not width > 0.0:
        return False
    n_bins = max(math.ceil(span / width), 3)
    counts, edges = np.histogram(p, bins=n_bins, range=(float(p.min()), float(p.max())))
    smooth = np.convolve(counts, np.ones(3), mode="same")
    centre = 0.5 * (edges[:-1] + edges[1:])

    def peak(values: NDArray) -> int:
        inside = (centre >= values.min() - width) & (centre <= values.max() + width)
        idx = np.flatnonzero(inside)
        return int(idx[np.argmax(smooth[idx])])

    ia, ib = peak(pa), peak(pb)
    lo, hi = min(ia, ib), max(ia, ib)
    if hi - lo < 2:
        return False
    valley = float(np.min(smooth[lo : hi + 1]))
    top = float(min(smooth[ia], smooth[ib]))
    return valley <= VALLEY_RATIO * top and top - valley >= 3.0 * math.sqrt(top)


def _groups(draws: NDArray) -> list[NDArray]:
    """Index arrays of the separated groups of ``draws`` (recursive two-way splits)."""
    pending = [np.arange(draws.shape[0])]
    done: list[NDArray] = []
    while pending:
        idx = pending.pop()
        if len(done) + len(pending) + 1 >= MAX_MODES or idx.size < 2 * MIN_DRAWS:
            done.append(idx)
            continue
        z = _standardised(draws[idx])
        if z.shape[1] == 0:
            done.append(idx)
            continue
        labels = _kmeans2(z)
        if _separated(z, labels):
            pending.extend([idx[labels == 0], idx[labels == 1]])
        else:
            done.append(idx)
    return done


def find_modes(
    chains: NDArray,
    log_prob: NDArray,
    names: Sequence[str],
    n_walkers: int,
) -> ModeReport:
    """Separated populations of the draws of a sampler run (rule in the module notes).

    Parameters
    ----------
    chains : ndarray
        Thinned draws, shape (ensembles, draws, params), step-major as
        :class:`~bayestribo.inference.sampling.SamplerRun` keeps them.
    log_prob : ndarray
        Log-posterior of each draw, shape (ensembles, draws).
    names : sequence of str
        Parameter names.
    n_walkers : int
        Walkers per ensemble (a kept step is ``n_walkers`` consecutive draws).

    Returns
    -------
    ModeReport
        Modes heaviest first; ``matters`` and ``reason`` say whether the draws can be
        summarised as one population.
    """
    chains = np.asarray(chains, dtype=float)
    n_ens, n_draws, ndim = chains.shape
    names = tuple(names) if len(names) == ndim else tuple(f"theta[{i}]" for i in range(ndim))
    flat = chains.reshape(-1, ndim)
    lp = np.asarray(log_prob, dtype=float).reshape(-1)
    per_step = max(int(n_walkers), 1)
    steps = np.tile(np.arange(n_draws) // per_step, n_ens)
    walker = np.repeat(np.arange(n_ens), n_draws) * per_step + np.tile(
        np.arange(n_draws) % per_step, n_ens
    )
    draws_per_walker = np.bincount(walker, minlength=n_ens * per_step)
    last_step = max(int(steps.max()), 1) if steps.size else 1
    finite = np.all(np.isfinite(flat), axis=1)
    groups = _groups(flat[finite]) if np.count_nonzero(finite) >= 2 * MIN_DRAWS else []
    where = np.flatnonzero(finite)
    groups = [where[g] for g in groups] or [np.arange(flat.shape[0])]
    groups.sort(key=lambda g: -g.size)
    total = sum(g.size for g in groups)
    modes = []
    for k, g in enumerate(groups):
        first, last = steps[g].min() / last_step, steps[g].max() / last_step
        occupancy = np.bincount(walker[g], minlength=draws_per_walker.size)
        share = occupancy / np.maximum(draws_per_walker, 1)
        stuck = share >= STUCK_FRACTION
        from_stuck = occupancy[stuck].sum() / max(g.size, 1)
        if k == 0:
            kind = "main"
        elif last < TRANSIENT_BEFORE:
            kind = "transient"
        elif from_stuck >= STUCK_FRACTION or np.count_nonzero(occupancy) <= max(
            1, FEW_WALKERS * draws_per_walker.size
        ):
            kind = "stuck"
        else:
            kind = "mode"
        modes.append(
            Mode(
                weight=g.size / total,
                mean=dict(zip(names, flat[g].mean(axis=0).tolist(), strict=True)),
                sd=dict(zip(names, flat[g].std(axis=0).tolist(), strict=True)),
                log_prob=float(np.mean(lp[g])) if lp.size == flat.shape[0] else float("nan"),
                n_draws=int(g.size),
                steps=(float(first), float(last)),
                kind=kind,
                walkers=int(np.count_nonzero(occupancy)),
                stuck_walkers=int(np.count_nonzero(stuck)),
            )
        )
    main = modes[0]
    mattering = [m for m in modes[1:] if _matters(m, main)]
    return ModeReport(modes, names, bool(mattering), _reason(mattering, main) if mattering else "")


def _shift(minor: Mode, main: Mode) -> float:
    """Largest shift of a parameter's mean the minor mode causes [main-mode sd]."""
    out = 0.0
    for name, value in minor.mean.items():
        sd = main.sd[name]
        if sd > 0.0:
            out = max(out, minor.weight * abs(value - main.mean[name]) / sd)
    return out


def _matters(minor: Mode, main: Mode) -> bool:
    return minor.weight >= MIN_WEIGHT or _shift(minor, main) >= MIN_SHIFT


def _reason(minor: list[Mode], main: Mode) -> str:
    parts = []
    for m in minor:
        at = ", ".join(f"{n}={v:.4g}" for n, v in m.mean.items())
        dlp = main.log_prob - m.log_prob
        what = {
            "transient": "a transient the walkers left by "
            f"{100 * m.steps[1]:.0f} % of the kept steps (burn-in too short; not draws "
            "of the posterior)",
            "stuck": f"a region where {m.walkers} walker(s) stay (until "
            f"{100 * m.steps[1]:.0f} % of the kept steps) while the others never go there "
            "(its weight is not a probability)",
        }.get(m.kind, "a separate mode the walkers cross to and from")
        parts.append(
            f"{100 * m.weight:.2g} % of the draws are in {what}, at {at}, log-posterior "
            f"{dlp:.3g} below the main mode"
        )
    mains = ", ".join(f"{n}={v:.4g}" for n, v in main.mean.items())
    return (
        "the draws hold separated populations, not one posterior summary: "
        + "; ".join(parts)
        + f" (main mode {100 * main.weight:.3g} % at {mains})"
    )


def mode_check(sampled: Any) -> tuple[Any, ModeReport]:
    """The modes of a sampled posterior, and the sampled posterior they leave.

    Parameters
    ----------
    sampled : Sampled
        From :func:`bayestribo.inference.chains.sample` (its ``run`` is a
        :class:`~bayestribo.inference.sampling.SamplerRun`, its ``settings`` give the
        walkers per ensemble).

    Returns
    -------
    sampled : Sampled
        ``sampled`` itself; when every minor mode that matters is a transient of a
        converged run, a copy with the burn-in extended past it where the draws left
        still meet the sampler's rule (:func:`_past_transients`); otherwise, when a
        minor mode matters, a copy whose run is not converged with the modes' reason
        added to its reasons.
    report : ModeReport
        Of the draws in the ``sampled`` returned.
    """
    run = sampled.run
    report = find_modes(run.chains, run.log_prob, run.names, sampled.settings.n_walkers)
    if report.matters and run.converged:
        # -- a transient the burn-in did not cover: the burn-in extended past it --
        trimmed = _past_transients(sampled, report)
        if trimmed is not None:
            return trimmed
    if report.matters:
        run = replace(run, converged=False, reasons=[*run.reasons, report.reason])
        sampled = replace(sampled, run=run)
    return sampled, report


def transient_steps(
    chains: NDArray, log_prob: NDArray, names: Sequence[str], n_walkers: int
) -> int:
    """Kept steps at the start of the draws that hold the walkers' way to the posterior.

    Parameters
    ----------
    chains, log_prob, names, n_walkers
        As :func:`find_modes` takes them.

    Returns
    -------
    int
        The kept steps up to the last visit of the transients (rule 6 of the module
        notes) when every minor mode that matters is one and what follows them holds
        no minor mode that matters; 0 otherwise (no transient, or other modes).
    """
    report = find_modes(chains, log_prob, names, n_walkers)
    if not report.matters:
        return 0
    minor = [m for m in report.modes[1:] if _matters(m, report.modes[0])]
    if any(m.kind != "transient" for m in minor):
        return 0
    per_step = max(int(n_walkers), 1)
    kept = np.asarray(chains).shape[1] // per_step
    cut = max(round(m.steps[1] * max(1, kept - 1)) for m in minor) + 1
    if cut >= kept - 1:
        return 0
    rest = np.asarray(log_prob)[:, cut * per_step :]
    if find_modes(np.asarray(chains)[:, cut * per_step :], rest, names, n_walkers).matters:
        return 0
    return int(cut)


def _past_transients(sampled: Any, report: ModeReport) -> tuple[Any, ModeReport] | None:
    """The sampled posterior with its burn-in extended past the transients of
    ``report`` (:func:`transient_steps`), when what is left meets the sampler's rule;
    else None.

    A transient holds the walkers' way from where they started to the posterior (its
    draws are not the posterior's: rule 6 of the module notes). The kept steps up to
    its last visit are dropped, in every ensemble; the rest must still hold the
    sampler's required autocorrelation times after the burn-in
    (:meth:`~bayestribo.inference.sampling.SamplerSettings.required_multiple`) and have R-hat below
    ``rhat_max`` for every parameter. The report returned is that of the draws kept,
    with ``dropped_steps`` the sampler steps added to the burn-in.
    """
    run, settings = sampled.run, sampled.settings
    per_step = max(int(settings.n_walkers), 1)
    cut = transient_steps(run.chains, run.log_prob, run.names, per_step)
    if cut == 0:
        return None
    burn = run.burn + cut * run.thin
    required = settings.required_multiple()
    if not run.n_steps - burn >= required * float(np.max(run.autocorr_time)):
        return None
    chains = run.chains[:, cut * per_step :]
    log_prob = run.log_prob[:, cut * per_step :]
    r_hat = rhat(chains)
    if not np.all(r_hat < settings.rhat_max):
        return None
    after = find_modes(chains, log_prob, run.names, per_step)
    n_ens = run.chains.shape[0]
    trimmed = replace(
        run,
        chains=chains,
        log_prob=log_prob,
        burn=burn,
        rhat=r_hat,
        ess=(run.n_steps - burn) * per_step * n_ens / run.autocorr_time,
    )
    pointwise = sampled.pointwise
    if pointwise is not None:
        pointwise = pointwise[:, cut * per_step :]
    return (
        replace(sampled, run=trimmed, pointwise=pointwise),
        replace(after, dropped_steps=cut * run.thin),
    )
