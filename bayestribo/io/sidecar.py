"""The JSON sidecar of a run file: ``run.csv`` -> ``run.json`` (same stem).

The sidecar is one JSON object of metadata (see :data:`bayestribo.io.run.METADATA_KEYS`).
Numbers are written with Python's shortest round-trip representation, so reading
a written sidecar gives back exactly the same values.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bayestribo._files import write_text
from bayestribo.errors import RunFormatError
from bayestribo.io.run import METADATA_KEYS, check_metadata

__all__ = ["RUN_ID_PATTERN", "is_run_id", "read_sidecar", "sidecar_path", "write_sidecar"]

#: What a run id may hold: the characters the package writes in the run ids it makes
#: (acquisition, synthetic campaigns), at most 128 of them, starting with a letter or
#: digit. A run id names files, so no path separator and no ``..`` either.
RUN_ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,127}")


def is_run_id(value: object) -> bool:
    """True if ``value`` is a run id that is safe as a file name (:data:`RUN_ID_PATTERN`)."""
    return (
        isinstance(value, str) and RUN_ID_PATTERN.fullmatch(value) is not None and ".." not in value
    )


def sidecar_path(path: str | Path) -> Path:
    """The sidecar of a run file: same folder and stem, suffix ``.json``."""
    return Path(path).with_suffix(".json")


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"key {key!r} appears twice")
        out[key] = value
    return out


def read_sidecar(path: str | Path) -> dict:
    """Read and check a sidecar file.

    Parameters
    ----------
    path : str or Path
        The ``.json`` file itself.

    Returns
    -------
    dict
        Checked metadata (see :func:`bayestribo.io.run.check_metadata`).

    Raises
    ------
    RunFormatError
        If the file is not UTF-8 JSON holding one object, repeats a key, holds NaN
        or infinity, holds a key that is not a known key (a key of one's own goes
        under ``user``), has a value of the wrong type, or a ``run_id`` that is not a
        run id (:data:`RUN_ID_PATTERN`: it could name a path outside the folder).
    """
    path = Path(path)
    where = str(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RunFormatError(f"sidecar is not UTF-8 text ({exc.reason})", where) from None
    try:
        data = json.loads(text, parse_constant=_no_constant, object_pairs_hook=_no_duplicates)
    except ValueError as exc:  # json.JSONDecodeError is a ValueError
        raise RunFormatError(f"sidecar is not valid JSON: {exc}", where) from None
    except RecursionError:
        raise RunFormatError(
            "sidecar is nested too deeply to read; expected one object of metadata", where
        ) from None
    if not isinstance(data, dict):
        raise RunFormatError(
            f"sidecar must hold one JSON object of metadata; got {type(data).__name__}", where
        )
    try:
        metadata = check_metadata(data, where, strict=True)
    except RecursionError:
        raise RunFormatError(
            "sidecar is nested too deeply to read; expected plain metadata values", where
        ) from None
    run_id = metadata.get("run_id")
    if run_id is not None and not is_run_id(run_id):
        raise RunFormatError(
            f"metadata 'run_id': {run_id[:60]!r} is not a run id; expected 1 to 128 letters, "
            "digits, '.', '_', '+' or '-', starting with a letter or digit (no path "
            "separators, no '..')",
            where,
        )
    return metadata


def write_sidecar(metadata: Mapping[str, Any], path: str | Path) -> Path:
    """Write metadata as a sidecar (known keys first, in their documented order).

    A key that is not a known key (metadata a program built, which may hold any) is
    written under ``user``, where :func:`read_sidecar` reads it back: a sidecar refuses
    unknown keys at the top level.

    Parameters
    ----------
    metadata : mapping
        Checked metadata (a :class:`~bayestribo.io.run.Run`'s ``metadata``).
    path : str or Path
        The ``.json`` file to write.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    ordered = {k: metadata[k] for k in METADATA_KEYS if k in metadata}
    own = {k: v for k, v in metadata.items() if k not in METADATA_KEYS}
    if own:
        user = ordered.get("user") or {}
        if not isinstance(user, Mapping):
            raise ValueError(
                f"metadata 'user' must be a mapping to hold the keys {sorted(own)}, got "
                f"{type(user).__name__}"
            )
        clash = sorted(set(own) & set(user))
        if clash:
            raise ValueError(
                f"metadata: key(s) {clash} are both top-level and under 'user'; keep one"
            )
        ordered["user"] = {**user, **own}
    text = json.dumps(ordered, indent=2, ensure_ascii=False, allow_nan=False)
    write_text(path, text + "\n")
    return path
