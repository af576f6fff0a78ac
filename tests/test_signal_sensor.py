"""The sensor's gain in the intervals: its uncertainty and a known anti-alias filter.

The filtered record is an independent simulation: ``solve_ivp`` of
m x'' + c x' + k x + μ_k N sgn(x') = 0 from rest at x0, half cycle by half cycle,
sticking at the first turning point with |k x| <= μ_s N,
then a first-order low-pass filter at 10 f on both channels with
``scipy.signal.lfilter`` (bilinear, started in its steady state), white noise at ten
times the vibrometer's resolution.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import scipy.signal
from scipy.integrate import solve_ivp

from bayestribo.errors import RunFormatError
from bayestribo.inference import fit
from bayestribo.io.run import Run
from bayestribo.signal.sensor import (
    DEFAULT_GAIN_UNCERTAINTY,
    amplitude_gain_sd,
    check_filter,
    filter_gain,
    gain_variance_share,
    sensor_calibration,
)

pytestmark = pytest.mark.filterwarnings("ignore::FutureWarning")

MASS, F_HZ, LOAD = 0.035, 32.6, 0.31
ZETA, MU_K, MU_S, X0 = 0.0236, 0.0294, 0.04, 1e-3
FS = 4000.0
ONE_POLE = {"kind": "butterworth", "order": 1, "cutoff_Hz": 10 * F_HZ}


@pytest.mark.parametrize("order", [1, 2, 4, 8])
@pytest.mark.parametrize("ratio", [0.05, 0.1, 0.5, 1.0, 2.0])
def test_filter_gain_is_the_analog_prototypes_magnitude(order, ratio):
    # independent: scipy's analog Butterworth and Bessel evaluated with freqs
    for kind, design in (("butterworth", scipy.signal.butter), ("bessel", scipy.signal.bessel)):
        kw = {"norm": "mag"} if kind == "bessel" else {}
        b, a = design(order, 2 * np.pi * 100.0, analog=True, **kw)
        _, h = scipy.signal.freqs(b, a, worN=[2 * np.pi * 100.0 * ratio])
        spec = {"kind": kind, "order": order, "cutoff_Hz": 100.0}
        assert filter_gain(spec, 100.0 * ratio) == pytest.approx(abs(h[0]), rel=1e-10)


def test_one_pole_gain_at_a_tenth_of_its_cutoff():
    assert filter_gain(ONE_POLE, F_HZ) == pytest.approx(1 / math.sqrt(1.01), rel=1e-12)


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ({"kind": "chebyshev", "order": 2, "cutoff_Hz": 10.0}, "'kind' must be one of"),
        ({"kind": "bessel", "order": 0, "cutoff_Hz": 10.0}, "'order' must be an integer"),
        ({"kind": "bessel", "order": 2, "cutoff_Hz": -1.0}, "'cutoff_Hz' must be a positive"),
        ({"kind": "bessel", "order": 2, "cutoff": 10.0}, "unknown field"),
        ([1, 2], "expected a mapping"),
    ],
)
def test_a_filter_that_cannot_be_is_refused_naming_the_field(spec, match):
    with pytest.raises(ValueError, match=match):
        check_filter(spec)


def test_channel_gains_combine_as_the_energy_weighs_them():
    assert amplitude_gain_sd(0.02, None) == 0.02
    assert amplitude_gain_sd(None, 0.01) == 0.01
    assert amplitude_gain_sd(0.02, 0.02) == pytest.approx(0.02 / math.sqrt(2))
    # one transducer behind both channels: one gain error, not two that average out
    assert amplitude_gain_sd(0.02, 0.02, correlation=1.0) == pytest.approx(0.02)
    assert amplitude_gain_sd(0.02, 0.04, correlation=1.0) == pytest.approx(0.03)
    with pytest.raises(ValueError, match="correlation"):
        amplitude_gain_sd(0.02, 0.02, correlation=1.5)
    # a sensor of unstated kind: its two channels taken as one transducer's
    default = sensor_calibration({}, F_HZ)
    assert not default.stated and default.gain == 1.0
    assert default.gain_sd == pytest.approx(DEFAULT_GAIN_UNCERTAINTY)
    assert "the default for a sensor of unstated kind" in default.describe()
    assert "'sensor_kind'" in default.describe()
    stated = sensor_calibration({"gain_uncertainty": 0.0, "filter": ONE_POLE}, F_HZ)
    assert stated.stated and stated.gain_sd == 0.0
    assert stated.gain == pytest.approx(1 / math.sqrt(1.01))
    assert "butterworth filter of order 1" in stated.describe()


@functools.lru_cache(maxsize=1)
def _filtered_record() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time, displacement and velocity through the one-pole filter, with noise."""
    omega = 2 * math.pi * F_HZ
    k, c = MASS * omega**2, 2 * ZETA * MASS * omega
    t_end = 0.7  # the pin sticks at about 0.45 s: rest after it
    t = np.arange(0.0, t_end, 1.0 / FS)
    x, v = np.empty(0), np.empty(0)
    state, t0 = [X0, 0.0], 0.0
    while t0 < t_end - 1e-12 and abs(k * state[0]) > MU_S * LOAD:
        s = -math.copysign(1.0, state[0])

        def rhs(_t, u, s=s):
            return [u[1], (-c * u[1] - k * u[0] - MU_K * LOAD * s) / MASS]

        def turned(_t, u):
            return u[1]

        turned.terminal, turned.direction = True, -s  # v returns to 0
        sol = solve_ivp(
            rhs,
            (t0, t_end),
            state,
            events=turned,
            rtol=1e-11,
            atol=1e-14,
            dense_output=True,
            first_step=1e-7,
        )
        t1 = sol.t_events[0][0] if sol.t_events[0].size else t_end
        inside = (t >= t0) & (t < t1) if t1 < t_end else (t >= t0)
        if inside.any():
            u = sol.sol(t[inside])
            x, v = np.r_[x, u[0]], np.r_[v, u[1]]
        state, t0 = [float(sol.sol(t1)[0]), 0.0], t1
    x, v = np.r_[x, np.full(t.size - x.size, state[0])], np.r_[v, np.zeros(t.size - v.size)]
    # 0.1 s at rest at x0 before the release, then the filter in its steady state there
    rest = np.arange(-0.1, 0.0, 1.0 / FS)
    time = np.r_[rest, t]
    x, v = np.r_[np.full(rest.size, X0), x], np.r_[np.zeros(rest.size), v]
    b, a = scipy.signal.butter(1, ONE_POLE["cutoff_Hz"], fs=FS)
    zi = scipy.signal.lfilter_zi(b, a)
    xf = scipy.signal.lfilter(b, a, x, zi=zi * x[0])[0]
    vf = scipy.signal.lfilter(b, a, v, zi=zi * v[0])[0]
    rng = np.random.default_rng(2024)
    return time, xf + rng.normal(0, 1.5e-6, x.size), vf + rng.normal(0, 1.5e-7, v.size)


