"""``restoring="auto"``: the restoring force chosen from how the half period changes.

Independent simulations (``solve_ivp``): the pendulum released at 90° and the Duffing
spring of ``test_model_restoring``; a linear oscillator with viscous damping; the same
with a natural frequency that drifts in time (no restoring force follows that); and a
pendulum with viscous damping and Coulomb friction, simulated half cycle by half cycle
(the friction's sign fixed within each), for the fits.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_model_restoring import _duffing, _pendulum

from bayestribo import fit
from bayestribo.errors import FrequencyTrendWarning, MisfitWarning
from bayestribo.inference.restoring_choice import choose_restoring, trend_beyond
from bayestribo.io.run import Run
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.frequency import turning_point_trend

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")


def _choose(t, x, length_unit):
    """The choice on the record's turning points, and the warnings it gave."""
    decay = energy_decay(t, x, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        choice = choose_restoring(decay.turning_times, decay.peaks.value, length_unit=length_unit)
    return choice, [str(w.message) for w in caught if w.category is FrequencyTrendWarning]


@functools.lru_cache(maxsize=2)
def _linear(drift: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """x'' + 2ζω x' + ω² x = 0, ζ = 0.004, f₀ = 1.5 Hz (times 1 + drift t/T: a natural
    frequency that drifts in time), from 1 unit, 30 s at 200 Hz, noise 1e-4."""
    w0, duration = 2 * math.pi * 1.5, 30.0

    def rhs(t, u):
        w = w0 * (1.0 + drift * t / duration)
        return [u[1], -2 * 0.004 * w * u[1] - w * w * u[0]]

    t = np.arange(0.0, duration, 1 / 200.0)
    sol = solve_ivp(rhs, (0.0, t[-1]), [1.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-13)
    return t, sol.y[0] + np.random.default_rng(8).normal(0.0, 1e-4, t.size)


def test_a_pendulum_in_radians_is_a_pendulum():
    t, angle, _ = _pendulum()
    choice, said = _choose(t, angle, "rad")
    assert choice.name == "pendulum" and not said
    # its change is far beyond the noise, and the pendulum's half periods leave none
    assert choice.trend.significant and not choice.left["pendulum"].significant
    assert choice.describe().startswith("auto → pendulum: the half period changes by")


def test_a_duffing_spring_is_a_duffing_spring_with_its_beta():
    t, x, _, beta = _duffing()
    choice, said = _choose(t, x, "arbitrary")
    assert choice.name == "duffing" and not said
    assert "pendulum" not in choice.left  # not in radians: never examined as one
    # β from the package's turning times: 0.6007 (test_model_restoring)
    assert choice.beta == pytest.approx(beta, rel=5e-3)
    left = choice.left["duffing"]
    assert abs(left.change) < 0.01 * abs(choice.trend.change)


def test_a_linear_oscillator_is_linear():
    t, x = _linear()
    choice, said = _choose(t, x, "m")
    assert choice.name == "linear" and not said and not choice.trend.significant
    assert "constant within its noise" in choice.describe()
    # on the linear spring's own half periods (all equal) nothing is taken off
    decay = energy_decay(t, x, None)
    same = trend_beyond(decay.turning_times, decay.peaks.value, np.ones_like)
    measured = turning_point_trend(decay.turning_times, decay.peaks.value)
    # (to the rounding of the straight line through the equal steps)
    assert same.change == pytest.approx(measured.change, rel=1e-6)
    assert same.z == pytest.approx(measured.z, rel=1e-6)


def test_a_pendulums_change_in_metres_is_not_a_pendulum():
    # the pendulum's record said to be in metres: its change is a pendulum's only were the
    # displacement an angle in radians; the Duffing spring is taken, and the warning says
    # how a pendulum is fitted
    t, angle, _ = _pendulum()
    choice, said = _choose(t, angle, "m")
    assert choice.name == "duffing" and "pendulum" not in choice.left
    assert len(said) == 1 and "an angle in radians" in said[0]
    assert "--length-unit rad" in said[0] and "--restoring pendulum" in said[0]


def test_a_change_no_force_follows_keeps_the_one_that_leaves_least_and_says_so():
    # a frequency that drifts 1 % in time: the half period changes along the decay, and
    # the Duffing spring's change, concentrated at the large swings, does not follow it
    t, x = _linear(0.01)
    choice, said = _choose(t, x, "m")
    assert choice.trend.significant and not choice.followed
    found = {k: abs(v.change) for k, v in choice.left.items()}
    assert choice.name == min(found, key=found.get)
    assert len(said) == 1 and "no restoring force follows it" in said[0]
    assert "no force follows it" in choice.describe()


def test_too_few_turning_points_are_taken_as_linear_with_a_warning():
    t, x = _linear()
    decay = energy_decay(t, x, None)
    with pytest.warns(FrequencyTrendWarning, match="too few turning points"):
        choice = choose_restoring(decay.turning_times[:6], decay.peaks.value[:6], length_unit="m")
    assert choice.name == "linear" and choice.trend is None


# -- fits -------------------------------------------------------------------------------

F0, ZETA, MU, THETA0, FS = 0.5, 0.005, 0.004, math.pi / 2, 100.0


@functools.lru_cache(maxsize=1)
def _rubbing_pendulum() -> tuple[np.ndarray, np.ndarray]:
    """θ'' + 2ζω θ' + ω² (sin θ + μ sgn θ') = 0 released at rest at 90°: f₀ = 0.5 Hz,
    ζ = 0.005, μ = 0.004 rad (the friction as an angle), 40 s at 100 Hz, 1 mrad of
    noise; half cycle by half cycle, each ending at the velocity's zero."""
    w = 2 * math.pi * F0
    t = np.arange(0.0, 40.0, 1 / FS)
    x = np.empty_like(t)
    y, t0, filled = THETA0, 0.0, 0
    while filled < t.size:
        sgn = -1.0 if y > 0 else 1.0
        if abs(math.sin(y)) <= MU:
            x[filled:] = y  # at rest
            break

        def turned(_t, u):
            return u[1]

        turned.terminal = True
        turned.direction = 1.0 if sgn < 0 else -1.0
        sol = solve_ivp(
            lambda _t, u, s=sgn: [u[1], -2 * ZETA * w * u[1] - w * w * (math.sin(u[0]) + MU * s)],
            (t0, t0 + 10.0 / F0),
            [y, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(t, t1, side="right"))
        x[filled:stop] = sol.sol(t[filled:stop])[0]
        filled, y, t0 = stop, float(sol.y_events[0][0][0]), t1
    return t, x + np.random.default_rng(9).normal(0.0, 1e-3, t.size)


def _fit_pendulum(restoring):
    t, angle = _rubbing_pendulum()
    run = Run(t, angle, metadata={"length_unit": "rad", "gain_uncertainty": 0.0})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=3, grid_points=32, restoring=restoring)
    return result, [str(w.message) for w in caught if issubclass(w.category, FrequencyTrendWarning)]


def test_auto_fits_a_pendulum_as_the_pendulum_and_the_linear_fits_advice_works():
    _, said = _fit_pendulum(None)
    # the linear fit's warning advises --restoring auto ...
    assert said and "--restoring auto" in said[0]
    # ... which, followed, fits the pendulum exactly as --restoring pendulum does
    auto, said = _fit_pendulum("auto")
    pendulum, _ = _fit_pendulum("pendulum")
    assert not said
    assert auto.restoring["name"] == "pendulum" and auto.restoring["in_model"]
    assert auto.restoring["auto"]["chosen"] == "pendulum"
    assert auto.metadata["restoring"] == "pendulum" and auto.spec.restoring == "auto"
    assert "restoring auto → pendulum: the half period changes by" in auto.to_text()
    for name in ("zeta", "friction_displacement"):
        assert np.array_equal(auto.samples(name), pendulum.samples(name)), name
    # the truth inside the 95 % intervals: ζ, and the friction as an angle [rad]
    for name, truth in (("zeta", ZETA), ("friction_displacement", MU)):
        lo, hi = auto.interval(name, 0.95)
        assert lo <= truth <= hi, (name, lo, hi)


def test_auto_fits_a_duffing_spring_with_its_beta():
    t, x, _, beta = _duffing()
    run = Run(t, x, metadata={"length_unit": "arbitrary"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, law="viscous", seed=1, grid_points=32, restoring="auto")
    spring = result.restoring
    assert spring["name"] == "duffing" and spring["auto"]["chosen"] == "duffing"
    assert spring["beta"] == pytest.approx(beta, rel=5e-3)
    assert "restoring auto → duffing" in result.to_text() and "β = " in result.to_text()
    lo, hi = result.interval("zeta", 0.95)
    assert lo <= 0.004 <= hi


def test_auto_on_the_bundled_run_is_the_default_fit(bundled_runs):
    # the bundled run's half period is constant within its noise: the default fit, as
    # it is, with the choice recorded
    path = bundled_runs / "glycerol-N0.31-r1.csv"
    default = fit(path)
    auto = fit(path, restoring="auto")
    assert auto.restoring["auto"]["chosen"] == "linear"
    assert default.restoring.get("auto") is None
    names = default.summary().keys()
    assert all(np.array_equal(default.samples(n), auto.samples(n)) for n in names)
    assert auto.dissipation == default.dissipation
    assert auto.turning_point_dissipation == default.turning_point_dissipation
    assert "restoring auto → linear: the half period is constant" in auto.to_text()


def test_the_adequacy_checks_choose_once_for_every_window():
    # a window holds too few turning points to measure the change: the checks choose on
    # the whole run, and each window's fit takes that force
    from bayestribo.adequacy.restoring import chosen_run

    t, angle = _rubbing_pendulum()
    run = Run(t, angle, metadata={"length_unit": "rad", "restoring": "auto"})
    assert chosen_run(run).metadata["restoring"] == "pendulum"
    named = run.with_metadata(restoring="duffing")
    assert chosen_run(named) is named
    # the option overrides the run's own
    assert chosen_run(named, "auto").metadata["restoring"] == "pendulum"


def test_auto_fits_a_stiffening_spring_on_the_papers_rig_without_a_warning():
    # test_inference_fitting's cubic spring (+0.1 % at 2 mm) on the paper's rig: the
    # linear fit warns of the frequency's change and advises --restoring auto; followed,
    # the Duffing spring is chosen, no change is left to warn of, and ζ and μ_k hold
    # the simulation's values
    from test_signal_frequency import _decay

    t, x, v = _decay(10_000.0, k3_over_k=667.0)
    rng = np.random.default_rng(5)
    run = Run(
        t,
        x + rng.normal(0.0, 1.5e-6, t.size),
        v + rng.normal(0.0, 1.5e-7, t.size),
        {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31},
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fit(run, seed=1, max_steps=3000, restoring="auto")
    assert not [w for w in caught if issubclass(w.category, FrequencyTrendWarning)]
    assert not [w for w in caught if issubclass(w.category, MisfitWarning)]
    assert result.restoring["auto"]["chosen"] == "duffing"
    mu_k = 0.035 * (2 * np.pi * 32.6) ** 2 * 6.2e-6 / 0.31
    for name, truth in (("zeta", 0.0236), ("mu_k", mu_k)):
        lo, hi = result.interval(name, 0.95)
        assert lo < truth < hi, name


# -- what the linear analysis says, once a force is chosen ---------------------------


@functools.lru_cache(maxsize=2)
def _rig_pendulum(zeta: float = 0.0236) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """θ'' + 2ζω θ' + ω² (sin θ + μ sgn θ') = 0 released at rest at 90° on the paper's
    rig's frequency and damping (f₀ = 32.6 Hz, ζ = 0.0236 unless said, μ = 0.0049 rad),
    angle and angular velocity at 10 kHz for 0.8 s with 1.2 mrad and 0.12 mrad/s of
    noise; half cycle by half cycle, at rest once sin θ is inside the static band
    (1.36 μ)."""
    w, mu = 2 * math.pi * 32.6, 0.0049
    t = np.arange(0.0, 0.8, 1e-4)
    x, v = np.empty_like(t), np.zeros_like(t)
    y, t0, filled = math.pi / 2, 0.0, 0
    while filled < t.size:
        sgn = -1.0 if y > 0 else 1.0
        if abs(math.sin(y)) <= 1.36 * mu:
            x[filled:] = y
            break

        def turned(_t, u):
            return u[1]

        turned.terminal = True
        turned.direction = 1.0 if sgn < 0 else -1.0
        sol = solve_ivp(
            lambda _t, u, s=sgn: [u[1], -2 * zeta * w * u[1] - w * w * (math.sin(u[0]) + mu * s)],
            (t0, t0 + 0.3),
            [y, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(t, t1, side="right"))
        x[filled:stop], v[filled:stop] = sol.sol(t[filled:stop])
        filled, y, t0 = stop, float(sol.y_events[0][0][0]), t1
    rng = np.random.default_rng(12)
    return t, x + rng.normal(0.0, 1.2e-3, t.size), v + rng.normal(0.0, 1.2e-4, t.size)


def _prepared_with(run):
    from bayestribo.inference.preparation import prepare

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prepared = prepare(run)
    return prepared, {w.category.__name__ for w in caught}


def test_auto_says_only_what_holds_of_the_force_it_chose():
    t, angle, rate = _rig_pendulum()
    run = Run(t, angle, rate, metadata={"length_unit": "rad"})
    # the linear analysis reads the pendulum's wide swings as a soft clip and leaves
    # them out ...
    linear, said = _prepared_with(run)
    assert "ClippingWarning" in said
    # ... which the pendulum's analysis does not: auto, choosing it, says nothing of a
    # clip and keeps every turning point the named pendulum keeps
    auto, said = _prepared_with(run.with_metadata(restoring="auto"))
    named, _ = _prepared_with(run.with_metadata(restoring="pendulum"))
    assert auto.restoring_choice.name == "pendulum" and "ClippingWarning" not in said
    assert np.array_equal(auto.decay.turning_times, named.decay.turning_times)
    assert auto.decay.turning_times.size > linear.decay.turning_times.size


def test_auto_on_a_linear_record_says_what_its_analysis_found():
    # a spike on a linear oscillator: the linear choice keeps the linear analysis, and
    # what it said
    t, x = _linear()
    x = x.copy()
    x[1000] += 0.3
    _, said = _prepared_with(Run(t, x, metadata={"length_unit": "arbitrary", "restoring": "auto"}))
    assert "SpikeWarning" in said


def test_a_damped_pendulum_is_a_pendulum():
    # damping moves the turning points off the undamped half periods by a share that
    # grows as ζ²: the pendulum leaves a small change far beyond its noise, which a
    # Duffing spring's β would take up; the pendulum follows it as the Duffing spring
    # would be said to (at most a tenth of the change), and is the force
    from bayestribo.inference.restoring_choice import FOLLOWED

    t, angle, rate = _rig_pendulum(0.04)
    decay = energy_decay(t, angle, rate, linear_spring=False)
    choice = choose_restoring(decay.turning_times, decay.peaks.value, length_unit="rad")
    left = choice.left["pendulum"]
    assert left.significant and abs(left.change) <= FOLLOWED * abs(choice.trend.change)
    assert choice.name == "pendulum" and choice.followed
