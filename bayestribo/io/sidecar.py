"""The JSON sidecar of a run file: ``run.csv`` -> ``run.json`` (same stem).

The sidecar is one JSON object of metadata (see :data:`bayestribo.io.run.METADATA_KEYS`).
Numbers are written with Python's shortest round-trip representation, so reading
a written sidecar gives back exactly the same values.

A sidecar the package writes beside a data file records that file as written, under
``data_file``: its sample count and SHA-256 (:func:`data_record`). Reading the file
checks it (:func:`check_data_file`): a file cut short on a row boundary, or with one
value changed, is refused naming what differs, never analysed as if whole. A sidecar
without ``data_file`` (older, or written by hand) is read as before.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bayestribo._files import write_text
from bayestribo._warnings import warn
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.run import METADATA_KEYS, check_metadata
from bayestribo.io.sidecar_units import si_quantities

__all__ = [
    "DATA_FILE",
    "RUN_ID_PATTERN",
    "DataFileMismatchError",
    "check_data_file",
    "data_record",
    "file_sha256",
    "is_run_id",
    "read_sidecar",
    "sidecar_path",
    "write_sidecar",
]

#: The sidecar key recording the data file as written: ``{"samples": n, "sha256": hex}``.
DATA_FILE = "data_file"


class DataFileMismatchError(RunFormatError):
    """A data file is not the file its sidecar records (cut short, or changed).

    Attributes
    ----------
    expected : dict
        The sidecar's ``data_file`` record.
    found : dict
        What the file holds: ``samples`` (None when it cannot be read) and ``sha256``.
    """

    def __init__(
        self, message: str, where: str | None, expected: Mapping[str, Any], found: Mapping[str, Any]
    ) -> None:
        super().__init__(message, where)
        self.expected = dict(expected)
        self.found = dict(found)


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes, hexadecimal."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def data_record(path: str | os.PathLike[str], samples: int) -> dict[str, Any]:
    """The ``data_file`` record of a data file as written: its sample count and SHA-256.

    Parameters
    ----------
    path : path-like
        The data file, as written.
    samples : int
        Its number of samples (rows).

    Returns
    -------
    dict
        ``{"samples": samples, "sha256": <hex>}``.
    """
    return {"samples": int(samples), "sha256": file_sha256(path)}


def check_data_file(
    path: str | os.PathLike[str],
    record: Mapping[str, Any],
    samples: int | None,
    *,
    sidecar: str | os.PathLike[str] | None = None,
    sha256: str | None = None,
) -> None:
    """Refuse a data file that is not the one its sidecar's ``data_file`` records.

    The file is accepted when its SHA-256 is the recorded one (it is the file written,
    whatever options read it), or, for a record without a SHA-256, when it holds the
    recorded number of samples.

    Parameters
    ----------
    path : path-like
        The data file.
    record : mapping
        The sidecar's ``data_file``: ``samples`` and/or ``sha256``.
    samples : int or None
        The samples read from the file (None: it could not be read).
    sidecar : path-like, optional
        The sidecar, for the message.
    sha256 : str, optional
        The file's SHA-256 if known (computed otherwise).

    Raises
    ------
    DataFileMismatchError
        Naming the sample count recorded and found, and the checksums when they differ.
    """
    path = Path(path)
    side = Path(sidecar).name if sidecar is not None else sidecar_path(path).name
    expected_sha = record.get("sha256")
    expected_n = record.get("samples")
    found: dict[str, Any] = {"samples": samples}
    if expected_sha is not None:
        found["sha256"] = sha256 or file_sha256(path)
        if found["sha256"] == expected_sha:
            return
    elif expected_n is None or samples == expected_n:
        return
    said = []
    if expected_n is not None and samples != expected_n:
        holds = "cannot be read" if samples is None else f"holds {samples} samples"
        said.append(
            f"{path.name} {holds} but its sidecar {side} records {expected_n} (data_file.samples)"
        )
    if expected_sha is not None:
        same = (
            f" with the same {samples} samples: a value changed"
            if samples is not None and samples == expected_n
            else ""
        )
        said.append(
            f"its SHA-256 is {found['sha256'][:16]}..., the sidecar records "
            f"{expected_sha[:16]}... (data_file.sha256){same}"
        )
    raise DataFileMismatchError(
        "; ".join(said)
        + ": the file is not the one written with its sidecar (cut short, or changed "
        "since); restore the file, or, if the change is meant, remove 'data_file' from "
        f"{side}",
        str(path),
        record,
        found,
    )


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
        Checked metadata (see :func:`bayestribo.io.run.check_metadata`). A load or a
        mass in another unit, named in the key or the value (``load_kgf``, ``mass_g``,
        ``"load_N": "30 gf"``), is converted to ``load_N`` and ``mass_kg``
        (:func:`bayestribo.io.sidecar_units.si_quantities`), each with a
        :class:`~bayestribo.errors.ReadingWarning` that says so.

    Raises
    ------
    RunFormatError
        If the file is not UTF-8 JSON holding one object, repeats a key (or gives the
        load or the mass twice, in two units), holds NaN or infinity, holds a key that
        is not a known key (a key of one's own goes under ``user``), has a value of the
        wrong type, or a ``run_id`` that is not a run id (:data:`RUN_ID_PATTERN`: it
        could name a path outside the folder).
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
        data, notes = si_quantities(data)
    except ValueError as exc:
        raise RunFormatError(str(exc), where) from None
    for note in notes:
        warn(f"{where}: {note}", ReadingWarning)
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


def write_sidecar(
    metadata: Mapping[str, Any], path: str | Path, *, data: Mapping[str, Any] | None = None
) -> Path:
    """Write metadata as a sidecar (known keys first, in their documented order), whole
    or not at all.

    A key that is not a known key (metadata a program built, which may hold any) is
    written under ``user``, where :func:`read_sidecar` reads it back: a sidecar refuses
    unknown keys at the top level.

    Parameters
    ----------
    metadata : mapping
        Checked metadata (a :class:`~bayestribo.io.run.Run`'s ``metadata``). A
        ``data_file`` in it is not written (it described another file).
    path : str or Path
        The ``.json`` file to write.
    data : mapping, optional
        The data file's record (:func:`data_record`), written as ``data_file``.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    metadata = {k: v for k, v in metadata.items() if k != DATA_FILE}
    if data is not None:
        metadata[DATA_FILE] = check_metadata({DATA_FILE: data}, str(path))[DATA_FILE]
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
