"""The reference firmware (``firmware/``) against the host, through a pseudo-terminal.

The C library is compiled with the system compiler into ``host_sim``, which runs the
board logic behind a pty with a synthetic damped oscillation and writes every sample
it takes to a side file. The host (``bayestribo acquire`` and its library entry) must
give back exactly those samples, and, with frames dropped, corrupted or lost to an
overrun of the board's buffers, exactly the others, with the run reported incomplete
and the missing samples listed. The command rules of ``docs/protocol.md`` are checked
on the firmware and on the package's simulated instrument alike.
"""

from __future__ import annotations

import json
import shutil
import struct
import subprocess
import time
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from bayestribo.acquisition import OperatorInputs, acquire_run
from bayestribo.acquisition.instrument import SimulatedInstrument, SimulationConfig
from bayestribo.acquisition.protocol import (
    Frame,
    FrameParser,
    FrameType,
    RunHeader,
    decode_data,
    decode_end,
    decode_release,
    decode_text,
)
from bayestribo.io import read_run

FIRMWARE = Path(__file__).resolve().parents[1] / "firmware"
CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
needs_cc = pytest.mark.skipif(
    CC is None, reason="no C compiler (cc, gcc or clang) on PATH: the firmware cannot be built"
)
INPUTS = OperatorInputs(load_N=0.31, lubricant="glycerol", repeat=1)
SCALES = (2e-3 / 32767, 0.5 / 32767)


@pytest.fixture(scope="module")
def host_sim(tmp_path_factory) -> Path:
    """``firmware/host_sim`` built with the system compiler, warnings shown as failures."""
    if CC is None:
        pytest.skip("no C compiler (cc, gcc or clang) on PATH: the firmware cannot be built")
    exe = tmp_path_factory.mktemp("firmware") / "host_sim"
    sources = [str(FIRMWARE / "host_sim.c"), str(FIRMWARE / "tribo_board.c")]
    flags = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-O2"]
    built = subprocess.run(
        [CC, *flags, "-o", str(exe), *sources, "-lm"], capture_output=True, text=True
    )
    assert built.returncode == 0, built.stderr
    assert "warning" not in built.stderr, built.stderr
    return exe


