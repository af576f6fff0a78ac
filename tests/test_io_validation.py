"""Validation: every bad input has its own clear error; good recordings pass unchanged."""

from __future__ import annotations

import string
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from _paths import APPSTAT
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bayestribo import Run, read_run, simulate, write_run
from bayestribo.errors import BayestriboError, RecordingError, RunFormatError
from bayestribo.io import validate_run
from bayestribo.model.scaling import Rig
from bayestribo.synthetic import PAPER_RIG, Sensor

EXTERNAL = APPSTAT


@pytest.fixture(scope="module")
def good() -> Run:
    """A realistic simulated run (noise and quantisation at the vibrometer's resolution)."""
    return simulate(
        rig=PAPER_RIG,
        sensor=Sensor(sample_rate_Hz=5000.0, quantise=True),
        seed=7,
    )


def _replace(run: Run, **changes: object) -> Run:
    fields = {
        "time": run.time,
        "displacement": run.displacement,
        "velocity": run.velocity,
        "metadata": run.metadata,
    }
    fields.update(changes)
    return Run(**fields)


def _with(array: np.ndarray, index: int, value: float) -> np.ndarray:
    out = array.copy()
    out[index] = value
    return out


def _swap(array: np.ndarray, i: int) -> np.ndarray:
    out = array.copy()
    out[i], out[i + 1] = out[i + 1], out[i]
    return out


def _clip_flat(values: np.ndarray, fraction: float) -> np.ndarray:
    limit = fraction * np.abs(values).max()
    return np.clip(values, -limit, limit)


def _clipped_to_the_end(run: Run, fraction: float) -> Run:
    """The displacement clipped at ``fraction`` of its swing, the record cut one period
    after the last clipped sample: no analysis can start after the clipped cycles."""
    x = _clip_flat(run.displacement, fraction)
    last = int(np.flatnonzero(np.abs(x) == np.abs(x).max())[-1])
    end = last + round(1.0 / (32.6 * (run.time[1] - run.time[0])))
    return _replace(run, time=run.time[:end], displacement=x[:end], velocity=run.velocity[:end])


