"""Peak resident memory of every registered reader over damaged files under 10 MB.

Three sets of damaged files, each read in its own process (forked from one that has
imported the readers and read every seed file once) under an address-space limit of
:data:`ADDRESS_LIMIT` and a CPU-time limit of :data:`CPU_LIMIT_S`, its peak resident
memory taken from ``wait4``:

- hostile HDF5 files (``tests/_hostile_hdf5.py``): a chunk of ten values whose deflate
  stream inflates to 1 GB (deflated once, a 1 MB file; twice, 11 kB; twice in a MATLAB
  v7.3 file), a chunk shape of 1 GB, a scale-offset filter claiming 2^28 values, a
  variable-length string ``units`` attribute whose stored length is 2^31 bytes, a
  global heap object stating 2^64 - 1 bytes (libhdf5 loops on it);
- a sweep of an HDF5 file's metadata (superblock, object headers, B-trees, local and
  global heaps, layout, filter pipeline, dataspace, attribute and link messages, in an
  old-style and a new-style file with compact, contiguous and filtered datasets and
  string attributes): 4- and 8-byte huge values written every ``--stride`` bytes
  outside the raw data and the insides of runs of zeros (free space, padding);
- ``--mutants`` mutants of every registered reader's seed files from the fuzzing
  harness (``benchmarks/fuzz.py``: bytes flipped, cut, inserted, repeated, huge fields).

A forked process's peak counts the pages it touches and those of its parent it maps;
``conservative_peak_MB`` adds the whole parent (``baseline_MB``: the interpreter, numpy,
SciPy, h5py and the readers) to the largest peak, an upper bound of a reading process's.
The goal: no file makes any reader exceed 500 MB. The cost of the chunk check
(:mod:`bayestribo.io.hdf5_storage`) on ordinary compressed files is the CPU time of
reading them with and without it, side by side.

Run: ``python benchmarks/reader_memory.py``; writes
``benchmarks/results/reader_memory.json`` (``--output`` names another, e.g. a run of
the tree before the check with ``PYTHONPATH`` pointing at it).
"""

from __future__ import annotations

import argparse
import collections
import os
import random
import resource
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(1, str(HERE.parent / "tests"))
import fuzz  # noqa: E402
from _machine import commit, write_results  # noqa: E402

#: The goal: peak resident memory of a reading process [MB].
GOAL_MB = 500.0
#: Address-space limit of a reading process [bytes]: the damaged files before the check
#: asked for gigabytes; this keeps the shared machine safe.
ADDRESS_LIMIT = 6 * 1024**3
#: Most CPU time of a reading process [s]: libhdf5 loops on some damaged heaps, in C
#: code where the harness's alarm handler never runs.
CPU_LIMIT_S = 10
#: Huge values written into the metadata sweep's fields.
SWEEP_VALUES = (b"\xff\xff\xff\xff", b"\x00\x00\x00\x80", b"\xff" * 8)
#: Exit codes of a reading process, by outcome.
OUTCOMES = {0: "read", 1: "package error", 2: "other exception", 3: "memory error", 4: "timeout"}


def _hostile(folder: Path) -> list[dict[str, Any]]:
    """The hostile HDF5 files, as reading items."""
    import _hostile_hdf5 as hostile

    folder.mkdir(parents=True, exist_ok=True)
    made = [
        ("inflates once to 1 GB", "hdf5", hostile.inflating_chunk(folder / "once.h5", 1024)),
        (
            "inflates twice to 1 GB",
            "hdf5",
            hostile.inflating_chunk(folder / "twice.h5", 1024, passes=2),
        ),
        (
            "MATLAB v7.3, inflates twice to 1 GB",
            "mat",
            hostile.inflating_chunk(folder / "twice.mat", 1024, passes=2, v73=True),
        ),
        ("chunk shape of 1 GB", "hdf5", hostile.huge_chunk(folder / "chunk.h5", 1024)),
        (
            "scale-offset claiming 2^28 values",
            "hdf5",
            hostile.scaleoffset_count(folder / "scaled.h5", 1 << 28),
        ),
        (
            "string units claiming 2^31 bytes",
            "hdf5",
            hostile.vlen_unit_length(folder / "unit.h5", 2**31 - 1),
        ),
        (
            "global heap object of 2^64 - 1 bytes",
            "hdf5",
            hostile.heap_object_size(folder / "heap.h5"),
        ),
    ]
    return [
        {
            "path": str(path),
            "options": {"group": "run1"} if reader == "hdf5" else {},
            "cli": ["--group", "run1"] if reader == "hdf5" else [],
            "reader": reader,
            "seed": "hostile HDF5",
            "mutation": what,
        }
        for what, reader, path in made
    ]


