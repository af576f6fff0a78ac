"""WAV files: a free decay written as integer PCM (8, 16, 24, 32 bit) and float, read
back within the quantisation and fitted; a file that does not say what it holds is
refused with the options that read it; bad files are refused naming what is wrong."""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.io.wavfile
from _free_decay import F_HZ, METADATA, RATE_HZ, RELEASE_S, X_C, ZETA, free_decay

from bayestribo import fit, read_run
from bayestribo.cli import main
from bayestribo.errors import ClippingWarning, ReadingWarning, RecordingError, RunFormatError
from bayestribo.io.layout import describe_file
from bayestribo.io.registry import format_for
from bayestribo.signal.decay import energy_decay

ARBITRARY = {"length_unit": "arbitrary"}


@pytest.fixture(scope="module")
def decay():
    return free_decay()


def _pcm(values: np.ndarray, bits: int) -> np.ndarray:
    """Fractions of full scale as the integer counts of a ``bits``-bit WAV."""
    counts = np.round(values * 2.0 ** (bits - 1))
    if bits == 8:
        return (counts + 128).astype(np.uint8)
    return counts.astype({16: np.int16, 32: np.int32}[bits])


def _write_24_bit(path: Path, counts: np.ndarray, rate: int, *, extensible: bool) -> Path:
    """A 24-bit PCM WAV (``counts``: frames x channels), written byte by byte as an
    audio interface writes it (WAVE_FORMAT_EXTENSIBLE when ``extensible``)."""
    counts = np.asarray(counts, dtype=np.int64).reshape(counts.shape[0], -1)
    channels = counts.shape[1]
    raw = (counts & 0xFFFFFF).astype("<u4").view(np.uint8).reshape(-1, 4)[:, :3].tobytes()
    align = 3 * channels
    if extensible:
        guid = struct.pack("<IHH", 1, 0x0000, 0x0010) + bytes.fromhex("800000aa00389b71")
        fmt = struct.pack("<HHIIHHHHI", 0xFFFE, channels, rate, rate * align, align, 24, 22, 24, 0)
        fmt += guid
    else:
        fmt = struct.pack("<HHIIHH", 1, channels, rate, rate * align, align, 24)
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt
    body += b"data" + struct.pack("<I", len(raw)) + raw + (b"\0" if len(raw) % 2 else b"")
    path.write_bytes(b"RIFF" + struct.pack("<I", len(body)) + body)
    return path


@pytest.mark.parametrize("bits", [8, 16, 32])
def test_integer_pcm_reads_as_fractions_of_full_scale_exactly(tmp_path, decay, bits) -> None:
    path = tmp_path / f"pcm{bits}.wav"
    counts = _pcm(decay.displacement, bits)
    scipy.io.wavfile.write(path, RATE_HZ, counts)
    run = read_run(path, channels={"displacement_m": "0"}, metadata=ARBITRARY, validate=False)
    zero = 128.0 if bits == 8 else 0.0
    np.testing.assert_array_equal(
        run.displacement, (counts.astype(np.float64) - zero) / 2.0 ** (bits - 1)
    )
    # the counts are the decay rounded: within half a step of it
    assert np.abs(run.displacement - decay.displacement).max() <= 0.5 / 2.0 ** (bits - 1)
    np.testing.assert_array_equal(run.time, np.arange(decay.time.size) / RATE_HZ)


@pytest.mark.parametrize("extensible", [False, True])
def test_24_bit_pcm_reads_as_fractions_of_full_scale(tmp_path, decay, extensible) -> None:
    counts = np.round(decay.displacement * 2.0**23).astype(np.int64)
    path = _write_24_bit(tmp_path / "pcm24.wav", counts, RATE_HZ, extensible=extensible)
    run = read_run(path, channels={"displacement_m": 0}, metadata=ARBITRARY, validate=False)
    np.testing.assert_array_equal(run.displacement, counts / 2.0**23)
    assert "24-bit integer PCM, 1 channel at 2000 Hz" in describe_file(path)["reader"]


def test_float_wav_reads_as_stored(tmp_path, decay) -> None:
    path = tmp_path / "float.wav"
    scipy.io.wavfile.write(path, RATE_HZ, decay.displacement.astype(np.float32))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReadingWarning)  # float: no full-scale warning
        run = read_run(path, channels={"displacement_mm": "0"}, validate=False)
    want = decay.displacement.astype(np.float32).astype(np.float64) * 1e-3
    np.testing.assert_allclose(run.displacement, want, rtol=1e-15, atol=0)
    assert describe_file(path)["reader"].startswith("WAV, 32-bit float, 1 channel")


