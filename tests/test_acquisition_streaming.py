"""Bounded memory: the run is indexed, not held, and its CSV written while it streams.

The assembler keeps where each DATA frame lies in the raw log, not its samples; the
checks here compare it with an obviously-right reference (every frame's counts in a
dict, sorted at the end, as the assembler did before it was made lean), write the CSV
in chunks and compare it byte for byte with :func:`bayestribo.io.text.write_csv`.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bayestribo.acquisition import OperatorInputs, acquire_run, recover_run
from bayestribo.acquisition.assembly import assemble_bytes, assemble_file
from bayestribo.acquisition.csvstream import CsvStream
from bayestribo.acquisition.instrument import FaultPlan, SimulatedInstrument, SimulationConfig
from bayestribo.acquisition.protocol import (
    FrameType,
    RunHeader,
    encode_data,
    encode_end,
    encode_frame,
)
from bayestribo.io import read_run
from bayestribo.io.text import write_csv

HEADER = RunHeader(
    sample_rate_Hz=1000.0,
    displacement_scale_m=2e-3 / 32767,
    velocity_scale_m_per_s=0.5 / 32767,
    displacement_range_m=2e-3,
    velocity_range_m_per_s=0.5,
    samples_per_frame=4,
    range_label="test",
)
INPUTS = OperatorInputs(load_N=0.31, lubricant="glycerol", repeat=1, mass_kg=0.035)


def reference(frames: list[tuple[int, int, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Samples as the first-kept rule gives them: every accepted frame in a dict, sorted.

    ``frames`` are (seq, first, counts) in arrival order, all after one header.
    """
    seqs: dict[int, tuple[int, bytes]] = {0: (-1, b"")}
    data: dict[int, np.ndarray] = {}
    for seq, first, counts in frames:
        if seq in seqs or first in data:
            continue
        seqs[seq] = (first, counts.tobytes())
        data[first] = counts
    expected, index, chunks = 0, [], []
    for first in sorted(data):
        counts = data[first]
        if first < expected:
            counts = counts[expected - first :]
            first = expected
            if len(counts) == 0:
                continue
        index.append(np.arange(first, first + len(counts)))
        chunks.append(counts)
        expected = first + len(counts)
    if not index:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2), dtype=np.int16)
    return np.concatenate(index), np.concatenate(chunks)


def stream(frames: list[tuple[int, int, np.ndarray]], end: tuple[int, int] | None) -> bytes:
    out = [encode_frame(FrameType.HEADER, 0, HEADER.to_payload())]
    out += [encode_frame(FrameType.DATA, s, encode_data(f, c)) for s, f, c in frames]
    if end is not None:
        out.append(encode_frame(FrameType.END, end[0], encode_end(*end)))
    return b"".join(out)


