"""A campaign on a disk that fills up: what is kept, what is said, and the resume.

Two faults on a real, small filesystem (a tmpfs mounted for the run, so this needs root;
it says so and stops otherwise):

1. **Full during the fits.** ``bayestribo campaign data/`` writes its fits to a tmpfs
   of ``--small`` MB, too small for all 54 fits. Measured: the exit status and the
   message; the fit files left (every one must read back), temporary or partial files
   left (there must be none); the catalog (every fit it records must exist and read
   back). Then the filesystem is enlarged and the same command run again: it must
   reuse every fit finished before (``n_cached``) and complete.
2. **Full while writing the tables.** On the completed campaign, the free space is
   filled but for a few kB and the command run again (every fit reused, the tables
   rewritten): the tables written before must be left whole (no empty or cut
   ``population.json``), and the message must say what happened.

Run: ``sudo python benchmarks/disk_full.py``; prints a table and writes
``benchmarks/results/disk_full.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import write_results

TREE = Path(__file__).resolve().parent.parent
DATA = TREE / "data"


def mount(point: Path, size_mb: float) -> None:
    subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={int(size_mb * 1024)}k", "tmpfs", str(point)],
        check=True,
    )


def remount(point: Path, size_mb: float) -> None:
    subprocess.run(["mount", "-o", f"remount,size={int(size_mb * 1024)}k", str(point)], check=True)


def campaign(out: Path, *extra: str) -> dict:
    command = [sys.executable, "-m", "bayestribo", "campaign", str(DATA), "--out", str(out)]
    command += ["--workers", "2", "--quiet", "--json", "--no-figures", *extra]
    proc = subprocess.run(
        command,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "PYTHONPATH": str(TREE)},
    )
    report = None
    try:
        report = json.loads(proc.stdout) if proc.stdout.strip() else None
    except json.JSONDecodeError:
        pass
    return {
        "exit_status": proc.returncode,
        "stderr_last_lines": proc.stderr.strip().splitlines()[-3:],
        "traceback": "Traceback" in proc.stderr,
        "n_cached": None if report is None else report.get("n_cached"),
        "failures": None if report is None else len(report.get("failures", [])),
    }


def state(out: Path) -> dict:
    """What is on the disk: fits that read back, files that are not whole, the catalog."""
    from bayestribo.campaign.catalog import list_fits
    from bayestribo.inference.result import FitResult

    fits = sorted((out / "fits").glob("*.nc")) if (out / "fits").is_dir() else []
    unreadable = []
    for f in fits:
        try:
            FitResult.load(f)
        except Exception as exc:  # a fit file that is not whole
            unreadable.append(f"{f.name}: {type(exc).__name__}")
    leftovers = [
        str(p.relative_to(out))
        for p in out.rglob("*")
        if p.is_file()
        and (p.name.startswith(".") or p.suffix == ".tmp")
        and p.name != ".bayestribo-campaign.lock"
    ]
    catalog = out / "catalog.sqlite"
    recorded, missing = 0, []
    if catalog.is_file():
        for record in list_fits(catalog):
            recorded += 1
            path = record.summary.get("result_path")
            if not path or not Path(path).is_file():
                missing.append(path)
    tables = {}
    for name in ("population.json", "groups.csv", "runs.csv", "trends.csv"):
        p = out / name
        tables[name] = None if not p.exists() else p.stat().st_size
    population_valid = None
    if (out / "population.json").exists():
        try:
            json.loads((out / "population.json").read_text())
            population_valid = True
        except (json.JSONDecodeError, UnicodeDecodeError):
            population_valid = False
    return {
        "fit_files": len(fits),
        "unreadable_fit_files": unreadable,
        "partial_or_temporary_files": leftovers,
        "catalog_fits": recorded,
        "catalog_fits_without_file": missing,
        "table_sizes": tables,
        "population_json_valid": population_valid,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--small", type=float, default=12.0, help="first size [MB]")
    parser.add_argument("--large", type=float, default=300.0, help="size after the fault [MB]")
    parser.add_argument("--output", default="disk_full")
    args = parser.parse_args()
    if os.geteuid() != 0:
        sys.exit("disk_full.py mounts a small tmpfs: run it as root (sudo)")
    rows = {}
    with tempfile.TemporaryDirectory(prefix="bt-disk-") as tmp:
        point = Path(tmp) / "small"
        point.mkdir()
        mount(point, args.small)
        try:
            out = point / "out"
            first = campaign(out)
            rows["1. full during the fits"] = {"command": first, "disk": state(out)}
            remount(point, args.large)
            again = campaign(out)
            rows["1. resumed on a larger disk"] = {"command": again, "disk": state(out)}
            # 2: fill the disk but for 8 kB, then rewrite the tables
            free = os.statvfs(point)
            room = free.f_bavail * free.f_frsize - 8 * 1024
            filler = point / "filler"
            with filler.open("wb") as fh:
                block = b"\0" * (1 << 20)
                while room > 0:
                    n = min(room, len(block))
                    try:
                        fh.write(block[:n])
                        fh.flush()
                    except OSError:
                        break
                    room -= n
            before = (
                (out / "population.json").read_bytes()
                if (out / "population.json").exists()
                else None
            )
            tables = campaign(out)
            after = (
                (out / "population.json").read_bytes()
                if (out / "population.json").exists()
                else None
            )
            rows["2. full while writing the tables"] = {
                "command": tables,
                "disk": state(out),
                "population_json_unchanged": before == after,
            }
        finally:
            subprocess.run(["umount", str(point)], check=False)
    for name, row in rows.items():
        c, d = row["command"], row["disk"]
        print(
            f"{name:36s} exit {c['exit_status']}  traceback {c['traceback']!s:5s}  "
            f"fits {d['fit_files']:2d} (unreadable {len(d['unreadable_fit_files'])})  "
            f"partial files {len(d['partial_or_temporary_files'])}  catalog {d['catalog_fits']} "
            f"(no file {len(d['catalog_fits_without_file'])})  cached {c['n_cached']}"
        )
        for line in c["stderr_last_lines"]:
            print(f"    {line[:150]}")
    write_results(
        args.output,
        {"benchmark": "disk_full", "description": __doc__, "settings": vars(args), "rows": rows},
    )


if __name__ == "__main__":
    main()