# (id, corruption of the good run, regex the message must match)
BAD: list[tuple[str, Callable[[Run], Run], str]] = [
    (
        "nan-displacement",
        lambda r: _replace(r, displacement=_with(r.displacement, 500, np.nan)),
        r"field 'displacement_m': 1 sample\(s\) are NaN or infinite.*sample 500.*finite",
    ),
    (
        "inf-velocity",
        lambda r: _replace(r, velocity=_with(r.velocity, 20, -np.inf)),
        r"field 'velocity_m_per_s'.*NaN or infinite.*sample 20",
    ),
    (
        "nan-time",
        lambda r: _replace(r, time=_with(r.time, 3, np.nan)),
        r"field 'time_s'.*NaN or infinite.*sample 3",
    ),
    (
        "time-not-increasing",
        lambda r: _replace(r, time=_swap(r.time, 100)),
        r"field 'time_s' is not strictly increasing: sample 101",
    ),
    (
        "time-repeated",
        lambda r: _replace(r, time=_with(r.time, 100, r.time[99])),
        r"field 'time_s' is not strictly increasing: sample 100",
    ),
    (
        "time-gap-beyond-a-tenth-of-a-period",
        lambda r: _replace(
            r,
            time=np.delete(r.time, np.arange(300, 320)),
            displacement=np.delete(r.displacement, np.arange(300, 320)),
            velocity=np.delete(r.velocity, np.arange(300, 320)),
        ),
        r"field 'displacement': 20 samples are missing after sample 299 .* "
        r"cannot be bridged",
    ),
    (
        "too-few-samples",
        lambda r: _replace(
            r, time=r.time[:40], displacement=r.displacement[:40], velocity=r.velocity[:40]
        ),
        r"field 'time_s': 40 sample\(s\); expected at least 64",
    ),
    (
        "sample-rate-disagrees",
        lambda r: r.with_metadata(sample_rate_Hz=10_000.0),
        r"metadata 'sample_rate_Hz' is 10000.0 Hz but the time stamps give 5000 Hz",
    ),
    (
        "undersampled",
        lambda r: r.with_metadata(natural_frequency_Hz=3000.0, sample_rate_Hz=None),
        r"sample rate 5000 Hz does not resolve the natural frequency 3000.0 Hz",
    ),
    (
        "clipped-at-declared-range",
        lambda r: _replace(
            r,
            velocity=_clip_flat(r.velocity, 0.8),
            metadata={**r.metadata, "velocity_range_m_per_s": 0.8 * np.abs(r.velocity).max()},
        ),
        r"field 'velocity_m_per_s' is clipped: \d+ sample\(s\) reach the sensor range",
    ),
    (
        "clipped-flat-top-no-range",
        lambda r: _clipped_to_the_end(r, 0.7),
        r"field 'displacement_m' is clipped: it is held flat at its (maximum|minimum) "
        r"[-0-9.e]+ in \d+ cycle\(s\) between t = .* fewer than 4 periods",
    ),
    (
        "displacement-in-millimetres",
        lambda r: _replace(r, displacement=1e3 * r.displacement),
        r"displacement is 1000 times the time integral.*likely displacement in mm: "
        r"scale=\{'displacement_m': 0\.001\}",
    ),
    (
        "displacement-in-micrometres",
        lambda r: _replace(r, displacement=1e6 * r.displacement),
        r"likely displacement in µm: scale=\{'displacement_m': 1e-06\}",
    ),
    (
        "velocity-in-mm-per-s",
        lambda r: _replace(r, velocity=1e3 * r.velocity),
        r"0\.001 times the time integral.*likely velocity in mm/s",
    ),
    (
        "velocity-wrong-sign",
        lambda r: _replace(r, velocity=-r.velocity),
        r"-1 times the time integral.*opposite sign",
    ),
]


