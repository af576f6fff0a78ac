"""The package's own exceptions and warnings.

Every error a user can provoke with bad input derives from :class:`BayestriboError`,
so a caller can catch the package's errors apart from programming errors. Errors
about argument *values* of pure functions are ``ValueError`` subclasses as well, so
``except ValueError`` keeps working for numerical callers.
"""

from __future__ import annotations

__all__ = [
    "AcquisitionError",
    "ArmNoiseWarning",
    "BayestriboError",
    "BinnedRecordWarning",
    "ClockRestartWarning",
    "CoarseSignalWarning",
    "ConvergenceWarning",
    "CreepWarning",
    "EnergyGainWarning",
    "FadeWarning",
    "FrequencyTrendWarning",
    "GapWarning",
    "HighPassWarning",
    "ImplausibleFrictionWarning",
    "LinearSpringWarning",
    "MisfitWarning",
    "MissingDependencyError",
    "NominalFrequencyWarning",
    "OffsetDriftWarning",
    "PluginWarning",
    "ReadingWarning",
    "RecordingError",
    "RunFormatError",
    "SeparateMotionWarning",
    "ShapeUnresolvedWarning",
    "ShortAnalysisWarning",
    "SpikeWarning",
]


class BayestriboError(Exception):
    """Base class of every error raised by bayestribo on bad input or bad data."""


class RecordingError(BayestriboError, ValueError):
    """A recorded signal cannot be analysed (too short, irregular, not oscillating...).

    Parameters
    ----------
    message : str
        What is wrong, naming the field and what was expected.
    where : str, optional
        The file, channel or sample range concerned.
    """

    def __init__(self, message: str, where: str | None = None) -> None:
        self.where = where
        self.message = message
        super().__init__(f"{where}: {message}" if where else message)


class RunFormatError(RecordingError):
    """A run file or its sidecar does not follow the expected format."""


class AcquisitionError(BayestriboError, OSError):
    """The acquisition link failed (timeout, disconnect, bad frame, busy port)."""


class MissingDependencyError(BayestriboError, ImportError):
    """A feature needs an optional package that is not installed (the message names
    the extra to install)."""


class ConvergenceWarning(UserWarning):
    """A sampler run did not meet its convergence criteria."""


class MisfitWarning(UserWarning):
    """The model does not reproduce the data within their noise (intervals too narrow)."""


class FrequencyTrendWarning(UserWarning):
    """The half period changes along the decay beyond what the law makes (a stiffness
    that depends on amplitude): the reported quantities carry it as a frequency
    nuisance, so the intervals hold it (the message gives the change and the nuisance)."""


class LinearSpringWarning(FrequencyTrendWarning, MisfitWarning):
    """A :class:`FrequencyTrendWarning` on the linear spring with a law whose half
    period is constant (viscous damping and Coulomb friction, the closed forms): the
    half period changes with amplitude beyond its noise, which neither the spring nor
    the law makes. The intervals carry the frequency nuisance, but they are then wide for
    what the record holds and the law's parameters are those of an average spring; the
    message names the restoring force to try (``--restoring auto``). A misfit: ``fit``
    exits 1."""


class ReadingWarning(UserWarning):
    """A file was read with rows left out (empty cells at its start or end, or rows
    that repeat the one before exactly): the message names the lines or samples and
    the columns."""


class MetadataWarning(UserWarning):
    """A metadata value was missing and the package took it from the recording (the
    message says which value, and how to give it instead)."""


class PriorBoundWarning(UserWarning):
    """A posterior piles on a physical bound of its prior: no measurement (the message
    names the parameter and what to check)."""


class ChannelCalibrationWarning(UserWarning):
    """The displacement and velocity channels disagree (v ≠ dx/dt) in gain or delay by
    more than the recording's own uncertainty (the message gives both, and what was
    done)."""


class ClippingWarning(UserWarning):
    """The largest swings of a recording are flattened at their peaks (a sensor that
    saturates softly, or a spring that softens): their cycles were left out of the
    analysis (the message says how many, at which swing and by how much)."""


class GapWarning(UserWarning):
    """Samples were missing from a recording's clock and the gaps were bridged on the
    regular grid (the message names each gap: after which sample, how many samples, and
    the interpolation's error bound against the noise)."""


class ClockRestartWarning(UserWarning):
    """A recording's time stamps restart and the signal goes on smoothly across: the
    stamps after the restart were continued by one sample step (the message names the
    sample and the stamps)."""


class SpikeWarning(UserWarning):
    """Isolated samples far off their neighbours were left out of the analysis (the
    message names the channel, times and values)."""


class BinnedRecordWarning(UserWarning):
    """A record refused on its raw samples (its swings within ten times its noise per
    sample, though a period holds many samples) was analysed averaged in bins of
    consecutive samples (:mod:`bayestribo.signal.binning`; the message names the bin,
    the samples a period and the raw record's refusal)."""


