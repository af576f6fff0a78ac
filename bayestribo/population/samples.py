"""Per-run posterior samples with their prior densities: the input of the population.

The population of repeats reuses each run's posterior samples. To do so it needs, at
every sample, the density of the prior the run was fitted with, which is divided out
(see :mod:`bayestribo.population.likelihood`). :class:`RunSamples` holds both, and
:func:`run_samples` builds it from a single-run fit result (any object with
``samples(name)``, ``prior_logpdf(name, values)`` and ``metadata``, such as
:class:`bayestribo.inference.FitResult`).
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError

__all__ = ["FitLike", "RunSamples", "as_run_samples", "run_samples"]


@runtime_checkable
class FitLike(Protocol):
    """What the population needs of a single-run fit result."""

    metadata: Mapping[str, Any]

    def samples(self, name: str) -> NDArray[np.float64]: ...

    def prior_logpdf(self, name: str, values: NDArray[np.float64]) -> NDArray[np.float64]: ...


@dataclass(frozen=True)
class RunSamples:
    """Posterior samples of one run and the log prior density at each of them.

    Attributes
    ----------
    name : str
        The run's name (its ``run_id``).
    values : dict of str to ndarray
        Parameter name -> 1-D posterior samples (all the same length).
    log_prior : ndarray
        Sum over the parameters of the log prior density at each sample; the per-run
        priors are independent, so this is the log joint prior density.
    metadata : dict
        The run's metadata (grouping keys such as ``load_N`` or ``lubricant``).
    """

    name: str
    values: dict[str, NDArray[np.float64]]
    log_prior: NDArray[np.float64]
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.values:
            raise BayestriboError(f"run {self.name!r}: no parameters")
        lengths = {k: np.shape(v) for k, v in self.values.items()}
        n = len(self.log_prior)
        for key, shape in lengths.items():
            if shape != (n,):
                raise BayestriboError(
                    f"run {self.name!r}: samples of {key!r} have shape {shape}, expected "
                    f"({n},) like the log prior"
                )
            if not np.all(np.isfinite(self.values[key])):
                raise BayestriboError(f"run {self.name!r}: non-finite samples of {key!r}")
        if n < 2:
            raise BayestriboError(f"run {self.name!r}: expected at least 2 samples, got {n}")
        if not np.all(np.isfinite(self.log_prior)):
            raise BayestriboError(
                f"run {self.name!r}: the prior density is zero or not finite at some "
                "posterior samples; the samples and the prior do not belong together"
            )

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return len(self.log_prior)


def run_samples(
    result: FitLike,
    parameters: Sequence[str],
    *,
    max_samples: int | None = None,
    seed: int = 0,
    name: str | None = None,
) -> RunSamples:
    """Extract the samples of ``parameters`` and their prior densities from a fit result.

    Parameters
    ----------
    result : FitLike
        A single-run fit result (``samples``, ``prior_logpdf``, ``metadata``).
    parameters : sequence of str
        Parameter names, e.g. ``("zeta", "mu_k")``.
    max_samples : int, optional
        Keep a random subset (without replacement, seeded) of at most this many
        samples, to bound the cost of the population likelihood.
    seed : int
        Seed of the subset; combined with the run's name, so a run keeps the same
        subset whatever the order of the runs.
    name : str, optional
        The run's name; default ``metadata["run_id"]``, else ``result.run_name``.
    """
    metadata = dict(getattr(result, "metadata", {}) or {})
    if name is None:
        name = str(metadata.get("run_id") or getattr(result, "run_name", None) or "run")
    values: dict[str, NDArray[np.float64]] = {}
    log_prior: NDArray[np.float64] | None = None
    for key in parameters:
        try:
            s = np.asarray(result.samples(key), dtype=float).ravel()
        except (KeyError, ValueError) as exc:
            raise BayestriboError(
                f"run {name!r}: no posterior samples of {key!r} ({exc})"
            ) from None
        lp = np.asarray(result.prior_logpdf(key, s), dtype=float).ravel()
        if lp.shape != s.shape:
            raise BayestriboError(
                f"run {name!r}: prior_logpdf({key!r}) returned shape {lp.shape}, expected {s.shape}"
            )
        values[key] = s
        log_prior = lp if log_prior is None else log_prior + lp
    assert log_prior is not None
    n = len(log_prior)
    rng = _rng(seed, name)
    if max_samples is not None:
        if not (isinstance(max_samples, int) and max_samples >= 2):
            raise BayestriboError(f"max_samples: expected an integer >= 2, got {max_samples!r}")
        if n > max_samples:
            keep = np.sort(rng.choice(n, size=max_samples, replace=False))
            values = {k: v[keep] for k, v in values.items()}
            log_prior = log_prior[keep]
    return RunSamples(name, values, log_prior, metadata)


def as_run_samples(
    runs: Iterable[RunSamples | FitLike],
    parameters: Sequence[str],
    *,
    max_samples: int | None = 1000,
    seed: int = 0,
) -> list[RunSamples]:
    """Convert fit results (or pass :class:`RunSamples` through), with per-run subset seeds.

    Each run's subset is drawn from a seed derived from ``seed`` and the run's name,
    so the population is reproducible and does not depend on the order of the runs.
    """
    out: list[RunSamples] = []
    for run in runs:
        if isinstance(run, RunSamples):
            out.append(_subset(run, parameters, max_samples, _rng(seed, run.name)))
        else:
            out.append(run_samples(run, parameters, max_samples=max_samples, seed=seed))
    if not out:
        raise BayestriboError("runs: expected at least one run, got none")
    names = [r.name for r in out]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise BayestriboError(f"runs: duplicate run names {dup}")
    return out


def _rng(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def _subset(
    run: RunSamples, parameters: Sequence[str], max_samples: int | None, rng: np.random.Generator
) -> RunSamples:
    """The parameters' samples of ``run``, at most ``max_samples`` of them (random subset).

    The log prior of the kept samples must then cover only ``parameters``: a
    :class:`RunSamples` with more parameters than asked for is refused.
    """
    missing = [p for p in parameters if p not in run.values]
    if missing:
        raise BayestriboError(f"run {run.name!r}: no posterior samples of {missing}")
    extra = sorted(set(run.values) - set(parameters))
    if extra:
        raise BayestriboError(
            f"run {run.name!r}: its log prior also covers {extra}; give RunSamples with "
            f"exactly the parameters {list(parameters)}"
        )
    if max_samples is None or run.n_samples <= max_samples:
        return run
    keep = np.sort(rng.choice(run.n_samples, size=max_samples, replace=False))
    return RunSamples(
        run.name, {k: v[keep] for k, v in run.values.items()}, run.log_prior[keep], run.metadata
    )