def _fit_filtered(**metadata) -> np.ndarray:
    time, x, v = _filtered_record()
    meta = {"load_N": LOAD, "mass_kg": MASS, "natural_frequency_Hz": F_HZ, **metadata}
    return fit(Run(time, x, v, meta), seed=11, grid_points=32).samples("mu_k")


@pytest.mark.slow
def test_a_declared_filter_is_corrected_and_an_undeclared_one_is_within_the_gain():
    # without the gain: the filter's -0.5 % at f is many posterior sd off (the bug)
    exact = _fit_filtered(gain_uncertainty=0.0)
    z_exact = (np.mean(exact) - MU_K) / np.std(exact)
    assert z_exact < -4
    # the filter declared: corrected
    corrected = _fit_filtered(gain_uncertainty=0.0, filter=ONE_POLE)
    assert abs(np.mean(corrected) - MU_K) < 4 * np.std(corrected)
    # nothing declared: the default gain uncertainty holds the filter's gain
    default = _fit_filtered()
    assert abs(np.mean(default) - MU_K) < 2 * np.std(default)
    assert np.std(default) / np.mean(default) == pytest.approx(DEFAULT_GAIN_UNCERTAINTY, rel=0.2)


@functools.lru_cache(maxsize=1)
def _spread_without_gain() -> float:
    """Relative sd of μ_k from the filtered record with the gain known exactly."""
    exact = _fit_filtered(gain_uncertainty=0.0, filter=ONE_POLE)
    return float(np.std(exact) / np.mean(exact))