@contextmanager
def firmware(exe: Path, *args: str) -> Iterator[str]:
    """Run ``host_sim`` with options; yield the device path of its pty."""
    proc = subprocess.Popen([str(exe), *args], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        yield proc.stdout.readline().strip()
    finally:
        proc.terminate()
        proc.wait(5)


def side_file(path: Path) -> np.ndarray:
    """The samples the firmware took: pair k is sample index k."""
    return np.fromfile(path, dtype="<i2").reshape(-1, 2)


@needs_cc
def test_the_firmware_checks_its_crc_and_its_float_encoding(host_sim):
    # CRC-32 check value of "123456789", chained in two parts; binary64 bits made from
    # binary32 ones (the path of boards whose double is 32-bit) for normal, subnormal,
    # signed-zero values; 20000.0 written little-endian.
    out = subprocess.run([str(host_sim), "--selftest"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "selftest ok"


@needs_cc
def test_a_firmware_run_arrives_sample_for_sample(host_sim, tmp_path):
    side = tmp_path / "side.bin"
    with firmware(host_sim, "--unpaced", "--once", "--samples", str(side)) as port:
        result = acquire_run(
            port, tmp_path / "out", INPUTS, duration_s=0.5, samples_per_frame=96, catalog=None
        )
    taken = side_file(side)
    run = result.run
    release = run.report["release_sample_index"]
    assert result.complete, {k: v for k, v in run.report.items() if k != "device_header"}
    # Every sample the board took, in order; the run ends DUR × RATE samples after the
    # release, so its last, shorter frame was flushed before END.
    assert run.n_samples == len(taken) == release + 10_000
    assert np.array_equal(run.sample_index, np.arange(len(taken)))
    assert np.array_equal(run.counts, taken)
    header = run.report["device_header"]
    assert header["samples_per_frame"] == 96 and header["sample_rate_Hz"] == 20_000.0
    assert header["displacement_scale_m_per_count"] == SCALES[0]
    assert run.report["device_ident"] == "bayestribo,host_sim,0001,tribo_board-1"
    # The canonical reader, with every check on, gives the same samples in SI units.
    back = read_run(result.files.csv)
    assert np.array_equal(back.displacement, taken[:, 0] * SCALES[0])
    assert np.array_equal(back.velocity, taken[:, 1] * SCALES[1])
    assert np.array_equal(back.time, np.arange(len(taken)) / 20_000.0)


@needs_cc
def test_a_corrupted_and_a_dropped_frame_leave_the_run_incomplete_losing_nothing(
    host_sim, tmp_path, capsys
):
    from bayestribo.cli import main

    side = tmp_path / "side.bin"
    out = tmp_path / "out"
    faults = ["--drop", "3", "--corrupt", "7", "--garbage", "5"]
    with firmware(host_sim, "--once", "--unpaced", "--samples", str(side), *faults) as port:
        argv = ["acquire", "--port", port, "--load", "0.31", "--lubricant", "glycerol"]
        options = ["--duration", "0.2", "--samples-per-frame", "64", "--out", str(out)]
        status = main([*argv, *options, "--no-catalog", "--quiet", "--run-id", "fw"])
    assert status == 1  # written incomplete
    err = capsys.readouterr()
    assert "Traceback" not in err.err and "INCOMPLETE: frames or samples missing" in err.err
    meta = json.loads((out / "fw.json").read_text())
    acq = meta["acquisition"]
    assert meta["complete"] is False
    # DATA frames 3 and 7 (samples 192..255 and 448..511, before the release at 50 ms)
    # carry sequence numbers 4 and 8: both listed, nothing else missing.
    assert acq["missing_sequence_numbers"] == [4, 8]
    assert [(g["start_sample"], g["stop_sample"]) for g in meta["gaps"]] == [(192, 256), (448, 512)]
    assert acq["rejected_frame_candidates"] >= 1 and acq["discarded_bytes"] > 64
    taken = side_file(side)
    back = read_run(out / "fw.csv", validate=False)
    index = np.rint(back.time * 20_000).astype(np.int64)
    kept = np.ones(len(taken), dtype=bool)
    kept[192:256] = kept[448:512] = False
    assert np.array_equal(index, np.flatnonzero(kept))  # every other sample is there
    assert np.array_equal(back.displacement, taken[index, 0] * SCALES[0])
    assert np.array_equal(back.velocity, taken[index, 1] * SCALES[1])


@needs_cc
def test_an_overrun_of_the_boards_buffers_loses_whole_frames_and_says_which(host_sim, tmp_path):
    # The link takes nothing for 60 ms of samples (on the board's sample clock, whatever
    # the load of the machine) after DATA frame 2 while samples keep coming at
    # 20 kS/s: the board's four buffers fill, later frames are lost whole with their
    # sequence numbers used, and the host lists exactly their samples as missing.
    side = tmp_path / "side.bin"
    with firmware(host_sim, "--once", "--samples", str(side), "--stall-link", "2", "60") as port:
        result = acquire_run(
            port, tmp_path / "out", INPUTS, duration_s=0.1, samples_per_frame=32, catalog=None
        )
    report = result.run.report
    taken = side_file(side)
    assert not result.complete and report["samples_missing"] > 0
    assert report["frames_missing"] == len(report["missing_sequence_numbers"]) > 0
    for gap in report["gaps"]:  # whole frames: start and length on frame boundaries
        assert gap["start_sample"] % 32 == 0 and gap["n_samples"] % 32 == 0
    assert report["samples_reported_by_device"] == len(taken)
    assert report["samples_received"] + report["samples_missing"] == len(taken)
    assert np.array_equal(result.run.counts, taken[result.run.sample_index])


# -- the command rules, on the firmware and on the simulated instrument ------------------


class Conversation:
    """Send command lines to a board on a pty and read its frames.

    Every frame is filed once, as it comes off the link and in the order it came:
    DATA frames into :attr:`data`, the others into :attr:`answers`. Both queues
    therefore keep the board's order whatever the reads happen to return together
    (a DATA frame that shares a read with an answer is never overtaken by a later one).
    """

    #: Longest wait for a frame [s]: a guard against a hang, not a measure of speed.
    PATIENCE_S = 30.0

    def __init__(self, port: str) -> None:
        import serial

        self.port = serial.Serial(port, timeout=0.05)
        self.parser = FrameParser()
        self.answers: deque[Frame] = deque()
        self.data: list[Frame] = []

    def send(self, line: str) -> None:
        self.port.write(line.encode() + b"\n")

    def _read(self) -> None:
        """Read what the link has and file each complete frame in arrival order."""
        for frame in self.parser.feed(self.port.read(self.port.in_waiting or 1)):
            (self.data if frame.type == FrameType.DATA else self.answers).append(frame)

    def _read_until(self, done: Callable[[], bool], what: str) -> None:
        deadline = time.monotonic() + self.PATIENCE_S
        while not done():
            if time.monotonic() > deadline:
                raise AssertionError(f"{what} within {self.PATIENCE_S} s")
            self._read()

    def answer(self, line: str | None = None) -> Frame:
        """The next frame other than DATA (DATA frames are kept in :attr:`data`)."""
        if line is not None:
            self.send(line)
        self._read_until(lambda: bool(self.answers), f"no answer to {line!r}")
        return self.answers.popleft()

    def wait_data(self, n: int) -> None:
        """Read until ``n`` DATA frames have arrived (answers are kept for later)."""
        self._read_until(lambda: len(self.data) >= n, f"fewer than {n} DATA frames")

    def close(self) -> None:
        self.port.close()


@contextmanager
def board(kind: str, exe: Path | None) -> Iterator[Conversation]:
    if kind == "firmware":
        if exe is None:
            pytest.skip("no C compiler (cc, gcc or clang) on PATH: the firmware cannot be built")
        with firmware(exe) as port:
            talk = Conversation(port)
            try:
                yield talk
            finally:
                talk.close()
    else:
        config = SimulationConfig(duration_s=0.2, samples_per_frame=128)
        with SimulatedInstrument(config, realtime=True) as sim:
            talk = Conversation(sim.start_pty())
            try:
                yield talk
            finally:
                talk.close()


@pytest.fixture
def maybe_host_sim(request) -> Path | None:
    return request.getfixturevalue("host_sim") if CC is not None else None


def expect(frame: Frame, kind: int, text: str | None = None, seq: int | None = 0) -> None:
    assert frame.type == kind, (frame, decode_text(frame))
    if text is not None:
        assert decode_text(frame) == text
    if seq is not None:
        assert frame.seq == seq


@pytest.mark.parametrize("kind", ["firmware", "python"])
def test_the_command_rules_of_the_protocol(kind, maybe_host_sim):
    with board(kind, maybe_host_sim) as talk:
        expect(talk.answer("ID?"), FrameType.IDENT)
        # ACK echoes the command line; errors come as ERROR, sequence number 0.
        expect(talk.answer("RATE 20000"), FrameType.ACK, "RATE 20000")
        expect(talk.answer("SPF 128\r"), FrameType.ACK, "SPF 128")  # a '\r' is ignored
        for bad in ("SPF 0", "SPF 1.5", "SPF 1025", "DUR -1", "RATE x", "BOGUS", "X" * 33):
            expect(talk.answer(bad), FrameType.ERROR)
        assert decode_text(talk.answer("Y" * 40)) == "line too long"
        talk.send("")  # an empty line is ignored: the next answer is the IDENT
        expect(talk.answer("ID?"), FrameType.IDENT)
        expect(talk.answer("FIRE"), FrameType.ERROR)  # no run
        expect(talk.answer("STOP"), FrameType.ERROR)
        config = talk.answer("CFG?")
        expect(config, FrameType.HEADER)
        # The packed run header: <BBHddddd, 44 bytes, then the label.
        fields = struct.unpack_from("<BBHddddd", config.payload)
        assert fields[:4] == (1, 2, 128, 20_000.0)
        assert fields[4:] == (*SCALES, 2e-3, 0.5)
        assert RunHeader.from_payload(config.payload).samples_per_frame == 128
        expect(talk.answer("ARM"), FrameType.HEADER, seq=0)
        # During a run: no second ARM, no configuration; the run goes on.
        for busy in ("ARM", "CFG?", "RATE 1000"):
            expect(talk.answer(busy), FrameType.ERROR, "busy: a run is in progress")
        talk.wait_data(2)  # the run streams before the release
        release = talk.answer("FIRE")
        expect(release, FrameType.RELEASE, seq=None)
        expect(talk.answer("FIRE"), FrameType.ERROR, "released already")
        end = talk.answer("STOP")
        expect(end, FrameType.END, seq=None)
        frames, samples = decode_end(end.payload)
        # Sequence numbers: HEADER 0, then DATA and RELEASE 1, 2, … with none missing;
        # END carries the next one, which is also the count of frames before it.
        seqs = sorted([f.seq for f in talk.data] + [release.seq])
        assert seqs == list(range(1, end.seq)) and frames == end.seq
        firsts = [decode_data(f.payload) for f in talk.data]
        assert samples == sum(len(c) for _, c in firsts)
        lengths = [len(c) for _, c in firsts]
        assert [first for first, _ in firsts] == list(np.cumsum([0, *lengths])[:-1])
        assert 0 < decode_release(release.payload) <= samples


@needs_cc
def test_the_firmware_refuses_what_its_link_or_its_sample_index_cannot_carry(host_sim):
    # On a 921 600 bit/s UART, 20 kS/s needs 128 pairs a frame (827 kbit/s, within
    # 90 %); 64 pairs (853 kbit/s) are refused. (10 s + DUR) × RATE must fit the
    # 32-bit sample index.
    with firmware(host_sim, "--link-bps", "921600") as port:
        talk = Conversation(port)
        try:
            expect(talk.answer("RATE 20000"), FrameType.ACK, "RATE 20000")
            refused = talk.answer("SPF 64")
            expect(refused, FrameType.ERROR)
            assert "90 %" in decode_text(refused)
            expect(talk.answer("SPF 256"), FrameType.ACK, "SPF 256")
            expect(talk.answer("RATE 1e+06"), FrameType.ERROR, "RATE out of range")
            expect(talk.answer("RATE 100"), FrameType.ACK, "RATE 100")
            config = RunHeader.from_payload(talk.answer("CFG?").payload)
            assert (config.sample_rate_Hz, config.samples_per_frame) == (100.0, 256)
        finally:
            talk.close()
    with firmware(host_sim) as port:  # USB: no link limit
        talk = Conversation(port)
        try:
            expect(talk.answer("RATE 100000"), FrameType.ACK, "RATE 100000")
            refused = talk.answer("DUR 86400")  # 8.6e9 samples
            expect(refused, FrameType.ERROR, "DUR x RATE exceeds the 32-bit sample index")
            expect(talk.answer("DUR 40000"), FrameType.ACK, "DUR 40000")  # 4.0e9: fits
        finally:
            talk.close()


@needs_cc
def test_any_command_line_gets_one_answer_and_leaves_the_board_working(host_sim):
    # Lines of random printable characters, and commands with random arguments: every
    # non-empty line is answered by exactly one frame, and the board still identifies.
    rng = np.random.default_rng(7)
    alphabet = np.array(list("ABCDEFIMOPRSTUXY?0123456789 .-+e\t\r"))
    lines = []
    for _ in range(150):
        if rng.random() < 0.5:
            lines.append("".join(rng.choice(alphabet, rng.integers(0, 45))))
        else:
            word = rng.choice(["RATE", "SPF", "DUR", "ID?", "CFG?", "FIRE", "STOP"])
            value = rng.random() * 10.0 ** int(rng.integers(-3, 9))
            lines.append(f"{word} {rng.choice(['', '-'])}{value:g}")
    lines = [line for line in lines if line.strip(" \t\r") != "ARM"]  # no run
    with firmware(host_sim) as port:
        talk = Conversation(port)
        try:
            for line in lines:
                body = line[:-1] if line.endswith("\r") else line  # one '\r' is ignored
                command = body.strip(" \t")
                if len(body) <= 32 and not command:
                    talk.send(line)
                    continue
                answer = talk.answer(line)
                assert answer.seq == 0
                if len(body) > 32:
                    expect(answer, FrameType.ERROR, "line too long")
                elif command == "ID?":
                    expect(answer, FrameType.IDENT)
                elif command == "CFG?":
                    expect(answer, FrameType.HEADER)
                elif answer.type == FrameType.ACK:  # the line it answers, as executed
                    assert decode_text(answer) == command
                else:
                    expect(answer, FrameType.ERROR)
            expect(talk.answer("ID?"), FrameType.IDENT)
            assert not talk.data and not talk.answers
        finally:
            talk.close()
