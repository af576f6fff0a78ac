"""Description of the machine a benchmark ran on, stored with its results."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import scipy

RESULTS = Path(__file__).resolve().parent / "results"
#: The repository the benchmarks belong to.
ROOT = RESULTS.parent.parent


def machine() -> dict[str, Any]:
    """Platform, processor, core count and library versions."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "platform": platform.platform(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def niced_worker() -> None:
    """Process-pool initialiser: lower the worker's priority on a shared machine."""
    try:
        os.nice(10)
    except OSError:
        pass


def write_results(name: str, results: dict[str, Any]) -> Path:
    """Write ``results`` with the machine description to ``results/<name>.json``."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"machine": machine(), **results}, indent=2) + "\n")
    return path


def commit(tree: Path = ROOT, *, short: bool = False, unknown: str = "") -> str:
    """The commit checked out in ``tree`` (default this repository), with "+changes"
    when tracked files are modified; ``unknown`` when git cannot say."""

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", "-C", str(tree), *args], capture_output=True, text=True, check=True
        ).stdout.strip()

    try:
        head = git("rev-parse", *(["--short"] if short else []), "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.CalledProcessError):
        return unknown
    return head + ("+changes" if dirty else "")


def provenance(
    module: str, settings: dict[str, Any], load_start: tuple[float, float, float]
) -> dict[str, Any]:
    """What a result file records of its run: the commit, the package module timed,
    the settings and the load averages at its start and now."""
    return {
        "commit": commit(),
        "module": module,
        "settings": settings,
        "load_average_start": load_start,
        "load_average_end": os.getloadavg(),
    }
