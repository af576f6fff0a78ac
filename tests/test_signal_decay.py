"""Energy decay of a recording: simulated runs with real-rig effects, real recordings."""

from __future__ import annotations

import numpy as np
import pytest
from _paths import APPSTAT
from _sim import simulate_flat

from bayestribo.errors import RecordingError
from bayestribo.model import exact_pi
from bayestribo.model.scaling import Rig
from bayestribo.signal.decay import energy_decay, retrograde_integral

HARMOSC = APPSTAT

ZETA, MU_K = 0.0236, 0.0294
OFFSET = 3.1e-4  # displacement zero 0.31 mm away from the equilibrium
COMMON = dict(zeta=ZETA, mu_k=MU_K, offset_m=OFFSET, time_origin_s=12.3, sample_rate_Hz=10_000.0)


def _pair(noise_factor: float, seed: int = 3, **kw):
    """A noisy run and the same run without noise (same release, same trajectory)."""
    noisy = simulate_flat(
        seed=seed,
        displacement_noise_m=1.5e-7 * noise_factor,
        velocity_noise_m_per_s=1.5e-8 * noise_factor,
        **{**COMMON, **kw},
    )
    clean = simulate_flat(
        seed=seed, displacement_noise_m=0.0, velocity_noise_m_per_s=0.0, **{**COMMON, **kw}
    )
    return noisy, clean


def _true_energy(decay, clean):
    """E of the noise-free signals, in the decay's own scaling, at its samples."""
    idx = np.searchsorted(clean.time, decay.t)
    sc = decay.scaling
    y = sc.y(clean.displacement[idx] - OFFSET)
    yp = sc.yp(clean.velocity[idx])
    return 0.5 * (y * y + yp * yp)


@pytest.mark.parametrize("noise_factor", [0.0, 1.0, 30.0])
def test_energy_of_simulated_run_with_rig_effects(noise_factor):
    noisy, clean = _pair(noise_factor)
    decay = energy_decay(noisy.time, noisy.displacement, noisy.velocity, rig=noisy.rig())
    sim = noisy.metadata["simulation"]
    # Release found within 1 ms (the fading magnet makes the departure gradual; it
    # only anchors the skipped oscillation, 31 ms long); the first oscillation is
    # skipped; the motion ends inside the record.
    assert decay.release_time == pytest.approx(sim["release_time_s"], abs=1e-3)
    period = 1 / 32.6
    assert period < decay.start_time - decay.release_time < 1.6 * period
    assert decay.motion_ended
    # Equilibrium from the turning points, not from the rest before or after.
    assert decay.equilibrium == pytest.approx(OFFSET, abs=max(3e-3 * 1.5e-3, 4e-7 * noise_factor))
    # Measured noise matches the simulated one (1585 quiet samples: ±10 % is > 4σ).
    if noise_factor > 0:
        assert decay.noise.source == "rest before release and rest after stop"
        assert decay.noise.displacement == pytest.approx(1.5e-7 * noise_factor, rel=0.1)
        assert decay.noise.velocity == pytest.approx(1.5e-8 * noise_factor, rel=0.1)
    # E agrees with the noise-free signals sample by sample as long as each channel's
    # error stays within 6σ of its noise (plus the equilibrium error on y): the bound
    # is ½[(|y| + δy)² - y²] + ½[(|y'| + δy')² - y'²].
    e_true = _true_energy(decay, clean)
    idx = np.searchsorted(clean.time, decay.t)
    sc = decay.scaling
    y_true = np.abs(sc.y(clean.displacement[idx] - OFFSET))
    yp_true = np.abs(sc.yp(clean.velocity[idx]))
    dy = 6 * 1.5e-7 * noise_factor / sc.length_scale + abs(sc.y(decay.equilibrium - OFFSET))
    dyp = 6 * sc.yp(1.5e-8 * noise_factor)
    bound = 0.5 * ((y_true + dy) ** 2 - y_true**2 + (yp_true + dyp) ** 2 - yp_true**2)
    assert np.all(np.abs(decay.energy - e_true) <= bound + 1e-9 * e_true[0])