def test_stereo_channels_by_number_and_name(tmp_path, decay) -> None:
    path = tmp_path / "stereo.wav"
    frames = np.column_stack([decay.displacement, decay.velocity / 200.0]).astype(np.float32)
    scipy.io.wavfile.write(path, RATE_HZ, frames)
    by_name = read_run(
        path,
        channels={"displacement_m": "left", "velocity_m_per_s": "right"},
        scale={"velocity_m_per_s": 200.0},
        metadata=ARBITRARY,
        validate=False,
    )
    by_number = read_run(
        path,
        channels={"velocity_m_per_s": 1, "displacement_m": 0},
        scale={"velocity_m_per_s": 200.0},
        metadata=ARBITRARY,
        validate=False,
    )
    np.testing.assert_array_equal(by_name.displacement, frames[:, 0])
    np.testing.assert_array_equal(by_name.velocity, frames[:, 1].astype(np.float64) * 200.0)
    np.testing.assert_array_equal(by_number.velocity, by_name.velocity)
    columns = describe_file(path)["columns"]
    assert [c["label"] for c in columns] == ["0 (left)", "1 (right)"]


def test_an_accelerometer_channel_is_integrated_into_the_velocity(tmp_path, decay) -> None:
    path = tmp_path / "accelerometer.wav"
    scipy.io.wavfile.write(path, RATE_HZ, decay.acceleration / 2e4)  # float64, as stored
    with pytest.warns(ReadingWarning, match="integrated from the acceleration"):
        run = read_run(
            path,
            channels={"acceleration_m_per_s2": "0"},
            scale={"acceleration_m_per_s2": 2e4},
            metadata=ARBITRARY,
        )
    assert run.displacement is None
    assert run.metadata["acceleration"]["column"] == "acceleration_m_per_s2"
    # the channel read is the one integrated: past the high-pass's transient after the
    # release's step (the integrator's own accuracy, tests/test_io_acceleration.py),
    # the velocity is the decay's within 1 % of its swing
    late = decay.time > RELEASE_S + 5.0 / F_HZ
    error = np.abs(run.velocity - decay.velocity)[late].max()
    assert error < 0.01 * np.abs(decay.velocity).max()


def test_integer_pcm_named_in_metres_without_a_sensitivity_is_said(tmp_path, decay) -> None:
    path = tmp_path / "pcm.wav"
    scipy.io.wavfile.write(path, RATE_HZ, _pcm(decay.displacement, 16))
    with pytest.warns(ReadingWarning, match=r"16-bit integer PCM as fractions of the sound"):
        read_run(path, channels={"displacement_m": "0"}, validate=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ReadingWarning)
        scaled = read_run(
            path, channels={"displacement_m": "0"}, scale={"displacement_m": 2e-3}, validate=False
        )
        plain = read_run(path, channels={"displacement_m": "0"}, metadata=ARBITRARY)
    np.testing.assert_allclose(scaled.displacement, 2e-3 * plain.displacement, rtol=1e-15)


def test_a_wav_without_channels_named_is_refused_and_the_advice_reads_it(
    tmp_path, decay, capsys
) -> None:
    path = tmp_path / "piezo.wav"
    scipy.io.wavfile.write(path, RATE_HZ, _pcm(decay.displacement, 16))
    with pytest.raises(RunFormatError, match=r"states no quantity and no unit.*channels="):
        read_run(path)
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert "channels=" not in err and "length_unit=" not in err
    assert "velocity_m_per_s" in err and "acceleration_m_per_s2" in err
    advice = re.search(r"(--channel \S+) and (--length-unit \S+)", err)
    assert advice is not None, err
    options = " ".join(advice.groups()).split()
    assert main(["inspect", str(path), *options]) == 0
    out = capsys.readouterr().out
    assert "WAV, 16-bit integer PCM" in out and "0 [full scale]" in out
    assert "arbitrary length unit" in out


@pytest.mark.filterwarnings("ignore::bayestribo.errors.ShortAnalysisWarning")
def test_the_clipping_of_a_sound_card_is_found(tmp_path, decay) -> None:
    # the input overdriven fourfold: the first ten cycles held at full scale
    path = tmp_path / "clipped.wav"
    loud = np.clip(4.0 * decay.displacement, -1.0, 32767 / 32768)
    scipy.io.wavfile.write(path, RATE_HZ, _pcm(loud, 16))
    last_clip = float(decay.time[np.abs(loud) >= 32767 / 32768].max())
    # eleven periods follow the clipping: read, and the analysis leaves the clipped
    # cycles out, saying so
    run = read_run(path, channels={"displacement_m": "0"}, metadata=ARBITRARY)
    with pytest.warns(ClippingWarning, match=r"'displacement' is clipped: it is held flat"):
        decay_ = energy_decay(run.time, run.displacement, None)
    assert decay_.start_time > last_clip
    # cut two periods after it: too little is left, refused
    with pytest.raises(RecordingError, match=r"'displacement_m' is clipped: it is held flat"):
        read_run(
            path,
            channels={"displacement_m": "0"},
            metadata=ARBITRARY,
            window=(0.0, last_clip + 2.0 / F_HZ),
        )