@pytest.mark.parametrize(("corrupt", "match"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_each_bad_recording_has_its_own_clear_error(
    tmp_path: Path, good: Run, corrupt: Callable[[Run], Run], match: str
) -> None:
    bad = corrupt(good)
    path = write_run(bad, tmp_path / "bad_run.csv")
    with pytest.raises(RecordingError, match=match) as info:
        read_run(path)
    assert str(path) in str(info.value)
    # The same check on the object, without a file.
    with pytest.raises(RecordingError, match=match):
        validate_run(bad, where="memory")
    # Nothing repaired: reading without validation gives the bad data back as written.
    assert read_run(path, validate=False) == bad


def test_unknown_sidecar_value_type_names_file_key_and_expectation(
    tmp_path: Path, good: Run
) -> None:
    path = write_run(good, tmp_path / "r.csv")
    (tmp_path / "r.json").write_text('{"load_N": [0.31], "mass_kg": 0.035}')
    with pytest.raises(
        RunFormatError, match=r"r\.json: metadata 'load_N'.*expected a finite number >= 0.*list"
    ):
        read_run(path)
    with pytest.raises(RunFormatError, match=r"metadata 'operator': unknown value type"):
        read_run(write_run(good, tmp_path / "s.csv"), metadata={"operator": object()})


def test_good_simulated_run_passes_unchanged(good: Run) -> None:
    assert validate_run(good) is good


@pytest.mark.parametrize("seed", range(5))
def test_no_false_alarm_on_noise_free_or_coarse_quantised_runs(seed: int) -> None:
    # Noise-free and quantised: the rest before release is flat at the maximum, but it
    # touches the start of the record, so it is not a flat top.
    rng = np.random.default_rng(seed)
    run = simulate(
        rig=Rig(natural_frequency_Hz=32.6, mass_kg=0.035, load_N=float(rng.uniform(0.07, 0.6))),
        sensor=Sensor(
            displacement_noise_m=0.0,
            velocity_noise_m_per_s=0.0,
            quantise=True,
            sample_rate_Hz=float(rng.choice([1000.0, 2000.0, 10_000.0])),
        ),
        seed=seed,
    )
    validate_run(run)


@pytest.mark.parametrize("name", ["HarmOsc1.txt", "HarmOsc2.txt", "HarmOsc3.txt"])
def test_real_recordings_pass_validation(name: str) -> None:
    path = EXTERNAL / name
    if not path.is_file():
        pytest.skip(f"external data not present at {path}")
    read_run(path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"})


def _decaying(rate: float) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(30 * rate)) / rate
    return t, np.round(0.7 * np.exp(-0.1 * t) * np.sin(2 * np.pi * t), 3)


def test_coarsely_quantised_oversampled_peaks_are_not_flat_tops() -> None:
    # A 1 Hz oscillation sampled at 10 kHz and printed with 3 decimals repeats its
    # peak value dozens of times, but enters and leaves it by single 0.001 steps.
    t, x = _decaying(10_000.0)
    assert np.sum(x == x.max()) > 20
    validate_run(Run(t, x))


def test_flat_top_of_a_clipped_coarsely_quantised_signal_is_found() -> None:
    # At 100 Hz (like the real 100 Hz recordings) a cut at 80 % of the amplitude is
    # reached with steps of about 0.026, 26 quantisation steps. The clipped cycles are
    # the first large ones: the run passes (the energy decay starts after them and says
    # so); cut two periods after the last, it is refused naming the level.
    t, x = _decaying(100.0)
    validate_run(Run(t, x))
    clipped = np.clip(x, -0.56, 0.56)
    validate_run(Run(t, clipped))
    last = int(np.flatnonzero(np.abs(clipped) == 0.56)[-1])
    with pytest.raises(RecordingError, match=r"held flat at its (maximum|minimum) -?0.56 in"):
        validate_run(Run(t[: last + 200], clipped[: last + 200]))


def test_time_stamps_printed_with_few_digits_are_regular(tmp_path: Path) -> None:
    # 3 kHz stamps printed with 6 decimals: each step deviates by up to 0.3 % from 1/3 ms.
    t = np.round(np.arange(3000) / 3000.0, 6)
    x = 1e-3 * np.sin(2 * np.pi * 32.6 * t)
    validate_run(Run(t, x))


# -- robustness: nothing but the package's own errors on arbitrary input ---------------

_CSV_ALPHABET = string.digits + ",;.\t\n -+eE#" + "nafi"
_CSV_TOKENS = st.one_of(
    st.text(_CSV_ALPHABET, max_size=40),
    st.sampled_from(
        ["time_s", "displacement_m", "velocity_m_per_s", "nan", "inf", "1e999", "\ufeff", '"']
    ),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    text=st.lists(_CSV_TOKENS, max_size=30).map("".join),
    columns=st.sampled_from([None, ["time_s", "displacement_m"], ["time_s", "ignore"]]),
)
def test_random_csv_text_raises_only_package_errors(tmp_path_factory, text, columns) -> None:
    path = tmp_path_factory.mktemp("fuzz") / "run.csv"
    path.write_text(text, encoding="utf-8")
    try:
        read_run(path, columns=columns)
    except BayestriboError:
        pass


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.binary(max_size=600),
    suffix=st.sampled_from([".csv", ".txt", ".uff", ".tdms"]),
    prefix=st.sampled_from([b"", b"TDSm", b"    -1\n    58\n", b"time_s,displacement_m\n"]),
)
def test_random_bytes_raise_only_package_errors(tmp_path_factory, data, suffix, prefix) -> None:
    path = tmp_path_factory.mktemp("fuzz") / f"run{suffix}"
    path.write_bytes(prefix + data)
    channels = {"displacement_m": "x"} if suffix == ".tdms" else None
    try:
        read_run(path, channels=channels)
    except BayestriboError:
        pass


@pytest.mark.parametrize("offset_m", [0.0, 3e-4])
def test_swapped_channels_are_refused_naming_both(offset_m):
    # An offset of the displacement integrates to a ramp that hid the swap before.
    from bayestribo.synthetic import Release

    good = simulate(release=Release(offset_m=offset_m), seed=3)
    swapped = Run(good.time, good.velocity, good.displacement, good.metadata)
    with pytest.raises(
        RecordingError, match="'displacement_m' and 'velocity_m_per_s' look swapped"
    ):
        validate_run(swapped)


def test_channels_of_different_motions_are_refused():
    from bayestribo.synthetic import DissipationLaw

    a = simulate(seed=3)
    other = simulate(DissipationLaw(zeta=0.1), seed=4)
    n = min(a.n_samples, other.n_samples)
    mixed = Run(a.time[:n], a.displacement[:n], other.velocity[:n][::-1], a.metadata)
    with pytest.raises(RecordingError, match="do not describe one motion"):
        validate_run(mixed)


def test_a_velocity_of_opposite_sign_is_named_as_such():
    good = simulate(seed=3)
    flipped = Run(good.time, good.displacement, -good.velocity, good.metadata)
    with pytest.raises(RecordingError, match="opposite sign") as caught:
        validate_run(flipped)
    assert "scale={'velocity_m_per_s': -1} reads it" in str(caught.value)
    fixed = Run(good.time, good.displacement, -flipped.velocity, good.metadata)
    validate_run(fixed)  # the advice, followed, reads the run


def _units_file(tmp_path, t_factor, x_factor, v_factor):
    """The bundled paper-rig simulation written as a headerless file in other units."""
    from bayestribo.synthetic import simulate

    run = simulate(seed=4)
    path = tmp_path / "units.txt"
    np.savetxt(
        path,
        np.column_stack(
            [run.time / t_factor, run.displacement / x_factor, run.velocity / v_factor]
        ),
    )
    return run, path


def test_a_time_column_in_ms_is_named_with_the_signals_units_and_the_fix_works(tmp_path):
    """ms and mm read as s and m: the velocity alone "in mm/s" would make the channels
    agree at 0.03 Hz; the advice names the time unit too, and following it reads the run."""
    import re

    run, path = _units_file(tmp_path, 1e-3, 1e-3, 1e-3)
    columns = ["time_s", "displacement_m", "velocity_m_per_s"]
    with pytest.raises(RecordingError, match="likely time in ms and displacement in mm") as info:
        read_run(path, columns=columns)
    assert "velocity in mm/s (then f = 32." in str(info.value)
    scale = eval(re.search(r"scale=(\{[^}]*\})", str(info.value))[1])  # the advice as given
    fixed = read_run(path, columns=columns, scale=scale, metadata=dict(run.metadata))
    np.testing.assert_allclose(fixed.time, run.time, rtol=1e-12)
    np.testing.assert_allclose(fixed.displacement, run.displacement, rtol=1e-12)


def test_a_velocity_in_mm_per_s_alone_is_named_alone(tmp_path):
    _, path = _units_file(tmp_path, 1.0, 1.0, 1e-3)
    with pytest.raises(RecordingError) as info:
        read_run(path, columns=["time_s", "displacement_m", "velocity_m_per_s"])
    assert "likely velocity in mm/s: scale={'velocity_m_per_s': 0.001}" in str(info.value)


def test_a_stated_frequency_the_sampling_cannot_resolve_names_the_time_unit(tmp_path):
    _, path = _units_file(tmp_path, 1e-3, 1.0, 1e-3)
    with pytest.raises(RecordingError, match=r"a time column in ms read as seconds gives this"):
        read_run(
            path,
            columns=["time_s", "displacement_m", "velocity_m_per_s"],
            metadata={"natural_frequency_Hz": 32.6},
        )


def test_millimetres_read_as_metres_are_refused_without_a_mass(tmp_path):
    """Both channels in mm read as m agree with each other; no mass or load in the
    sidecar: the swing of a metre at 32.6 Hz is still refused at reading, with the
    scale factors that fix it, and following them reads the run."""
    import re

    from bayestribo.synthetic import simulate

    run = simulate(seed=5)
    path = tmp_path / "mm.txt"
    np.savetxt(path, np.column_stack([run.time, 1e3 * run.displacement, 1e3 * run.velocity]))
    columns = ["time_s", "displacement_m", "velocity_m_per_s"]
    with pytest.raises(RecordingError, match=r"plausibility: a swing of .* m at 32") as info:
        read_run(path, columns=columns)
    assert "likely displacement in mm and velocity in mm/s" in str(info.value)
    scale = eval(re.search(r"scale=(\{[^}]*\})", str(info.value))[1])
    fixed = read_run(path, columns=columns, scale=scale)
    np.testing.assert_allclose(fixed.displacement, run.displacement, rtol=1e-12)


def test_a_time_in_ms_with_only_a_displacement_is_refused_naming_the_time_unit(tmp_path):
    from bayestribo.synthetic import simulate

    run = simulate(seed=5)
    path = tmp_path / "ms.txt"
    np.savetxt(path, np.column_stack([1e3 * run.time, 1e3 * run.displacement]))
    with pytest.raises(RecordingError, match=r"likely time in ms and displacement in mm"):
        read_run(path, columns=["time_s", "displacement_m"])
    # declared arbitrary, the unit is not checked
    read_run(path, columns=["time_s", "displacement_m"], metadata={"length_unit": "arbitrary"})


def test_values_far_beyond_the_stated_range_are_a_unit_not_a_clip(good):
    """Millimetres read as metres with the sensor's range stated: the refusal names the
    unit that fixes it (and the range settles mm against cm), never "a larger range"."""
    meta = {**good.metadata, "displacement_range_m": 0.01, "velocity_range_m_per_s": 1.0}
    bad = Run(good.time, good.displacement * 1000, good.velocity * 1000, meta)
    with pytest.raises(RecordingError) as info:
        validate_run(bad)
    message = str(info.value)
    assert "larger range" not in message
    assert "scale={'displacement_m': 0.001, 'velocity_m_per_s': 0.001}" in message


def test_nan_cells_name_every_sample_and_deleting_their_rows_reads_the_run(tmp_path):
    """A DAQ's NaN for a missed reading: the refusal names the samples and says to
    delete their rows; done, the run reads and its short gaps are bridged."""
    from bayestribo.errors import GapWarning
    from bayestribo.signal import energy_decay

    good = simulate(seed=3)
    bad = good.velocity.copy()
    bad[[100, 300, 6100]] = np.nan  # single samples at rest
    path = tmp_path / "nan.csv"
    write_run(Run(good.time, good.displacement, bad, good.metadata), path)
    with pytest.raises(RecordingError, match=r"\(samples 100, 300, 6100\).*delete its row"):
        read_run(path)
    keep = np.isfinite(bad)
    write_run(Run(good.time[keep], good.displacement[keep], bad[keep], good.metadata), path)
    run = read_run(path)
    assert run.n_samples == good.n_samples - 3
    with pytest.warns(GapWarning, match="3 gap"):
        energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())


