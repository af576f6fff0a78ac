"""Synthetic recordings: a realistic simulator of the rig and the bundled campaign.

Modules
-------
setup
    What a simulated test is made of: :class:`DissipationLaw` or
    :class:`LawParameters` (any registered law), :class:`Release`, :class:`Sensor`
    (with the rig, :class:`bayestribo.model.scaling.Rig`).
recording
    :func:`simulate`: one free-decay recording on the exact model, or of any law by
    :mod:`~bayestribo.synthetic.motion`, with the sensor's noise and the rig's
    imperfections.
motion
    The motion of any registered law by ``solve_ivp``, independent of the fit's
    integrator.
campaign
    The paper's test programme (air, glycerol at five loads, glycerol-water) as a
    simulated campaign, with its manifest of true values.
"""

from bayestribo.synthetic.recording import simulate
from bayestribo.synthetic.setup import (
    DISPLACEMENT_RESOLUTION_M,
    PAPER_RIG,
    VELOCITY_RESOLUTION_M_PER_S,
    AmplitudeLaw,
    DissipationLaw,
    LawParameters,
    Release,
    Sensor,
)

__all__ = [
    "DISPLACEMENT_RESOLUTION_M",
    "PAPER_RIG",
    "VELOCITY_RESOLUTION_M_PER_S",
    "AmplitudeLaw",
    "DissipationLaw",
    "LawParameters",
    "Release",
    "Sensor",
    "simulate",
]