def test_wav_is_listed_and_chosen_by_suffix_or_format(tmp_path, decay, capsys) -> None:
    assert main(["inspect", "--formats"]) == 0
    assert re.search(r"^wav\s+\.wav", capsys.readouterr().out, re.MULTILINE)
    assert format_for("x.WAV").name == "wav"
    path = tmp_path / "record.dat"  # a WAV saved under a text suffix: named, not parsed
    scipy.io.wavfile.write(path, RATE_HZ, decay.displacement.astype(np.float32))
    named = r"not delimited text: its first bytes .* are those of WAV sound \(wav\) files"
    with pytest.raises(RunFormatError, match=named):
        read_run(path, columns=["displacement_m"], metadata=ARBITRARY)
    with pytest.raises(RunFormatError, match=named):
        describe_file(path)
    run = read_run(path, file_format="wav", channels={"displacement_m": "0"}, metadata=ARBITRARY)
    assert run.n_samples == decay.time.size
    cli = ["--format", "wav", "--channel", "x=0", "--length-unit", "arbitrary", "--json"]
    assert main(["inspect", str(path), *cli]) == 0
    assert '"format": "wav"' in capsys.readouterr().out


def _bad(tmp: Path, name: str, content: bytes) -> Path:
    path = tmp / name
    path.write_bytes(content)
    return path


def test_bad_wav_files_are_refused_naming_what_is_wrong(tmp_path, decay) -> None:
    good = tmp_path / "good.wav"
    scipy.io.wavfile.write(good, RATE_HZ, _pcm(decay.displacement, 16))
    x = {"channels": {"displacement_m": "0"}, "metadata": ARBITRARY}
    with pytest.raises(RunFormatError, match=r"channels\['displacement_m'\]: no channel '1'"):
        read_run(good, channels={"displacement_m": 1}, metadata=ARBITRARY)
    with pytest.raises(RunFormatError, match=r"channels\['time_s'\]: a WAV file's time is"):
        read_run(good, channels={"time_s": 0, "displacement_m": 0}, metadata=ARBITRARY)
    with pytest.raises(RunFormatError, match=r"column 'displacement' has no unit"):
        read_run(good, channels={"displacement": 0}, metadata=ARBITRARY)
    with pytest.raises(RunFormatError, match=r"'columns' applies to .* not to a wav file"):
        read_run(good, columns=["displacement_m"])
    with pytest.raises(RunFormatError, match=r"empty \(0 bytes\); expected a WAV file"):
        read_run(_bad(tmp_path, "empty.wav", b""), **x)
    silent = tmp_path / "silent.wav"
    scipy.io.wavfile.write(silent, RATE_HZ, np.zeros(0, np.int16))
    with pytest.raises(RunFormatError, match=r"holds no samples"):
        read_run(silent, **x)
    whole = good.read_bytes()
    with pytest.raises(
        RunFormatError, match=r"declares 4800 bytes but the file ends 2400 bytes .* cut short"
    ):
        read_run(_bad(tmp_path, "cut.wav", whole[:-2400]), **x)
    with pytest.raises(RunFormatError, match=r"not a WAV file: it starts with b'time"):
        read_run(_bad(tmp_path, "text.wav", b"time_s,displacement_m\n0,1\n"), **x)
    adpcm = whole[:20] + struct.pack("<H", 2) + whole[22:]  # format tag 2: MS ADPCM
    with pytest.raises(RunFormatError, match=r"format tag 0x0002 .* is not read"):
        read_run(_bad(tmp_path, "adpcm.wav", adpcm), **x)


def test_a_wav_record_is_fitted_with_its_truth_inside_the_intervals(tmp_path, decay) -> None:
    path = tmp_path / "decay.wav"
    scipy.io.wavfile.write(path, RATE_HZ, _pcm(decay.displacement, 16))
    result = fit(
        path,
        read_options={"channels": {"displacement_m": "0"}, "metadata": METADATA},
        seed=3,
        grid_points=32,
    )
    assert result.converged
    for name, truth in (("zeta", ZETA), ("friction_displacement", X_C)):
        low, high = result.interval(name)
        assert low < truth < high, (name, low, high, truth)