def _sweep_seeds(folder: Path) -> list[Path]:
    """An old-style and a new-style HDF5 file: a contiguous, a compact and a chunked
    (deflate, shuffle, Fletcher-32) dataset, each with a string ``units`` attribute."""
    import h5py
    import numpy as np

    folder.mkdir(parents=True, exist_ok=True)
    t = np.arange(200) / 1000.0
    x = 1e-3 * np.exp(-t) * np.cos(50 * t)
    v = np.gradient(x, t)
    paths = []
    for libver in ("earliest", "latest"):
        path = folder / f"{libver}.h5"
        with h5py.File(path, "w", libver=libver) as handle:
            group = handle.create_group("run1")
            group.create_dataset("time", data=t).attrs["units"] = "s"
            group.create_dataset(
                "displacement",
                data=1e6 * x,
                chunks=(50,),
                compression="gzip",
                shuffle=True,
                fletcher32=True,
            ).attrs["units"] = "um"
            dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
            dcpl.set_layout(h5py.h5d.COMPACT)
            space = h5py.h5s.create_simple(v.shape)
            dsid = h5py.h5d.create(group.id, b"velocity", h5py.h5t.IEEE_F64LE, space, dcpl=dcpl)
            dsid.write(h5py.h5s.ALL, h5py.h5s.ALL, v)
            group["velocity"].attrs["units"] = np.bytes_(b"m/s")
        paths.append(path)
    return paths


def _raw_ranges(path: Path) -> list[tuple[int, int]]:
    """Where ``path`` keeps its datasets' values (byte ranges), not its metadata."""
    import h5py

    ranges = []
    with h5py.File(path, "r") as handle:
        for name in ("time", "displacement"):
            dsid = handle["run1"][name].id
            if handle["run1"][name].chunks is None:
                ranges.append((dsid.get_offset(), dsid.get_offset() + dsid.get_storage_size()))
            else:
                for k in range(dsid.get_num_chunks()):
                    info = dsid.get_chunk_info(k)
                    ranges.append((info.byte_offset, info.byte_offset + info.size))
    return ranges


def _zero_runs(data: bytes, length: int = 32) -> list[tuple[int, int]]:
    """The insides of runs of ``length`` or more zero bytes (a heap's free space, padding),
    their first 16 bytes left out of the range."""
    import re

    return [(m.start() + 16, m.end()) for m in re.finditer(b"\0{%d,}" % length, data)]


def _sweep(folder: Path, stride: int) -> list[dict[str, Any]]:
    """The metadata sweep's files, as reading items."""
    items = []
    for seed in _sweep_seeds(folder / "seeds"):
        data = seed.read_bytes()
        skip = _raw_ranges(seed) + _zero_runs(data)
        for at in range(0, len(data), stride):
            if any(a <= at < b for a, b in skip):
                continue
            for k, value in enumerate(SWEEP_VALUES):
                mutant = bytearray(data)
                mutant[at : at + len(value)] = value
                path = folder / "sweep" / f"{seed.stem}-{at:05d}-{k}.h5"
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_bytes(bytes(mutant[: len(data)]))
                items.append(
                    {
                        "path": str(path),
                        "options": {"group": "run1"},
                        "cli": ["--group", "run1"],
                        "reader": "hdf5",
                        "seed": f"HDF5 metadata sweep ({seed.stem})",
                        "mutation": f"byte {at} = {value.hex()}",
                    }
                )
    return items


def _mutants(folder: Path, seeds: list[dict[str, Any]], count: int, rng: random.Random):
    """``count`` mutants of every seed file of the fuzzing harness, as reading items."""
    items = []
    for seed in seeds:
        path = Path(seed["path"])
        for _ in range(count):
            target = folder / "mutants" / seed["reader"] / f"{len(items):05d}"
            target.mkdir(parents=True)
            file = target / path.name
            side = path.with_suffix(".json")
            if seed["reader"] == "sidecar":
                mutant, how = fuzz.mutate(side.read_bytes(), "sidecar", rng)
                file.write_bytes(path.read_bytes())
                file.with_suffix(".json").write_bytes(mutant)
            else:
                mutant, how = fuzz.mutate(path.read_bytes(), seed["reader"], rng)
                file.write_bytes(mutant)
                file.with_suffix(".json").write_bytes(side.read_bytes())
            items.append({**seed, "path": str(file), "seed": seed["name"], "mutation": how})
    return items


