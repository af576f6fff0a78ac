"""The simulator: checked against an independent integration of the equation of motion."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from _sim import simulate_flat
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from bayestribo import read_run, simulate
from bayestribo.cli import simulate as simulate_command
from bayestribo.errors import BayestriboError
from bayestribo.model.scaling import Rig
from bayestribo.synthetic import PAPER_RIG, DissipationLaw, Release, Sensor

M, F = 0.035, 32.6
K = M * (2 * math.pi * F) ** 2


def _reference(
    t: np.ndarray,
    *,
    zeta: float | Callable[[float], float],
    mu_k: float | Callable[[float], float],
    mu_s: float,
    load: float,
    x0: float,
    release: float,
    fade: float,
) -> tuple[np.ndarray, np.ndarray]:
    """m x'' + c x' + k x = -μ_k N sgn(x') + F_mag(t), integrated with events at x' = 0.

    Physical units, written from the paper's Eq. 1-5 only (no package code): the magnet
    force k x₀ (1 + cos(π s/t_f))/2 fades over t_f after the release; at each turning
    point the pin sticks if the net force is within ±μ_s N. Amplitude laws are evaluated
    at |x| of the turning point that starts each half cycle (x₀ for the first).
    """
    omega = math.sqrt(K / M)

    def law(p, amp):
        return p(amp) if callable(p) else p

    def magnet(s: float) -> float:
        return K * x0 * 0.5 * (1 + math.cos(math.pi * s / fade)) if 0 <= s < fade else 0.0

    x, v = np.full(t.size, x0), np.zeros(t.size)
    s_break = 0.0
    if fade > 0 and mu_s > 0:
        s_break = brentq(lambda s: K * x0 - magnet(s) - mu_s * load, 0.0, fade)
    s, state, amp, direction = s_break, [x0, 0.0], x0, -1.0
    s_end = t[-1] - release
    while s < s_end:
        z, mk = law(zeta, amp), law(mu_k, amp)
        c = 2 * z * math.sqrt(K * M)

        def rhs(time, y, c=c, mk=mk, d=direction):
            return [y[1], (-c * y[1] - K * y[0] - d * mk * load + magnet(time)) / M]

        def turn(time, y, d=direction, start=s):
            return y[1] * d if time > start + 1e-9 / omega else 1.0

        turn.terminal = True
        sol = solve_ivp(
            rhs,
            (s, s_end),
            state,
            method="DOP853",
            rtol=1e-12,
            atol=1e-15,
            events=turn,
            dense_output=True,
        )
        sel = (t - release >= s) & (t - release <= sol.t[-1])
        x[sel], v[sel] = sol.sol(t[sel] - release)
        if sol.status != 1:
            break
        s, state = float(sol.t[-1]), [float(sol.y[0, -1]), 0.0]
        amp = abs(state[0])
        net = -K * state[0] + magnet(s)
        if abs(net) <= mu_s * load:  # sticks for good
            rest = t - release > s
            x[rest], v[rest] = state[0], 0.0
            break
        direction = math.copysign(1.0, net)
    return x, v


CASES = [
    {"load_N": 0.07, "zeta": 0.0236, "mu_k": 0.0294, "mu_s": 0.035},
    {"load_N": 0.59, "zeta": 0.025, "mu_k": 0.03, "mu_s": 0.03},
    {"load_N": 0.0, "zeta": 0.0033, "mu_k": 0.0, "mu_s": 0.0, "motion_duration_s": 1.0},
]


@pytest.mark.parametrize("case", CASES, ids=["N0.07", "N0.59", "air"])
def test_noise_free_run_matches_independent_integration(case: dict) -> None:
    run = simulate_flat(
        **case,
        initial_displacement_m=1.5e-3,
        sample_rate_Hz=5000.0,
        rest_before_s=0.02,
        time_origin_s=0.0,
        displacement_noise_m=0.0,
        velocity_noise_m_per_s=0.0,
    )
    truth = run.metadata["simulation"]
    x, v = _reference(
        run.time,
        zeta=case["zeta"],
        mu_k=case["mu_k"],
        mu_s=case["mu_s"],
        load=case["load_N"],
        x0=1.5e-3,
        release=truth["release_time_s"],
        fade=truth["magnet_fade_s"],
    )
    # Both sides are accurate to ~1e-12 relative per half cycle (exact formulas vs
    # DOP853 at rtol 1e-12); 1e-9 m (1e-6 of x0) and 1e-7 m/s allow ~50 half cycles of
    # accumulation with a wide margin, and would catch any error of the physics.
    np.testing.assert_allclose(run.displacement, x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.velocity, v, rtol=0, atol=1e-7)


def test_amplitude_dependent_damping_matches_independent_integration() -> None:
    def zeta(amplitude_m: float) -> float:
        return 0.015 + 8.0 * amplitude_m  # more damping at large amplitude

    def mu_k(amplitude_m: float) -> float:
        return 0.03 - 5.0 * amplitude_m

    run = simulate(
        DissipationLaw(zeta=zeta, mu_k=mu_k, mu_s=0.035),
        rig=PAPER_RIG,
        release=Release(initial_displacement_m=1.5e-3),
        sensor=Sensor(sample_rate_Hz=5000.0, displacement_noise_m=0.0, velocity_noise_m_per_s=0.0),
    )
    truth = run.metadata["simulation"]
    assert truth["amplitude_dependent"] and truth["zeta"] is None
    x, v = _reference(
        run.time,
        zeta=zeta,
        mu_k=mu_k,
        mu_s=0.035,
        load=0.31,
        x0=1.5e-3,
        release=truth["release_time_s"],
        fade=truth["magnet_fade_s"],
    )
    np.testing.assert_allclose(run.displacement, x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.velocity, v, rtol=0, atol=1e-7)
    constant = simulate(
        DissipationLaw(zeta=zeta(1.5e-3), mu_k=mu_k(1.5e-3), mu_s=0.035),
        rig=PAPER_RIG,
    )
    assert run.n_samples != constant.n_samples  # the law changes the decay


def _quiet(**kw: object):
    return simulate_flat(displacement_noise_m=0.0, velocity_noise_m_per_s=0.0, **kw)


def test_rest_before_release_offset_and_time_origin() -> None:
    run = _quiet(
        load_N=0.31,
        offset_m=2.5e-4,
        time_origin_s=17.25,
        rest_before_s=0.05,
        sample_rate_Hz=10_000.0,
        initial_displacement_m=1.5e-3,
    )
    assert run.time[0] == 17.25
    np.testing.assert_allclose(np.diff(run.time), 1e-4, rtol=1e-5)  # stamps rounded to 1 ns
    before = run.time <= 17.25 + 0.05
    assert before.sum() == 501
    np.testing.assert_array_equal(run.displacement[before], 1.5e-3 + 2.5e-4)
    np.testing.assert_array_equal(run.velocity[before], 0.0)
    assert run.metadata["simulation"]["release_time_s"] == 17.3


def test_magnet_pull_fades_smoothly_during_the_first_oscillation() -> None:
    kw = {"load_N": 0.31, "rest_before_s": 0.0, "sample_rate_Hz": 20_000.0}
    magnet, ideal = _quiet(**kw), _quiet(magnet_fade_s=0.0, **kw)
    fade = magnet.metadata["simulation"]["magnet_fade_s"]
    assert fade == pytest.approx(0.25 / F)
    # Ideal release: acceleration -(k x0 - μ_k N)/m at once. With the fading magnet the
    # pin starts with zero acceleration, so it has moved much less after fade/4 ...
    i = round(fade / 4 * 20_000)
    drop_magnet = 1.5e-3 - magnet.displacement[i]
    drop_ideal = 1.5e-3 - ideal.displacement[i]
    assert 0 <= drop_magnet < 0.2 * drop_ideal
    # ... and after the fade both decay freely: the first minimum is lower for the
    # magnet run (less time to gain speed), but by less than 20 %.
    period = int(20_000 / F)
    assert ideal.displacement[:period].min() < magnet.displacement[:period].min()
    assert magnet.displacement[:period].min() < 0.8 * ideal.displacement[:period].min()


def test_rest_tail_after_the_stop_is_inside_the_static_band() -> None:
    run = _quiet(load_N=0.46, mu_k=0.03, mu_s=0.04, rest_after_s=0.1, sample_rate_Hz=5000.0)
    truth = run.metadata["simulation"]
    stopped = run.time > truth["release_time_s"] + truth["motion_duration_s"]
    assert stopped.sum() == pytest.approx(0.1 * 5000, abs=1)
    assert np.all(run.velocity[stopped] == 0.0)
    assert np.ptp(run.displacement[stopped]) == 0.0
    assert abs(run.displacement[-1]) <= 0.04 * 0.46 / K
    # It is moving just before the stop.
    assert np.abs(run.velocity[~stopped][-200:]).max() > 0


def test_default_noise_is_the_resolution_and_independent_per_channel() -> None:
    kw = {"load_N": 0.31, "sample_rate_Hz": 10_000.0}
    noisy, clean = simulate_flat(seed=3, **kw), _quiet(**kw)
    ex = noisy.displacement - clean.displacement
    ev = noisy.velocity - clean.velocity
    n = ex.size
    # Sample standard deviation of n normal values: relative standard error 1/sqrt(2n)
    # (about 0.9 % here); 5 standard errors.
    tol = 5 / math.sqrt(2 * n)
    assert ex.std() == pytest.approx(0.15e-6, rel=tol)
    assert ev.std() == pytest.approx(0.015e-6, rel=tol)
    # Independent channels: correlation within 5 standard errors (1/sqrt(n)) of 0.
    assert abs(np.corrcoef(ex, ev)[0, 1]) < 5 / math.sqrt(n)


def test_seeded_and_reproducible() -> None:
    a, b = simulate(seed=42), simulate(seed=42)
    assert a == b
    assert simulate(seed=43) != a


def test_quantisation_to_the_resolution_gives_short_decimals() -> None:
    run = simulate(
        rig=PAPER_RIG,
        sensor=Sensor(quantise=True, sample_rate_Hz=2000.0),
        seed=1,
    )
    k = run.displacement / 0.15e-6
    np.testing.assert_allclose(k, np.round(k), rtol=0, atol=1e-6)
    kv = run.velocity / 0.015e-6
    np.testing.assert_allclose(kv, np.round(kv), rtol=0, atol=1e-6)
    # Multiples of 1.5e-7 m have at most 8 decimals: the shortest repr is short.
    assert max(len(repr(value)) for value in run.displacement.tolist()) <= 12


def test_channels_and_metadata() -> None:
    run = simulate(
        sensor=Sensor(channels=("velocity",)), seed=1, metadata={"repeat": 2, "operator": "X"}
    )
    assert run.displacement is None and run.velocity is not None
    meta = run.metadata
    assert meta["repeat"] == 2 and meta["operator"] == "X"
    assert meta["load_N"] == 0.31 and meta["natural_frequency_Hz"] == 32.6
    assert meta["displacement_resolution_m"] == 0.15e-6
    assert meta["sample_rate_Hz"] == 10_000.0
    assert meta["simulation"]["zeta"] == 0.0236 and meta["simulation"]["mu_k"] == 0.0294


def test_sensor_range_saturates_and_the_run_is_then_rejected(tmp_path: Path) -> None:
    from bayestribo import write_run

    run = simulate(
        rig=PAPER_RIG,
        sensor=Sensor(velocity_range_m_per_s=0.2),
        seed=2,
    )
    assert np.abs(run.velocity).max() == 0.2
    path = write_run(run, tmp_path / "clipped.csv")
    with pytest.raises(BayestriboError, match="velocity_m_per_s' is clipped"):
        read_run(path)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"load_N": 0.0, "mu_k": 0.03}, "mu_k must be 0 without contact"),
        ({"load_N": 0.0}, "never stops.*motion_duration_s"),
        ({"zeta": 1.0}, "zeta must satisfy"),
        ({"mu_k": 0.03, "mu_s": 0.02}, "mu_s must be >= mu_k"),
        ({"initial_displacement_m": 1e-6}, "inside the static-friction band"),
        ({"initial_displacement_m": -1e-3}, "initial_displacement_m"),
        ({"sample_rate_Hz": 0.0}, "sample_rate_Hz"),
        ({"magnet_fade_s": 0.1}, "magnet_fade_s is too long"),
        ({"channels": ("position",)}, "channels"),
        ({"displacement_noise_m": -1.0}, "displacement_noise_m"),
        ({"zeta": lambda a: -1.0}, r"zeta\(.*returned -1.0"),
        ({"zeta": lambda a: 0.05, "load_N": 0.0}, "never stops.*motion_duration_s"),
    ],
)
def test_bad_arguments_raise_value_errors_naming_them(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        simulate_flat(**kwargs)


def _cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="bayestribo")
    sub = parser.add_subparsers(dest="command")
    simulate_command.register(sub)
    args = parser.parse_args(argv)
    return args.handler(args)


def test_simulate_command_writes_a_run_that_reads_back_identically(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "cli.csv"
    argv = ["simulate", str(out), "--load", "0.46", "--seed", "5", "--quantise"]
    assert _cli([*argv, "--sample-rate", "2000", "--time-origin", "3.5"]) == 0
    assert "cli.csv" in capsys.readouterr().out
    expected = simulate(
        rig=Rig(natural_frequency_Hz=32.6, mass_kg=0.035, load_N=0.46),
        release=Release(time_origin_s=3.5),
        sensor=Sensor(quantise=True, sample_rate_Hz=2000.0),
        seed=5,
    )
    assert read_run(out) == expected


def test_simulate_command_errors_are_package_errors(tmp_path: Path) -> None:
    with pytest.raises(BayestriboError, match=r"OUT\.csv or --campaign"):
        _cli(["simulate"])
    with pytest.raises(BayestriboError, match="zeta must satisfy"):
        _cli(["simulate", str(tmp_path / "x.csv"), "--zeta", "2"])


def test_the_simulators_objects_check_their_fields_and_keep_the_defaults() -> None:
    from bayestribo.synthetic import PAPER_RIG, DissipationLaw, Release, Sensor

    with pytest.raises(ValueError, match="zeta must satisfy"):
        DissipationLaw(zeta=1.0)
    with pytest.raises(ValueError, match="initial_displacement_m must be a finite number > 0"):
        Release(initial_displacement_m=0.0)
    with pytest.raises(ValueError, match="channels must be some of"):
        Sensor(channels=())
    with pytest.raises(ValueError, match="rig must give mass_kg and load_N"):
        simulate(rig=Rig(natural_frequency_Hz=32.6))
    # Every default spelled out gives the same run as the defaults.
    explicit = simulate(
        DissipationLaw(zeta=0.0236, mu_k=0.0294),
        rig=PAPER_RIG,
        release=Release(initial_displacement_m=1.5e-3, rest_before_s=0.05, rest_after_s=0.1),
        sensor=Sensor(sample_rate_Hz=10_000.0, quantise=False),
        seed=8,
    )
    assert explicit == simulate(seed=8)
    assert Sensor().noise == (0.15e-6, 0.015e-6)
    assert Release().fade_s(PAPER_RIG) == pytest.approx(0.25 / 32.6, rel=1e-15)


def test_a_run_simulated_without_a_seed_records_the_seed_that_remakes_it():
    import numpy as np

    from bayestribo.synthetic import simulate

    first = simulate()
    seed = first.metadata["simulation"]["seed"]
    assert isinstance(seed, int)
    np.testing.assert_array_equal(simulate(seed=seed).displacement, first.displacement)