@pytest.mark.parametrize("noise_factor", [0.0, 30.0])
def test_pi_of_simulated_run_matches_exact_model(noise_factor):
    noisy, clean = _pair(noise_factor)
    decay = energy_decay(noisy.time, noisy.displacement, noisy.velocity, rig=noisy.rig())
    true = noisy.rig().scaling()
    i0 = int(np.searchsorted(clean.time, decay.start_time))
    y0 = true.y(clean.displacement[i0] - OFFSET)
    yp0 = true.yp(clean.velocity[i0])
    model = exact_pi(true.tau(decay.t - decay.start_time), y0, ZETA, MU_K, MU_K, yp0)
    # Same physical integral in the decay's scaling: Π ∝ ℓ⁻² Ω (y² and dτ).
    model *= (true.length_scale / decay.scaling.length_scale) ** 2 * (
        decay.scaling.omega / true.omega
    )
    # Error budget relative to Π(0): trapezoidal rule at 160 samples per period
    # (~1e-6), measured frequency (~3e-6), end of motion detected within the last
    # small half cycle (~1e-5) and, with noise, Σ y σ_y dτ over ~4000 samples
    # (~1e-4 at 30× the resolution).
    tol = 3e-5 if noise_factor == 0 else 5e-4
    np.testing.assert_allclose(decay.pi, model, rtol=0, atol=tol * model[0])
    assert abs(decay.natural_frequency_Hz - 32.6) < 1e-4 * 32.6


@pytest.mark.parametrize("channel", ["displacement", "velocity"])
def test_single_channel_recordings(channel):
    noisy, _ = _pair(10.0)
    signals = {channel: getattr(noisy, channel)}
    decay = energy_decay(noisy.time, **signals, rig=noisy.rig())
    full = energy_decay(noisy.time, noisy.displacement, noisy.velocity, rig=noisy.rig())
    assert decay.derived_channel == ("velocity" if channel == "displacement" else "displacement")
    # Compare at common time stamps: the start and end may differ by a sample.
    common, ia, ib = np.intersect1d(decay.t, full.t, return_indices=True)
    assert common.size > 0.95 * full.t.size

    def physical(d, i):  # Π ℓ²/Ω [m² s]: independent of the measured frequency
        pi = d.pi[i] - d.pi[i[-1]]  # both integrated to the last common sample
        return pi * d.scaling.length_scale**2 / d.scaling.omega

    # The derived channel (Savitzky-Golay derivative, or integral of the velocity)
    # changes Π by less than 5e-4 of Π(0) against the two-channel result ...
    np.testing.assert_allclose(
        physical(decay, ia), physical(full, ib), rtol=0, atol=5e-4 * physical(full, ib)[0]
    )
    # ... and the frequency from displacement peak times alone is biased by the
    # friction (turning arcs of different centres) by about 1e-4.
    assert decay.natural_frequency_Hz == pytest.approx(32.6, rel=2e-4)


def test_record_ending_before_the_motion():
    # A test in air: no contact, viscous damping only, 1.5 s recorded of a decay
    # lasting much longer.
    noisy, clean = _pair(
        1.0, zeta=0.0033, mu_k=0.0, load_N=0.0, motion_duration_s=1.5, rest_after_s=0.0
    )
    decay = energy_decay(noisy.time, noisy.displacement, noisy.velocity, rig=noisy.rig())
    assert not decay.motion_ended
    assert decay.end_time == pytest.approx(noisy.time[-1])
    assert not decay.scaling.friction_defined and decay.scaling.length_scale == 1.0
    true = noisy.rig().scaling()
    i0 = int(np.searchsorted(clean.time, decay.start_time))
    y0, yp0 = clean.displacement[i0] - OFFSET, true.yp(clean.velocity[i0])
    tau = true.tau(decay.t - decay.start_time)
    model = exact_pi(tau, y0, 0.0033, 0.0, 0.0, yp0, tau_end=tau[-1]) * (
        decay.scaling.omega / true.omega
    )
    np.testing.assert_allclose(decay.pi, model, rtol=0, atol=3e-5 * model[0])
    assert decay.pi[-1] == 0.0


