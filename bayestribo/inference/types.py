"""The types the stages of a fit hand each other, at the bottom of the import graph.

:class:`PreparedRun` is what the prepare stage gives (:mod:`bayestribo.inference.
preparation`) and every later stage takes; :class:`Sampled` is what the sample stage
gives (:mod:`bayestribo.inference.chains`) and the check and summarise stages take
(:mod:`bayestribo.inference.checks`, :mod:`bayestribo.inference.summarising`). The
thresholds several stages share live here too.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from numpy.typing import NDArray

from bayestribo.inference.sampling import (
    FIT_AUTOCORR_MULTIPLE,
    FIT_INDEPENDENCE,
    FIT_INDEPENDENCE_LIMIT,
    FIT_MAX_DRAWS,
    FIT_MIN_ESS,
    SamplerSettings,
)

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior
    from bayestribo.inference.sampling import SamplerRun
    from bayestribo.inference.surrogate import SurrogateCheck
    from bayestribo.io.run import Run
    from bayestribo.signal.decay import EnergyDecay
    from bayestribo.signal.increments import PiData
    from bayestribo.signal.noise import NoiseModel

__all__ = ["DEFAULT_SETTINGS", "MISFIT_P", "PreparedRun", "Sampled"]

#: Sampler settings of a default fit.
DEFAULT_SETTINGS = SamplerSettings(
    n_walkers=16,
    n_ensembles=2,
    max_steps=20_000,
    autocorr_multiple=FIT_AUTOCORR_MULTIPLE,
    min_ess=FIT_MIN_ESS,
    independence=FIT_INDEPENDENCE,
    max_draws=FIT_MAX_DRAWS,
    independence_limit=FIT_INDEPENDENCE_LIMIT,
    debias=True,
)

#: χ² p-value of the MAP residuals below which a fit warns of misfit.
MISFIT_P = 1e-3


@dataclass(frozen=True)
class PreparedRun:
    """A run ready for inference: what the likelihood observes, and where it came from.

    Attributes
    ----------
    run : Run
        The recording.
    name : str
        Its name in messages and results (file or ``run_id``).
    decay : EnergyDecay
        The analysed window and its energy decay.
    noise : NoiseModel
        Nominal resolution against the noise measured at rest.
    data : PiData
        Π increments and their noise variances.
    grid_points, skip_oscillations : int or None
        The preparation settings, recorded in the result.
    channels : dict or None
        The channel calibration (:func:`bayestribo.inference.calibration.calibrate_channels`),
        None for a run with one signal.
    noise_given : bool
        True when the noise model was given rather than measured in the recording.
    filter_undone : bool
        True when the run's declared first-order filter was undone on its channels
        (:func:`bayestribo.signal.sensor.undo_first_order`): ``run`` holds them so.
    restoring_choice : RestoringChoice or None
        For a run whose ``restoring`` was ``"auto"``: the force chosen and why
        (:func:`bayestribo.inference.restoring_choice.choose_restoring`); ``run``'s
        metadata name the force chosen.
    """

    run: Run
    name: str
    decay: EnergyDecay
    noise: NoiseModel
    data: PiData
    grid_points: int | None = None
    skip_oscillations: int = 1
    channels: dict[str, Any] | None = None
    noise_given: bool = False
    filter_undone: bool = False
    restoring_choice: Any = None

    @property
    def metadata(self) -> dict[str, Any]:
        """The run's metadata."""
        return dict(self.run.metadata)

    @property
    def contact(self) -> bool:
        """False for a test without contact (``load_N`` of 0): no friction to fit."""
        return self.run.metadata.get("load_N") != 0


@dataclass(frozen=True)
class Sampled:
    """The sampled posterior.

    Attributes
    ----------
    posterior : Posterior
    theta_map : ndarray
        Maximum a posteriori in sampling coordinates.
    run : SamplerRun
        Chains and convergence diagnostics.
    settings : SamplerSettings
    surrogate : SurrogateCheck or None
        For a law without a closed form, the check of the quadratic surrogate of Π
        (:mod:`bayestribo.inference.surrogate`): passed when the chains are the
        surrogate posterior's, failed when they are the exact posterior's after it;
        None when no surrogate was tried.
    surrogate_posterior : Posterior or None
        The surrogate posterior the chains sampled (None: the exact one).
    pointwise : ndarray or None
        The exact posterior's pointwise log-likelihood of the chains' draws, (chains,
        draws, m), where the sampler computed it already (draws of a surrogate
        corrected by their importance weights, :mod:`bayestribo.inference.correction`);
        PSIS-LOO takes it (:func:`bayestribo.inference.loo.sampled_pointwise`).
    log_prob_deferred : callable or None
        Where some draws were set after sampling (a nested law's draws mixed in at a
        boundary, :mod:`bayestribo.inference.boundary`): a function of no arguments that
        gives the log posterior density of every draw, shape (chains, draws), the
        draws set there evaluated when it is called; ``run.log_prob`` holds NaN at
        them meanwhile. None: ``run.log_prob`` is complete.
    """

    posterior: Posterior
    theta_map: NDArray
    run: SamplerRun
    settings: SamplerSettings
    surrogate: SurrogateCheck | None = None
    surrogate_posterior: Posterior | None = None
    pointwise: NDArray | None = field(default=None, repr=False, compare=False)
    log_prob_deferred: Callable[[], NDArray] | None = field(default=None, repr=False, compare=False)

    @property
    def draws_posterior(self) -> Posterior:
        """The posterior whose density the chains sampled: the surrogate's where its
        check passed (it then stands for the exact one within
        :data:`~bayestribo.inference.surrogate.MAX_WEIGHT_CV`), else the exact."""
        return self.surrogate_posterior if self.surrogate_posterior is not None else self.posterior