def frames_of(n_frames: int, n: int = 4, seed: int = 0) -> list[tuple[int, int, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [
        (1 + k, k * n, rng.integers(-30000, 30000, (n, 2)).astype(np.int16))
        for k in range(n_frames)
    ]


def test_an_undisturbed_run_is_one_block_whatever_its_length():
    frames = frames_of(500)
    run = assemble_bytes(stream(frames, (501, 2000)))
    assert run.complete and run.n_samples == 2000
    assert len(run.pieces) == 1 and run.pieces[0].count == 500
    index, counts = reference(frames)
    assert np.array_equal(run.sample_index, index) and np.array_equal(run.counts, counts)


def test_a_late_retransmission_fills_its_gap_in_order():
    frames = frames_of(10)
    late = frames[3]
    arrived = frames[:3] + frames[4:] + [late]  # frame 3 comes again at the end
    run = assemble_bytes(stream(arrived, (11, 40)))
    assert run.complete and len(run.pieces) == 3
    _, counts = reference(arrived)
    assert np.array_equal(run.sample_index, np.arange(40))
    assert np.array_equal(run.counts, counts)


def test_chunks_give_the_samples_in_runs_of_consecutive_indices():
    frames = frames_of(50)
    del frames[20]
    run = assemble_bytes(stream(frames, (51, 200)))
    chunks = list(run.chunks(max_samples=12))  # three frames of four samples a chunk
    assert all(len(c) <= 12 for _, c in chunks)
    for first, counts in chunks:
        expected = run.sample_index[run.sample_index >= first][: len(counts)]
        assert np.array_equal(expected, np.arange(first, first + len(counts)))
    assert np.array_equal(np.concatenate([c for _, c in chunks]), run.counts)
    assert run.report["gaps"][0]["start_sample"] == 80


@settings(max_examples=60, deadline=None)
@given(
    order=st.permutations(range(12)),
    repeats=st.lists(st.integers(0, 11), max_size=4),
    drops=st.sets(st.integers(0, 11), max_size=3),
    shifts=st.lists(st.tuples(st.integers(0, 11), st.integers(-3, 3)), max_size=3),
)
def test_any_arrival_order_gives_the_reference_samples(order, repeats, drops, shifts):
    # Frames arrive in any order, some twice, some never, some at shifted (overlapping)
    # first samples: the index gives what keeping every frame's samples gives.
    base = frames_of(12, seed=len(order))
    shifted = dict(shifts)
    frames = [
        (s, max(0, f + shifted.get(k, 0)), c) for k, (s, f, c) in enumerate(base) if k not in drops
    ]
    arrived = [frames[k] for k in order if k < len(frames)]
    arrived += [frames[k] for k in repeats if k < len(frames)]
    run = assemble_bytes(stream(arrived, None))
    index, counts = reference(arrived)
    assert np.array_equal(run.sample_index, index)
    assert np.array_equal(run.counts, counts)
    assert run.report["samples_received"] == len(index)


def test_a_conflicting_repeat_is_found_by_reading_the_first_one_back():
    frames = frames_of(6)
    seq, first, counts = frames[2]
    other = counts.copy()
    other[0, 0] += 1
    run = assemble_bytes(stream([*frames, (seq, first, other)], (7, 24)))
    assert run.report["conflicting_frames"] == 1 and not run.complete
    assert np.array_equal(run.counts, reference(frames)[1])


def test_the_file_and_the_bytes_give_the_same_run(tmp_path):
    frames = frames_of(300)
    data = stream(frames[:100] + frames[101:] + [frames[100]], (301, 1200))
    raw = tmp_path / "r.raw"
    raw.write_bytes(b"\x00garbage" + data)
    run, assembler = assemble_file(raw)
    in_memory = assemble_bytes(b"\x00garbage" + data)
    assert not assembler.in_order  # the late frame went to no sink
    assert run.report == in_memory.report
    assert np.array_equal(run.counts, in_memory.counts)


@pytest.mark.parametrize("n_rows", [0, 1, 5000])
def test_the_streamed_csv_is_the_one_write_csv_writes(tmp_path, n_rows):
    rng = np.random.default_rng(n_rows)
    counts = rng.integers(-32768, 32768, (n_rows, 2)).astype(np.int16)
    csv = CsvStream(tmp_path / "s.csv", HEADER)
    for start in range(0, n_rows, 700):
        csv.append(start + 3, counts[start : start + 700])
    digest = csv.close()
    index = np.arange(n_rows) + 3
    write_csv(
        {
            "time_s": index / HEADER.sample_rate_Hz,
            "displacement_m": counts[:, 0] * HEADER.displacement_scale_m,
            "velocity_m_per_s": counts[:, 1] * HEADER.velocity_scale_m_per_s,
        },
        tmp_path / "w.csv",
    )
    assert (tmp_path / "s.csv").read_bytes() == (tmp_path / "w.csv").read_bytes()
    import hashlib

    assert digest == hashlib.sha256((tmp_path / "w.csv").read_bytes()).hexdigest()


def test_rows_out_of_order_are_refused(tmp_path):
    csv = CsvStream(tmp_path / "s.csv", HEADER)
    csv.append(10, np.zeros((4, 2), dtype=np.int16))
    with pytest.raises(ValueError, match="first: sample 12 is before sample 14"):
        csv.append(12, np.zeros((1, 2), dtype=np.int16))
    csv.abort()


def _acquire(tmp_path, faults: FaultPlan | None = None):
    config = SimulationConfig(duration_s=0.4, samples_per_frame=32, noise_counts=2.0)
    with SimulatedInstrument(config, faults, realtime=False) as sim:
        result = acquire_run(sim.start_pty(), tmp_path, INPUTS, timeout_s=5.0)
    return result


def test_the_live_csv_is_what_a_recovery_writes(tmp_path):
    result = _acquire(tmp_path / "live", FaultPlan(drop=frozenset({5}), garbage=frozenset({9})))
    assert not result.complete and result.metadata["samples_missing"] == 32
    recovered = recover_run(result.files.raw, out_dir=tmp_path / "again")
    assert recovered.files.csv.read_bytes() == result.files.csv.read_bytes()
    assert recovered.run.report == result.run.report
    back = read_run(result.files.csv, validate=False)
    assert np.array_equal(back.time, result.run.time_s)
    assert np.array_equal(back.displacement, result.run.displacement_m)
    assert np.array_equal(back.velocity, result.run.velocity_m_per_s)
    live = tmp_path / "live"
    assert not [p for p in live.iterdir() if p.name.startswith(".")]  # no staging left


def test_a_crashed_loggers_staging_directory_is_removed_by_the_recovery(tmp_path):
    result = _acquire(tmp_path)
    for path in (result.files.csv, result.files.json, result.files.manifest):
        path.unlink()
    staging = tmp_path / f".{result.run_id}.staging-abc12_yz"
    staging.mkdir()
    (staging / f"{result.run_id}.csv").write_text("time_s,displacement_m\n0.0,")
    # The staging of another run whose id starts with this one's is left alone.
    other = tmp_path / f".{result.run_id}.2.staging-abc12_yz"
    other.mkdir()
    recovered = recover_run(result.files.raw)
    assert recovered.complete and not staging.exists() and other.is_dir()
    csv = result.files.csv.name
    assert recovered.files.digests[csv] == result.files.digests[csv]


def test_a_csv_that_cannot_be_written_is_a_storage_error_and_recover_rebuilds_it(
    tmp_path, monkeypatch
):
    # The disk takes the raw log but not the CSV (written while streaming, then again
    # from the raw log at the end): the package's storage error names --recover, no
    # run file and no staging directory are left, and the raw log holds the whole run.
    import errno

    from bayestribo.acquisition import csvstream
    from bayestribo.acquisition.faults import StorageError

    def full(self) -> None:
        self._pending.clear()
        self.error = self.error or OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as patch:
        patch.setattr(csvstream.CsvStream, "flush", full)
        with pytest.raises(StorageError, match=r"No space left.*--recover"):
            _acquire(tmp_path)
    [raw] = tmp_path.glob("*.raw")
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [raw.name, f"{raw.stem}.session.json"]
    recovered = recover_run(raw)
    assert recovered.complete and recovered.run.n_samples > 0