def _encoder_pendulum(scale: float) -> Run:
    """An independent pendulum decay (solve_ivp: θ'' = -ω² sin θ - 2ζωθ' - μ sgn θ'),
    released at 68°, logged at 50 Hz, its angle multiplied by ``scale`` (degrees: 180/π)."""
    from scipy.integrate import solve_ivp

    w = 2 * np.pi * 0.72
    t = np.arange(0.0, 30.0, 0.02)

    def rhs(_t, u):
        return [u[1], -w * w * np.sin(u[0]) - 2 * 0.01 * w * u[1] - 0.05 * np.sign(u[1])]

    sol = solve_ivp(rhs, (0.0, t[-1]), [np.radians(68.0), 0.0], t_eval=t, rtol=1e-9, atol=1e-11)
    return Run(t, scale * sol.y[0], metadata={"length_unit": "rad"})


def test_degrees_read_as_radians_are_refused_naming_the_degrees() -> None:
    # an encoder's degrees with a column named angle_rad: 68 "rad", fitted as 11 turns
    # each way without a word before
    degrees = _encoder_pendulum(180.0 / np.pi)
    refused = r"plausibility: the angle swings by 6\d\.\d rad .*likely degrees.*angle_deg"
    with pytest.raises(RecordingError, match=refused):
        validate_run(degrees)
    validate_run(_encoder_pendulum(1.0))  # the same decay in radians passes