def _frontend_record(fs: float, filt: bool):
    """The independent solve_ivp simulator's noise-free record (tests/test_signal_frontend.py),
    through its 2 kHz anti-alias filter when ``filt``."""
    import scipy.signal
    from test_signal_frontend import CUTOFF_HZ, record

    t, x, v, _, _ = record(fs, 0.1, 0.1)
    if filt:
        sos = scipy.signal.butter(4, CUTOFF_HZ, fs=fs, output="sos")
        zi = scipy.signal.sosfilt_zi(sos)
        x = scipy.signal.sosfilt(sos, x, zi=zi * x[0])[0]
        v = scipy.signal.sosfilt(sos, v, zi=zi * v[0])[0]
    return t, x, v


@pytest.mark.parametrize(
    "fs, filt",
    [(1000.0, False), (2000.0, False), (10_000.0, False), (10_000.0, True), (100_000.0, True)],
)
def test_frequency_is_unbiased_by_the_friction_kink(fs, filt):
    # The independent simulator (solve_ivp, paper's rig, ζ = 0.0236, μ_k = 0.0294), no
    # noise. Friction flips the velocity's slope at every turning point; a straight line
    # across the two bracketing samples put the turning points late by up to 0.15 ms at
    # 1 kHz near the end of motion, and an anti-alias filter smooths the kink into a
    # delay growing as the amplitude decays: damped frequency low by 2.5e-5 (1 kHz),
    # 9.3e-6 (2 kHz), 1.9e-6 (10 kHz), 3.4e-6 (10 kHz filtered), 2.7e-6 (100 kHz
    # filtered) before. Now within 1e-7 (the damped frequency) and 5e-7 (the natural,
    # with β from the decrement).
    from test_signal_frontend import F_HZ, RIG
    from test_signal_frontend import ZETA as Z

    t, x, v = _frontend_record(fs, filt)
    decay = energy_decay(t, x, v, rig=RIG)
    damped = F_HZ * np.sqrt(1.0 - Z**2)
    assert abs(decay.damped_frequency_Hz / damped - 1.0) < 1e-7
    assert abs(decay.natural_frequency_Hz / F_HZ - 1.0) < 5e-7


def test_frequency_at_1khz_with_noise_has_no_outliers():
    # Ten times the vibrometer's resolution at 1 kHz (31 samples per period): the last
    # peaks are a few times the noise, so their parabola times can be several samples
    # off; each turning time is the velocity crossing of the right direction nearest
    # to it. The damped frequency's noise is about 1e-8 (the velocity channel is
    # precise): all 12 within 1e-7 (before: all low by 2.2e-5).
    from test_signal_frontend import F_HZ, RIG, add_effects, record
    from test_signal_frontend import ZETA as Z

    t, x, v, _, _ = record(1000.0, 0.1, 0.1)
    damped = F_HZ * np.sqrt(1.0 - Z**2)
    errors = []
    for seed in [*range(1150, 1160), 1199, 7]:
        xs, vs = add_effects(t, x, v, 1000.0, seed=seed)
        errors.append(energy_decay(t, xs, vs, rig=RIG).damped_frequency_Hz / damped - 1.0)
    assert np.all(np.abs(errors) < 1e-7), errors


def test_nominal_frequency_difference_is_reported():
    noisy, _ = _pair(1.0)
    rig = Rig(natural_frequency_Hz=33.0, mass_kg=0.035, load_N=0.31)
    decay = energy_decay(noisy.time, noisy.displacement, noisy.velocity, rig=rig)
    assert decay.nominal_frequency_Hz == 33.0
    assert decay.frequency_difference_Hz == pytest.approx(-0.4, abs=1e-3)
    nominal = energy_decay(
        noisy.time, noisy.displacement, noisy.velocity, rig=rig, use_nominal_frequency=True
    )
    assert nominal.scaling.omega == pytest.approx(2 * np.pi * 33.0)


def test_retrograde_integral_is_scipys_trapezoids_to_the_bit():
    # the in-place sums against scipy's cumulative_trapezoid on the reversed arrays,
    # on irregular steps and energies of any magnitude
    from scipy.integrate import cumulative_trapezoid

    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 1000, 100_001):
        tau = np.cumsum(rng.uniform(0.0, 2.0, n)) * 10.0 ** rng.integers(-3, 4)
        energy = rng.standard_normal(n) * 10.0 ** rng.integers(-12, 6, n)
        got = retrograde_integral(tau, energy)
        expected = cumulative_trapezoid(energy[::-1], -tau[::-1], initial=0.0)[::-1]
        assert got.tobytes() == expected.tobytes()