def _resident_MB() -> float:
    """This process's resident memory now [MB] (what a forked reader starts from)."""
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) / 1024 for line in fh if line.startswith("VmRSS:"))


def _read_in_child(item: dict[str, Any]) -> dict[str, Any]:
    """Read ``item`` in a forked process: its outcome and peak resident memory [MB]."""
    pid = os.fork()
    if pid == 0:  # the reading process
        code = 2
        try:
            resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_LIMIT, ADDRESS_LIMIT))
            resource.setrlimit(resource.RLIMIT_CPU, (CPU_LIMIT_S, CPU_LIMIT_S + 5))
            outcome = fuzz._task(item)["outcome"]
            code = {v: k for k, v in OUTCOMES.items()}[outcome]
        finally:
            os._exit(code)
    _, status, usage = os.wait4(pid, 0)
    if os.WIFSIGNALED(status) and os.WTERMSIG(status) in (signal.SIGXCPU, signal.SIGKILL):
        outcome = f"timeout ({CPU_LIMIT_S} s of CPU)"
    elif os.WIFSIGNALED(status):
        outcome = f"crash ({signal.Signals(os.WTERMSIG(status)).name})"
    else:
        outcome = OUTCOMES.get(os.WEXITSTATUS(status), f"exit {os.WEXITSTATUS(status)}")
    return {
        "reader": item["reader"],
        "seed": item["seed"],
        "mutation": item["mutation"],
        "bytes": Path(item["path"]).stat().st_size,
        "outcome": outcome,
        "peak_MB": usage.ru_maxrss / 1024,
    }


def _ordinary_files(folder: Path, samples: int) -> list[tuple[str, Path, dict[str, Any]]]:
    """Ordinary compressed records: h5py's gzip with shuffle (its own chunks), and a
    MATLAB v7.3 file (deflate, chunks of MATLAB's shape)."""
    import h5py
    import numpy as np

    rng = np.random.default_rng(11)
    t = np.arange(samples) / 1e5
    x = 1e-3 * np.exp(-t) * np.cos(2 * np.pi * 20 * t) + 1e-7 * rng.normal(size=samples)
    v = np.gradient(x, t)
    h5 = folder / "ordinary.h5"
    with h5py.File(h5, "w") as handle:
        for name, values, unit in (
            ("time", t, "s"),
            ("displacement", x, "m"),
            ("velocity", v, "m/s"),
        ):
            handle.create_dataset(
                name, data=values, compression="gzip", shuffle=True, chunks=True
            ).attrs["units"] = unit
    mat = folder / "ordinary.mat"
    import _hostile_hdf5 as hostile

    with h5py.File(mat, "w", userblock_size=512) as handle:
        for name, values in (("time_s", t), ("displacement_m", x), ("velocity_m_per_s", v)):
            handle.create_dataset(
                name,
                data=values[None, :],
                compression="gzip",
                compression_opts=3,
                chunks=(1, min(samples, 1 << 15)),
            )
    with open(mat, "r+b") as fh:
        fh.write(hostile.V73_HEADER)
    return [("HDF5, gzip + shuffle", h5, {}), ("MATLAB v7.3, deflate", mat, {})]


def _unchecked(dataset: Any, *args: Any) -> Any:
    """A dataset read by libhdf5 whole, as before the chunk check."""
    return dataset[()]