class SeparateMotionWarning(UserWarning):
    """The record holds more than one motion, separated by rests (runs recorded back to
    back, a knock after the stop): the analysis takes the largest and the rests beside
    it, and leaves the others out (the message names their times and the ``--window``
    that analyses another)."""


class FadeWarning(UserWarning):
    """A decay fades into the noise: its last turning points, of swings within the
    noise's reach, break its half period and are left out; the analysis ends at the
    last turning point before them (the message names it)."""


class PluginWarning(UserWarning):
    """A dissipation term offered by an installed package (entry point group
    ``bayestribo.terms``) could not be loaded; its terms are not available."""


class CoarseSignalWarning(MisfitWarning):
    """A coarse channel (steps its noise does not dither) leaves the intervals
    uncalibrated or wide: it holds fewer than four of its steps across the motion's
    swing (the turning points stand on a few levels), its swings sink below two steps
    within three oscillations (the analysis takes two, the one skipped after the release
    included where it is what the record lacks), or it is a velocity recorded alone,
    whose rounding accumulates in its integral. The message names the channel, its step
    and the count."""


class EnergyGainWarning(MisfitWarning):
    """The law-free ΔE(A) (the turning points' energy lost per cycle) is below zero
    beyond its interval at some swings: an energy gain, which no free decay has, so the
    turning points there are not the motion's. The message gives the swings. A misfit:
    ``fit`` exits 1."""


class OffsetDriftWarning(MisfitWarning):
    """A velocity recorded alone is not at one level at rest: its level before the
    release and after the motion differ beyond its noise (an offset that drifts). The
    displacement integrated from it wanders off its equilibrium between the rests, which
    the noise model does not hold (the message gives both levels and the difference)."""


class CreepWarning(MisfitWarning):
    """The mass still moves after the stop: it creeps towards the equilibrium, which no
    law's motion does (a friction sticks, a drag oscillates on), so the friction
    vanishes towards zero speed and the law's ΔE(A) at the smallest swings is not to be
    trusted; the creep is not taken as rest, the noise is measured elsewhere, and the
    turning points' ΔE(A) is the answer. The message gives the times, the drift and
    where the noise comes from. A misfit: ``fit`` exits 1."""


class ShapeUnresolvedWarning(MisfitWarning):
    """``law="auto"``: laws whose ΔE(A) has another shape over the analysed swings (log-log
    slopes more than 0.5 apart: friction's A¹ against drag's A²) are as good as the
    verdict, so the record does not tell which law dissipates; the verdict's parameters
    hold only if its law is the one. The message names the laws and their slopes, and
    the ΔE(A) averaged over them (or the turning points') is the answer. A misfit:
    ``fit`` exits 1."""


class ArmNoiseWarning(MisfitWarning):
    """A length read as a pendulum's angle (``pendulum_radius_m``) swings beyond 48°:
    its noise grows as 1/cos θ, to more than 1.5 times its value at rest at the largest
    angle, and the fit takes it as at rest, so the law's intervals are not calibrated
    there (simple pendulums released at 60°: 4 of 10 ζ intervals missed, 2 with no
    other warning; at 20° and 40° 20 of 20 covered, ``benchmarks/pendulum_arm.py``).
    The turning points' ΔE(A) is the answer. A misfit: ``fit`` exits 1."""


class HighPassWarning(MisfitWarning):
    """The record bears a sensor high-pass's sign (an AC-coupled channel, a geophone):
    its swing's centre relaxes from the release toward the rest as exp(-ω_c t)
    (:func:`bayestribo.signal.high_pass.detect_high_pass`). The message gives the corner
    frequency the centres give and the option that undoes it (``--sensor-high-pass``).
    A misfit: ``fit`` exits 1."""


class ShortAnalysisWarning(MisfitWarning):
    """The analysis covers less than half of the motion the record holds; the message
    names the analysed span, the motion's span and why."""


class ImplausibleFrictionWarning(MisfitWarning):
    """μ_k's interval lies wholly above any contact's kinetic friction coefficient
    (:data:`bayestribo.inference.plausibility.MU_K_LIMIT`): the run's load or mass is
    likely in another unit (grams under ``mass_kg``, millinewtons under ``load_N``).
    The message gives the interval and the load and mass it was computed from. Not a
    measurement: ``fit`` exits 1."""


class NominalFrequencyWarning(MisfitWarning):
    """The natural frequency measured from the record is more than
    :data:`bayestribo.inference.nominal_frequency.NOMINAL_TOLERANCE` from the nominal
    ``natural_frequency_Hz`` given with it: the stiffness k = m(2πf)², hence μ_k, takes
    the measured one, which is wrong where the record's clock is off. The message gives
    both and the option that reads the record at the nominal frequency. Not a
    measurement until one of the two is corrected: ``fit`` exits 1."""
