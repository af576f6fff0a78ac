"""Windows of a velocity-only record (the displacement integrated from the velocity).

A record of the paper's rig with its velocity alone resolves μ_k to about 1e-5 of
itself in a window of two oscillations, so the windows see errors of the integrated
displacement that a recorded displacement's noise hides: the trapezoids' error at 300
samples a period, the equilibrium fitted to parabola-vertex turning points, the
integration constant's wander and the energy at rest after the stop. Before these were
dealt with, every such record of the law failed the constancy test (p about 1e-8).
"""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.adequacy.constancy import constancy_test
from bayestribo.adequacy.windows import analysed_decay, windowed_fits
from bayestribo.io.run import Run
from bayestribo.synthetic import DissipationLaw, Sensor
from bayestribo.synthetic.recording import simulate

ZETA, MU = 0.0236, 0.0294
X0 = 0.0015  # the default release [m]


def _law() -> DissipationLaw:
    return DissipationLaw(zeta=ZETA, mu_k=MU, mu_s=1.2 * MU)


def _velocity_only(law: DissipationLaw, seed: int) -> Run:
    return simulate(law, sensor=Sensor(channels=("velocity",)), seed=seed)


@pytest.fixture(scope="module")
def noise_free():
    """A noise-free record of the law with both channels, and its velocity alone."""
    run = simulate(
        _law(), sensor=Sensor(displacement_noise_m=0.0, velocity_noise_m_per_s=0.0), seed=0
    )
    return run, Run(run.time, None, run.velocity, dict(run.metadata))


def test_the_integrated_displacement_is_the_motion_up_to_a_line(noise_free):
    run, alone = noise_free
    decay = analysed_decay(alone)
    ell = decay.scaling.length_scale
    first = int(np.searchsorted(run.time, decay.t[0] - 1e-12))
    moving = decay.t < decay.stop_time - 2.0 * (decay.t[1] - decay.t[0])
    truth = run.displacement[first : first + decay.t.size][moving] / ell
    error = decay.y[moving] - truth
    line = np.polyval(np.polyfit(decay.tau[moving], error, 1), decay.tau[moving])
    # the trapezoids (gain divided out) left (ωh)²ζ/6 of the velocity: 1e-5 of ℓ
    assert np.max(np.abs(error - line)) < 1e-9


def test_the_equilibrium_of_the_integral_does_not_drift(noise_free):
    _, alone = noise_free
    decay = analysed_decay(alone)
    span = decay.t[-1] - decay.t[0]
    # turning points valued at parabola vertices (3e-4 of the swing low, unequally at
    # maxima and minima) put a drift of 6e-6 ℓ over the decay into the equilibrium
    assert abs(decay.equilibrium_drift) * span < 1e-7 * decay.scaling.length_scale


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_windows_of_the_law_are_constant(seed):
    windows = windowed_fits(_velocity_only(_law(), seed))
    test = constancy_test(windows)
    assert test.p_value > 0.01  # 5e-9 to 2e-8 when the windows drifted
    for w in windows.windows:
        assert abs(w.mu - MU) < 4.0 * w.mu_se
        assert abs(w.zeta - ZETA) < 4.0 * w.zeta_se


def test_a_growing_damping_still_fails_the_constancy_test():
    zeta_end = ZETA / 1.1  # ζ(a) = ζ_end (1 + 0.2 a/x₀): 20 % over the decay

    law = DissipationLaw(zeta=lambda a: zeta_end * (1.0 + 0.2 * a / X0), mu_k=MU, mu_s=1.2 * MU)
    test = constancy_test(windowed_fits(_velocity_only(law, 0)))
    assert not test.constant
    assert test.p_value < 1e-6
