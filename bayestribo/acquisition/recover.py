"""Rebuild a run from the raw log left by a crashed or killed acquisition.

The raw log holds every byte the device sent, and the session file written before
the run (``<stem>.session.json``) holds the operator's inputs. The run is parsed by
the same parser and assembler as the live acquisition, so it is what the logger
would have written from the bytes it had received. The log is read a megabyte at a
time and the CSV written a chunk at a time, so a log of any size is recovered in
bounded memory; the half-written CSV a crashed logger left in its staging directory
(``.<run_id>.staging-XXXXXXXX``) is removed.
"""

from __future__ import annotations

import glob
import inspect
import json
import os
import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bayestribo.acquisition.assembly import assemble_file
from bayestribo.acquisition.csvstream import is_staging_of
from bayestribo.acquisition.logger import OperatorInputs, check_run_id
from bayestribo.acquisition.session import AcquisitionResult, finish_run
from bayestribo.errors import AcquisitionError

__all__ = ["read_session", "recover_run"]


def read_session(raw_log: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The session file next to a raw log, or None if there is none.

    Raises
    ------
    AcquisitionError
        If the session file exists but is not valid JSON.
    """
    raw = Path(raw_log)
    path = raw.with_name(raw.stem + ".session.json")
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as exc:
        reason = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise AcquisitionError(f"{path}: session file does not parse ({reason})") from None
    if not isinstance(data, dict) or not isinstance(data.get("operator_inputs", {}), dict):
        raise AcquisitionError(f"{path}: expected one JSON object with a mapping 'operator_inputs'")
    return data


def _remove_staging(folder: Path, run_id: str) -> None:
    """Remove the staging directories a crashed logger left for ``run_id`` (half a CSV)."""
    for path in folder.glob(f".{glob.escape(run_id)}.*"):
        if is_staging_of(path, run_id) and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)


def recover_run(
    raw_log: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str] | None = None,
    inputs: Mapping[str, Any] | None = None,
    catalog: str | os.PathLike[str] | None = None,
    overwrite: bool = False,
) -> AcquisitionResult:
    """Rebuild the run of a raw log and write it in the canonical format.

    Parameters
    ----------
    raw_log : path-like
        The raw log (``<run_id>.raw``).
    out_dir : path-like, optional
        Where to write the run; the raw log's directory by default.
    inputs : mapping, optional
        Operator inputs; those of the session file by default (required if there is
        no session file). Keys given here override the session file's.
    catalog : path-like, optional
        Results catalog in which to register the recovered run.
    overwrite : bool
        Replace existing run files of the same run id.

    Returns
    -------
    AcquisitionResult

    Raises
    ------
    AcquisitionError
        If the raw log is missing, the operator inputs are unknown, or the run files
        exist and ``overwrite`` is false.
    FrameError, HeaderError
        If the raw log holds no valid run header.
    """
    raw = Path(raw_log)
    if not raw.is_file():
        raise AcquisitionError(f"{raw}: raw log not found")
    session = read_session(raw) or {}
    merged: dict[str, Any] = dict(session.get("operator_inputs") or {})
    merged.update({k: v for k, v in (inputs or {}).items() if v is not None})
    if "load_N" not in merged or "lubricant" not in merged or "repeat" not in merged:
        raise AcquisitionError(
            f"{raw}: no session file with the operator's inputs; give load, lubricant and repeat"
        )
    known = set(inspect.signature(OperatorInputs).parameters)
    unknown = sorted(set(merged) - known)
    if unknown:
        raise AcquisitionError(
            f"{raw}: unknown operator inputs {unknown} in the session file; expected some "
            f"of {sorted(known)}"
        )
    operator = OperatorInputs(**merged)
    out = Path(out_dir) if out_dir is not None else raw.parent
    run_id = check_run_id(session.get("run_id") or raw.stem, f"{raw}: run_id")
    if (out / f"{run_id}.csv").exists() and not overwrite:
        raise AcquisitionError(
            f"{out / (run_id + '.csv')}: run files exist already (recover into another "
            "directory, or overwrite)"
        )
    _remove_staging(raw.parent, run_id)
    if out != raw.parent:
        _remove_staging(out, run_id)
    # A megabyte at a time: memory does not grow with the raw log.
    run, _ = assemble_file(raw)
    return finish_run(
        run,
        operator,
        out_dir=out,
        run_id=run_id,
        raw_log=raw,
        port=session.get("port"),
        started_utc=session.get("host_time_start_utc"),
        catalog=catalog,
        fault=run.report["fault"],  # type: ignore[arg-type]
        recovered=True,
    )