@pytest.mark.parametrize(
    ("kind", "relative_sd"),
    [("accelerometer", 0.05), ("laser_vibrometer", 0.01 / math.sqrt(2)), ("encoder", 0.001)],
)
def test_the_sensor_kind_sets_the_friction_interval_where_no_gain_is_stated(kind, relative_sd):
    # μ_k is a length over N/k: its relative sd is the amplitude gain's and that of the
    # Π increments alone (the fit with a gain known exactly) in quadrature; the
    # vibrometer's two decoders are calibrated apart, the other kinds' channels share one
    # gain error
    draws = _fit_filtered(filter=ONE_POLE, sensor_kind=kind)
    spread = math.hypot(relative_sd, _spread_without_gain())
    assert np.std(draws) / np.mean(draws) == pytest.approx(spread, rel=0.15)
    assert abs(np.mean(draws) - MU_K) < 3 * np.std(draws)


def test_the_sensor_kind_gives_the_default_and_says_whose():
    accelerometer = sensor_calibration({"sensor_kind": "accelerometer"}, F_HZ)
    assert accelerometer.gain_sd == pytest.approx(0.05) and not accelerometer.stated
    assert "the default for an accelerometer" in accelerometer.describe()
    # a stated uncertainty wins over the kind's; the kind still says how channels combine
    stated = sensor_calibration({"sensor_kind": "accelerometer", "gain_uncertainty": 0.002}, F_HZ)
    assert stated.stated and stated.gain_sd == pytest.approx(0.002)
    vibrometer = sensor_calibration({"sensor_kind": "laser_vibrometer"}, F_HZ)
    assert vibrometer.gain_sd == pytest.approx(0.01 / math.sqrt(2))
    # one channel recorded: that channel's σ, whatever the kind
    alone = sensor_calibration({"sensor_kind": "laser_vibrometer"}, F_HZ, velocity=False)
    assert alone.gain_sd == pytest.approx(0.01)
    per_channel = sensor_calibration(
        {"sensor_kind": "video", "displacement_gain_uncertainty": 0.04}, F_HZ
    )
    assert per_channel.gain_sd == pytest.approx((0.04 + 0.02) / 2)


def test_a_sidecar_names_an_unknown_sensor_kind_and_the_nearest():
    time, x, v = _filtered_record()
    run = Run(time, x, v, {"sensor_kind": "Laser-Vibrometer"})
    assert run.metadata["sensor_kind"] == "laser_vibrometer"
    with pytest.raises(RunFormatError, match=r"'sensor_kind'.*did you mean 'accelerometer'"):
        Run(time, x, v, {"sensor_kind": "acclerometer"})
    with pytest.raises(RunFormatError, match="'sensor_kind': expected a name, got 3"):
        Run(time, x, v, {"sensor_kind": 3})


def test_a_lab_registers_its_own_sensor_kind():
    from bayestribo.signal import sensor_kinds

    kind = sensor_kinds.SensorKind("strain_gauge_blade", "a strain-gauged blade", 0.03, "own")
    sensor_kinds.register_sensor_kind(kind)
    try:
        assert sensor_calibration({"sensor_kind": "strain_gauge_blade"}, F_HZ).gain_sd == 0.03
        with pytest.raises(ValueError, match="registered already"):
            sensor_kinds.register_sensor_kind(kind)
    finally:
        sensor_kinds._KINDS.pop("strain_gauge_blade")
    with pytest.raises(ValueError, match="gain_uncertainty"):
        sensor_kinds.SensorKind("wide", "a wide one", 0.9, "none")
    with pytest.raises(ValueError, match="name"):
        sensor_kinds.SensorKind("Bad Name", "a bad one", 0.01, "none")