def _cost(folder: Path, samples: int, repeats: int) -> list[dict[str, Any]]:
    """CPU time of reading ordinary compressed files with and without the chunk check,
    alternating."""
    import importlib.util

    if importlib.util.find_spec("bayestribo.io.hdf5_storage") is None:
        return []
    import bayestribo.io.hdf5 as reader
    from bayestribo import read_run

    check = reader.read_dataset
    out = []
    for what, path, options in _ordinary_files(folder, samples):
        times: dict[str, list[float]] = {"with the check": [], "without": []}
        for _ in range(repeats):
            for label, fn in (("with the check", check), ("without", _unchecked)):
                reader.read_dataset = fn
                start = time.process_time()
                read_run(path, validate=False, **options)
                times[label].append(time.process_time() - start)
        reader.read_dataset = check
        medians = {k: statistics.median(v) for k, v in times.items()}
        out.append(
            {
                "file": what,
                "samples": samples,
                "bytes": path.stat().st_size,
                "cpu_seconds_median": medians,
                "cpu_seconds": times,
                "extra_fraction": medians["with the check"] / medians["without"] - 1,
            }
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mutants", type=int, default=40, help="per seed file")
    parser.add_argument("--stride", type=int, default=4, help="bytes between swept fields")
    parser.add_argument("--seed", type=int, default=2041)
    parser.add_argument("--samples", type=int, default=2_000_000, help="of the ordinary files")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--output", default="reader_memory")
    args = parser.parse_args()
    import logging

    import bayestribo

    logging.disable(logging.WARNING)  # npTDMS's notes on damaged files
    start = time.perf_counter()
    tree = Path(bayestribo.__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="bt-reader-memory-") as tmp:
        folder = Path(tmp)
        seeds = fuzz.write_seeds(folder / "seeds")
        for seed in seeds:  # every reader and library imported before the forks
            fuzz._task({**seed, "seed": seed["name"], "mutation": "none"})
        baseline = _resident_MB()
        items = _hostile(folder / "hostile") + _sweep(folder, args.stride)
        items += _mutants(folder, seeds, args.mutants, random.Random(args.seed))
        results = [_read_in_child(item) for item in items]
        cost = _cost(folder, args.samples, args.repeats)
    wall = time.perf_counter() - start
    per_reader: dict[str, dict[str, Any]] = {}
    for reader in sorted({r["reader"] for r in results}):
        mine = [r for r in results if r["reader"] == reader]
        per_reader[reader] = {
            "files": len(mine),
            "peak_MB": max(r["peak_MB"] for r in mine),
            "outcomes": dict(collections.Counter(r["outcome"] for r in mine)),
            "over_goal": sum(r["peak_MB"] + baseline >= GOAL_MB for r in mine),
            "largest": sorted(mine, key=lambda r: -r["peak_MB"])[:3],
        }
    peak = max(r["peak_MB"] for r in results)
    print(f"baseline (the forking process) {baseline:.0f} MB")
    print(f"{'reader':8s} {'files':>6s} {'peak MB':>8s}  outcomes")
    for reader, row in per_reader.items():
        print(
            f"{reader:8s} {row['files']:6d} {row['peak_MB']:8.0f}  {row['over_goal']} over the "
            f"goal; {row['outcomes']}"
        )
    for r in results:
        if r["seed"] == "hostile HDF5":
            print(
                f"  {r['mutation']:38s} {r['bytes']:9d} B  {r['peak_MB']:6.0f} MB  {r['outcome']}"
            )
    for r in results:
        if r["outcome"] not in ("read", "package error"):
            print(f"  {r['seed']} ({r['mutation']}): {r['outcome']}")
    for row in cost:
        med = row["cpu_seconds_median"]
        print(
            f"  {row['file']}: {med['with the check']:.3f} s with the check, "
            f"{med['without']:.3f} s without ({100 * row['extra_fraction']:+.0f} %)"
        )
    print(
        f"largest peak {peak:.0f} MB (goal < {GOAL_MB:.0f}); baseline {baseline:.0f} MB; "
        f"{wall:.0f} s"
    )
    write_results(
        args.output,
        {
            "benchmark": "reader_memory",
            "description": __doc__,
            "commit": commit(tree),
            "package": str(tree),
            "settings": vars(args),
            "wall_seconds": wall,
            "baseline_MB": baseline,
            "goal": f"no damaged file under 10 MB makes a reader exceed {GOAL_MB:.0f} MB resident",
            "largest_file_bytes": max(r["bytes"] for r in results),
            "peak_MB": peak,
            "conservative_peak_MB": peak + baseline,
            "goal_met": peak + baseline < GOAL_MB,
            "per_reader": per_reader,
            "hostile_hdf5": [r for r in results if r["seed"] == "hostile HDF5"],
            "escapes": [r for r in results if r["outcome"] not in ("read", "package error")],
            "cost_on_ordinary_files": cost,
        },
    )


if __name__ == "__main__":
    main()