def test_a_pendulum_whose_angle_turns_over_is_refused_cleanly() -> None:
    # with a pendulum's restoring force the potential raised ValueError deep in the fit;
    # now a clean refusal before it, naming the angle in degrees as the likely cause
    run = _encoder_pendulum(3.0)  # 204°: beyond π, within a turn
    run = Run(run.time, run.displacement, metadata={"length_unit": "rad", "restoring": "pendulum"})
    with pytest.raises(RecordingError, match=r"beyond π, where a pendulum turns over.*angle_deg"):
        validate_run(run)


def test_an_angular_velocity_in_degrees_read_as_radians_is_refused() -> None:
    # a rate gyro's deg/s labelled rad/s: the angle it integrates to swings by 68 "rad"
    run = _encoder_pendulum(180.0 / np.pi)
    velocity = np.gradient(run.displacement, run.time)
    alone = Run(run.time, None, velocity, metadata={"length_unit": "rad"})
    with pytest.raises(RecordingError, match=r"plausibility: the angle swings by .*angle_deg"):
        validate_run(alone)
    in_radians = Run(run.time, None, velocity * np.pi / 180.0, metadata={"length_unit": "rad"})
    validate_run(in_radians)


def test_a_row_written_twice_is_read_once_and_said(tmp_path):
    # rows that repeat the one before exactly (a logger that wrote them twice) hold
    # nothing new: each is read once, with a warning naming how many and the first
    from bayestribo.errors import ReadingWarning

    run = simulate(seed=5)
    path = tmp_path / "run.csv"
    write_run(run, path)
    lines = path.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("time_s"))
    doubled = [*lines[: header + 60], lines[header + 59], *lines[header + 60 :]]
    doubled = [*doubled[: header + 301], doubled[header + 300], *doubled[header + 301 :]]
    twice = tmp_path / "twice.csv"
    twice.write_text("\n".join(doubled) + "\n")
    with pytest.warns(ReadingWarning, match=r"2 samples repeat the one before exactly.*sample 59"):
        got = read_run(twice)
    clean = read_run(path)
    np.testing.assert_array_equal(got.time, clean.time)
    np.testing.assert_array_equal(got.displacement, clean.displacement)
    np.testing.assert_array_equal(got.velocity, clean.velocity)
    # a Run given as it is gets the same
    from bayestribo.io import as_run

    repeated = Run(
        np.insert(clean.time, 60, clean.time[59]),
        np.insert(clean.displacement, 60, clean.displacement[59]),
        np.insert(clean.velocity, 60, clean.velocity[59]),
        dict(clean.metadata),
    )
    with pytest.warns(ReadingWarning, match="1 sample repeat"):
        np.testing.assert_array_equal(as_run(repeated).time, clean.time)


def test_a_repeated_stamp_with_other_values_is_refused_naming_both_samples():
    run = simulate(seed=5)
    bad = _replace(run, time=_with(run.time, 100, run.time[99]))
    with pytest.raises(RecordingError, match=r"sample 100 .* with other values than sample 99"):
        validate_run(bad)