def test_the_gains_share_of_a_variance_is_its_part_of_the_quantitys():
    rng = np.random.default_rng(5)
    n, sd_g, rel_data = 100_000, 0.01, 0.005
    gain = 1.0 + sd_g * rng.standard_normal(n)
    data = 0.02 * (1.0 + rel_data * rng.standard_normal(n))  # the posterior's own spread
    shares = gain_variance_share(
        {"mu_k": data / gain, "zeta": 0.004 + 1e-5 * rng.standard_normal(n)}, gain
    )
    # μ_k = f/g: to first order the variance is f's plus the gain's, (0.01)² against (0.005)²
    assert shares["mu_k"] == pytest.approx(sd_g**2 / (sd_g**2 + rel_data**2), abs=0.01)
    assert shares["zeta"] < 1e-3  # not a length: the gain has no part in it


def test_the_gains_share_leaves_out_what_it_cannot_measure_and_refuses_a_mismatch():
    gain = np.linspace(0.99, 1.01, 50)
    assert gain_variance_share({"mu_k": 1.0 / gain}, np.ones(50)) == {}  # gain exact
    values = {"fixed": np.full(50, 3.0), "broken": np.where(gain > 1.0, np.nan, 1.0)}
    assert gain_variance_share(values, gain) == {}
    with pytest.raises(ValueError, match=r"quantities\['mu_k'\]: expected 50 draws"):
        gain_variance_share({"mu_k": np.ones(49)}, gain)


@pytest.fixture(scope="module")
def gain_fits():
    """One short simulated run fitted with its gain exact and with a gain uncertainty as
    large as μ_k's own relative sd (the same seed: the same draws of the posterior)."""
    from bayestribo.synthetic import Sensor
    from bayestribo.synthetic.recording import simulate

    run = simulate(sensor=Sensor(sample_rate_Hz=2000.0), seed=11)
    exact = fit(run.with_metadata(gain_uncertainty=0.0), seed=3)
    mu_k = exact.samples("mu_k")
    uncertain = run.with_metadata(gain_uncertainty=float(np.std(mu_k) / np.mean(mu_k)))
    return exact, fit(uncertain, seed=3)


def test_a_fit_records_and_says_how_much_of_mu_ks_variance_the_gain_makes(gain_fits):
    exact, uncertain = gain_fits
    added = 1.0 - np.var(exact.samples("mu_k")) / np.var(uncertain.samples("mu_k"))
    share = uncertain.sensor["variance_share"]
    assert share["mu_k"] == pytest.approx(added, abs=0.03)
    assert share["zeta"] < 0.05
    line = next(s for s in uncertain.to_text().splitlines() if s.startswith("sensor"))
    assert f"the gain makes {100 * share['mu_k']:.0f} % of μ_k's" in line
    assert "ζ's" not in line  # under a tenth: not named
    assert exact.sensor["variance_share"] == {}
    exact_line = next(s for s in exact.to_text().splitlines() if s.startswith("sensor"))
    assert "the gain makes" not in exact_line


def test_a_run_integrated_from_an_acceleration_takes_an_accelerometers_gain() -> None:
    """The kind is known from the column: an accelerometer's 5 %, said as such; a stated
    kind or uncertainty wins."""
    from bayestribo.signal.sensor import sensor_calibration
    from bayestribo.signal.sensor_kinds import get_sensor_kind

    integrated = {"acceleration": {"method": "any record of the integration"}}
    implied = sensor_calibration(integrated, 20.0, displacement=True, velocity=True)
    assert implied.kind is get_sensor_kind("accelerometer") and not implied.stated
    assert implied.gain_sd == pytest.approx(get_sensor_kind("accelerometer").gain_uncertainty)
    assert "the run being read from an acceleration" in implied.describe()
    phone = sensor_calibration({**integrated, "sensor_kind": "smartphone"}, 20.0)
    assert phone.gain_sd == pytest.approx(get_sensor_kind("smartphone").gain_uncertainty)
    assert "read from" not in phone.describe()
    stated = sensor_calibration({**integrated, "gain_uncertainty": 0.002}, 20.0)
    assert stated.stated and stated.gain_sd == pytest.approx(0.002)
    assert "read from" not in stated.describe()
    plain = sensor_calibration({}, 20.0)
    assert "a sensor of unstated kind" in plain.describe()