def test_retrograde_integral_is_exact_for_piecewise_linear_energy():
    tau = np.linspace(0.0, 3.0, 31)
    energy = 5.0 - tau
    expected = (5.0 * 3.0 - 4.5) - (5.0 * tau - 0.5 * tau**2)
    np.testing.assert_allclose(retrograde_integral(tau, energy), expected, atol=1e-12)


@pytest.mark.skipif(not HARMOSC.exists(), reason="shared external data not present")
@pytest.mark.parametrize(
    ("name", "ends"), [("HarmOsc1.txt", False), ("HarmOsc2.txt", False), ("HarmOsc3.txt", True)]
)
def test_real_position_only_recordings(name, ends):
    data = np.loadtxt(HARMOSC / name)
    decay = energy_decay(data[:, 0], data[:, 1])
    assert decay.derived_channel == "velocity"
    assert decay.motion_ended is ends  # only the dry-friction run stops
    assert 1.3 < decay.natural_frequency_Hz < 1.7  # a spring-mass of ~1.5 Hz
    assert decay.nominal_frequency_Hz is None and decay.frequency_difference_Hz is None
    assert np.all(np.diff(decay.pi) <= 0) and decay.pi[-1] == 0.0
    # Noise per point of the order the course estimated (0.003-0.014).
    assert 1e-3 < decay.noise.displacement < 3e-2


def _good():
    run = simulate_flat(
        seed=2, sample_rate_Hz=2000.0, **{k: v for k, v in COMMON.items() if k != "sample_rate_Hz"}
    )
    return run.time.copy(), run.displacement.copy(), run.velocity.copy()


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t, x, v: (t[::-1].copy(), x, v), "increase strictly"),
        (
            lambda t, x, v: (np.where(np.arange(t.size) > 500, t + 0.05, t), x, v),
            r"100 samples are missing after sample 500 .* cannot be bridged",
        ),
        (
            lambda t, x, v: (t, np.where(np.arange(x.size) == 40, np.nan, x), v),
            "displacement is not finite at sample 40",
        ),
        (lambda t, x, v: (t, x[:-1], v), "one value per time stamp"),
        (lambda t, x, v: (t, None, None), "displacement or a velocity"),
        (lambda t, x, v: (t[:200], x[:200], v[:200]), r"turning points: .* 4 are needed at least"),
        (lambda t, x, v: (t, np.full_like(x, 1e-3), np.zeros_like(v)), "constant"),
    ],
    ids=["backwards", "gap", "nan", "length", "no-signal", "too-short", "no-oscillation"],
)
def test_bad_recordings_raise_clear_errors(mutate, message):
    t, x, v = mutate(*_good())
    with pytest.raises(RecordingError, match=message):
        energy_decay(t, x, v)


def test_bad_skip_argument():
    t, x, v = _good()
    with pytest.raises(RecordingError, match="skip_oscillations"):
        energy_decay(t, x, v, skip_oscillations=-1)


@pytest.mark.parametrize("rest_after", [0.1, 2.0, 10.0])
def test_end_of_motion_does_not_depend_on_the_rest_recorded_after_it(rest_after):
    # The package's simulator with 0.1 to 10 s of rest after the stop (clean otherwise):
    # the end of motion is the same within a sample (it used to move with the longest
    # noise excursion of the rest tail).
    run = simulate_flat(
        seed=7,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        rest_after_s=rest_after,
        **COMMON,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    sim = run.metadata["simulation"]
    stop = sim["release_time_s"] + sim["motion_duration_s"]
    assert decay.motion_ended
    assert decay.stop_time == pytest.approx(stop, abs=1.0 / 10_000.0)


def test_errors_name_the_part_of_the_analysis():
    t, x, v = _good()
    rng = np.random.default_rng(0)
    with pytest.raises(RecordingError, match="release: no motion found"):
        energy_decay(t, 1e-6 * rng.standard_normal(t.size), 1e-7 * rng.standard_normal(t.size))
    with pytest.raises(RecordingError, match="turning points: "):
        energy_decay(t[:200], x[:200], v[:200])
