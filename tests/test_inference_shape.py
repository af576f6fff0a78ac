"""A law whose ΔE(A) has another shape than the turning points' is never reported as
holding, even where the χ² test cannot see it (a noise overstated), and the
comparison says how close each law came.

Independent simulations: ``solve_ivp`` of x'' + γ x'|x'| + ω² x = 0 (a disc in air on a
spring at 1.35 Hz; ΔE ∝ A³) and of x'' + 2ζω x' + ω² x = 0 (ΔE ∝ A²), sampled at
100 Hz in an arbitrary length unit.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo import fit
from bayestribo.errors import MisfitWarning
from bayestribo.inference.dissipation import shape_agreement
from bayestribo.io.run import Run

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

F_HZ, GAMMA, X0, FS = 1.35, 0.6, 0.08, 100.0


@functools.lru_cache(maxsize=2)
def _record(drag: str) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic drag (a disc in air) or viscous damping of the same first decrement."""
    omega = 2 * math.pi * F_HZ
    t = np.arange(0.0, 60.0, 1.0 / FS)
    if drag == "quadratic":
        force = lambda w: GAMMA * w * abs(w)  # noqa: E731
    else:
        force = lambda w: 2 * 0.004 * omega * w  # noqa: E731
    sol = solve_ivp(
        lambda _t, u: [u[1], -force(u[1]) - omega**2 * u[0]],
        (0.0, t[-1]),
        [X0, 0.0],
        t_eval=t,
        rtol=1e-10,
        atol=1e-13,
    )
    return t, sol.y[0] + np.random.default_rng(5).normal(0, 2e-5, t.size)


def _run(drag: str, **metadata) -> Run:
    t, x = _record(drag)
    return Run(t, x, metadata={"length_unit": "arbitrary", **metadata})


def test_the_slopes_of_friction_and_drag_differ_by_their_powers():
    amp = np.geomspace(0.01, 0.08, 12)
    measured = {
        "amplitude": amp.tolist(),
        "mean": (amp**3).tolist(),
        "sd": (0.01 * amp**3).tolist(),
    }
    friction = {"amplitude": amp.tolist(), "mean": (4 * amp).tolist()}
    drag = {"amplitude": amp.tolist(), "mean": (1.02 * amp**3).tolist()}
    assert shape_agreement(drag, measured)["same_shape"]
    assert shape_agreement(drag, measured)["max_percent"] == pytest.approx(2.0)
    odd = shape_agreement(friction, measured)
    assert not odd["same_shape"]
    assert odd["law_slope"] == pytest.approx(1.0) and odd["measured_slope"] == pytest.approx(3.0)


@pytest.mark.parametrize(
    ("drag", "law", "slope"), [("quadratic", "coulomb", 3), ("viscous", "coulomb", 2)]
)
def test_friction_on_drag_is_flagged_by_its_shape_when_the_noise_hides_the_misfit(drag, law, slope):
    # a noise of an eighth of the swing (as taken from a coarsely quantised segment that
    # still oscillates): the χ² test passes the wrong law; the shape does not
    run = _run(drag, displacement_resolution_m=1e-2)
    with pytest.warns(
        MisfitWarning, match=rf"another shape.*A\^1\.\d\d.*points' as A\^{slope}\.\d"
    ):
        result = fit(run, law=law, seed=2, grid_points=32)
    assert "ANOTHER SHAPE" in result.to_text()
    assert result.law_departs and not result.shape_agreement["same_shape"]


def test_the_right_law_has_the_turning_points_shape():
    with warnings.catch_warnings():
        warnings.simplefilter("error", MisfitWarning)
        right = fit(
            _run("viscous", displacement_resolution_m=1e-2), law="viscous", seed=2, grid_points=32
        )
    assert right.shape_agreement["same_shape"] and "ANOTHER SHAPE" not in right.to_text()
    assert abs(right.shape_agreement["law_slope"] - 2.0) < 1e-6


@pytest.mark.parametrize("half_cycles", [3, 5, 7])
def test_a_few_half_cycles_still_give_a_wide_law_free_answer(half_cycles):
    """A torsion pendulum recorded for two seconds, a seismometer's few swings: fewer
    than eight half cycles, a law-free ΔE(A) with a wide interval that holds the truth
    (viscous damping: Y_n = Y_0 exp(-πζn), ΔE = 2πζA² per cycle to first order in ζ)."""
    from bayestribo.inference.dissipation import turning_point_dissipation
    from bayestribo.model.laws import PhysicalScale

    zeta = 0.01
    n = np.arange(half_cycles + 1)
    noise = np.random.default_rng(half_cycles).normal(0, 1e-4, n.size)
    turning = (1.0 + noise) * np.exp(-math.pi * zeta * n) * (-1.0) ** n
    swings = np.geomspace(0.9, 0.98, 3)
    found = turning_point_dissipation(turning, swings, PhysicalScale())
    truth = 2 * math.pi * zeta * swings**2
    lo, hi = (np.asarray(side) for side in found["interval"])
    assert np.all((lo < truth) & (truth < hi)) and np.all(np.isfinite(found["sd"]))
    assert turning_point_dissipation(turning[:3], swings, PhysicalScale()) is None
