"""A results catalog in SQLite: the runs of a campaign and the fits made of them.

One file, standard library only (:mod:`sqlite3`). Every write is one transaction;
the schema carries its version in ``PRAGMA user_version`` so later versions can
migrate it. Version 1 has two tables::

    runs(id, run_id, path, sha256, metadata JSON, registered_utc)
    fits(id, run, settings JSON, package_version, summary JSON, diagnostics JSON,
         created_utc)

A run is identified by its content: registering the same file (same SHA-256) twice
returns the existing id; registering a different file under an existing run id is an
error.

A fit record (:func:`record_fit`) belongs to a run row and stores the fit's settings
as canonical JSON (sorted keys), so :func:`find_fit` can tell whether a run was
fitted already with the same data (the run row, i.e. the same SHA-256) and the same
settings; a campaign then skips it. Fit records use the version-1 ``fits`` table as
it is: catalogs written before fit records existed read and write unchanged.
"""

from __future__ import annotations

import json
import os
import sqlite3
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from bayestribo.errors import BayestriboError

__all__ = [
    "SCHEMA_VERSION",
    "CatalogError",
    "FitRecord",
    "RunRecord",
    "connect",
    "find_fit",
    "find_run",
    "list_fits",
    "list_runs",
    "record_fit",
    "register_run",
    "settings_key",
    "transaction",
]

#: Schema version written to ``PRAGMA user_version``.
SCHEMA_VERSION = 1

_SCHEMA_V1 = (
    """CREATE TABLE runs (
        id INTEGER PRIMARY KEY,
        run_id TEXT NOT NULL UNIQUE,
        path TEXT NOT NULL,
        sha256 TEXT NOT NULL UNIQUE,
        metadata TEXT NOT NULL,
        registered_utc TEXT NOT NULL
    )""",
    """CREATE TABLE fits (
        id INTEGER PRIMARY KEY,
        run INTEGER NOT NULL REFERENCES runs(id),
        settings TEXT NOT NULL,
        package_version TEXT NOT NULL,
        summary TEXT NOT NULL,
        diagnostics TEXT NOT NULL,
        created_utc TEXT NOT NULL
    )""",
    "CREATE INDEX fits_run ON fits(run)",
)


class CatalogError(BayestriboError):
    """The catalog cannot be opened, has an unknown schema, or a record conflicts."""


@dataclass(frozen=True)
class RunRecord:
    """A registered run.

    Attributes
    ----------
    id : int
        Row id in the catalog (referenced by fits).
    run_id : str
        The run's id (file stem).
    path : str
        Path of the run's CSV file as registered.
    sha256 : str
        SHA-256 of the run's CSV file.
    metadata : dict
        The run's sidecar metadata.
    registered_utc : str
        When it was registered (ISO 8601, UTC).
    """

    id: int
    run_id: str
    path: str
    sha256: str
    metadata: dict[str, Any]
    registered_utc: str


@contextmanager
def connect(path: str | os.PathLike[str]) -> Iterator[sqlite3.Connection]:
    """Open (creating if needed) a catalog, check its schema version, close on exit.

    Raises
    ------
    CatalogError
        If the file is not an SQLite database or has a newer schema version.
    """
    path = Path(path)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    try:
        conn = sqlite3.connect(path, timeout=10.0, isolation_level=None)
    except sqlite3.Error as exc:
        raise CatalogError(f"{path}: cannot open the catalog ({exc})") from None
    try:
        try:
            conn.execute("PRAGMA foreign_keys = ON")
            with transaction(conn):
                version = conn.execute("PRAGMA user_version").fetchone()[0]
                if version == 0:
                    for statement in _SCHEMA_V1:
                        conn.execute(statement)
                    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                    version = SCHEMA_VERSION
        except sqlite3.DatabaseError as exc:
            raise CatalogError(f"{path}: not an SQLite catalog ({exc})") from None
        if version > SCHEMA_VERSION:
            raise CatalogError(
                f"{path}: catalog schema version {version} is newer than this bayestribo "
                f"({SCHEMA_VERSION}); upgrade bayestribo"
            )
        yield conn
    finally:
        conn.close()


@contextmanager
def transaction(conn: sqlite3.Connection) -> Iterator[sqlite3.Connection]:
    """One write transaction (``BEGIN IMMEDIATE``): committed on success, rolled back on error.

    Use on a connection from :func:`connect` (which runs in autocommit mode).
    """
    conn.execute("BEGIN IMMEDIATE")
    try:
        yield conn
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _record(row: tuple[Any, ...]) -> RunRecord:
    return RunRecord(row[0], row[1], row[2], row[3], json.loads(row[4]), row[5])


def register_run(
    catalog: str | os.PathLike[str],
    *,
    path: str | os.PathLike[str],
    sha256: str,
    metadata: Mapping[str, Any],
) -> int:
    """Register a run file in the catalog; return its row id.

    Parameters
    ----------
    catalog : path-like
        The catalog file (created if absent).
    path : path-like
        The run's CSV file.
    sha256 : str
        SHA-256 of the CSV file (64 hexadecimal digits).
    metadata : mapping
        Sidecar metadata; must contain ``run_id``.

    Returns
    -------
    int
        The row id; the existing one if this file (same SHA-256) is registered already.

    Raises
    ------
    CatalogError
        If ``sha256`` is malformed, ``run_id`` is missing, or another file is
        registered under the same run id.
    """
    if not (isinstance(sha256, str) and len(sha256) == 64):
        raise CatalogError(f"sha256: expected 64 hexadecimal digits, got {sha256!r}")
    try:
        int(sha256, 16)
    except ValueError:
        raise CatalogError(f"sha256: expected 64 hexadecimal digits, got {sha256!r}") from None
    run_id = metadata.get("run_id")
    if not isinstance(run_id, str) or not run_id:
        raise CatalogError("metadata: missing the 'run_id' key")
    try:
        text = json.dumps(dict(metadata), allow_nan=False, sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise CatalogError(f"metadata: not JSON-serialisable ({exc})") from None
    with connect(catalog) as conn, transaction(conn):
        row = conn.execute("SELECT id, sha256 FROM runs WHERE run_id = ?", (run_id,)).fetchone()
        if row is not None:
            if row[1] == sha256:
                return int(row[0])
            raise CatalogError(
                f"{catalog}: run id {run_id!r} is registered already with another file "
                f"(sha256 {row[1][:12]}..., this one {sha256[:12]}...)"
            )
        row = conn.execute("SELECT id, run_id FROM runs WHERE sha256 = ?", (sha256,)).fetchone()
        if row is not None:
            raise CatalogError(
                f"{catalog}: this file (sha256 {sha256[:12]}...) is registered already "
                f"as run {row[1]!r}"
            )
        cursor = conn.execute(
            "INSERT INTO runs (run_id, path, sha256, metadata, registered_utc) "
            "VALUES (?, ?, ?, ?, ?)",
            (run_id, str(Path(path).resolve()), sha256, text, _now()),
        )
        return int(cursor.lastrowid or 0)


def find_run(
    catalog: str | os.PathLike[str],
    *,
    run_id: str | None = None,
    sha256: str | None = None,
    id: int | None = None,
) -> RunRecord | None:
    """Find a run by run id, file SHA-256 or row id; None if it is not registered.

    Raises
    ------
    CatalogError
        If not exactly one of ``run_id``, ``sha256``, ``id`` is given.
    """
    given = {k: v for k, v in (("run_id", run_id), ("sha256", sha256), ("id", id)) if v is not None}
    if len(given) != 1:
        raise CatalogError(
            f"find_run: give exactly one of run_id, sha256 or id, got {sorted(given) or 'none'}"
        )
    ((column, value),) = given.items()
    with connect(catalog) as conn:
        row = conn.execute(
            "SELECT id, run_id, path, sha256, metadata, registered_utc FROM runs "
            f"WHERE {column} = ?",
            (value,),
        ).fetchone()
    return None if row is None else _record(row)


def list_runs(catalog: str | os.PathLike[str]) -> list[RunRecord]:
    """All registered runs, in registration order."""
    with connect(catalog) as conn:
        rows = conn.execute(
            "SELECT id, run_id, path, sha256, metadata, registered_utc FROM runs ORDER BY id"
        ).fetchall()
    return [_record(row) for row in rows]


@dataclass(frozen=True)
class FitRecord:
    """A fit of a registered run.

    Attributes
    ----------
    id : int
        Row id of the fit.
    run : int
        Row id of the run it fits.
    settings : dict
        The fit's settings (model, seed, sampler settings...).
    package_version : str
        bayestribo version that made the fit.
    summary : dict
        Posterior summaries (and, by convention, where the full result is stored).
    diagnostics : dict
        Sampler diagnostics.
    created_utc : str
        When it was recorded (ISO 8601, UTC).
    """

    id: int
    run: int
    settings: dict[str, Any]
    package_version: str
    summary: dict[str, Any]
    diagnostics: dict[str, Any]
    created_utc: str


def settings_key(settings: Mapping[str, Any]) -> str:
    """Canonical JSON of fit settings (sorted keys): equal settings give equal text.

    Raises
    ------
    CatalogError
        If the settings are not JSON data.
    """
    try:
        return json.dumps(dict(settings), sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise CatalogError(f"settings: not JSON-serialisable ({exc})") from None


def _json(value: Mapping[str, Any], field: str) -> str:
    # Diagnostics may hold inf (an autocorrelation time that could not be estimated):
    # Python's JSON writes and reads it back as Infinity.
    try:
        return json.dumps(dict(value), sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise CatalogError(f"{field}: not JSON-serialisable ({exc})") from None


def _run_row(conn: sqlite3.Connection, catalog: Any, run: int | str) -> int:
    column = "run_id" if isinstance(run, str) else "id"
    row = conn.execute(f"SELECT id FROM runs WHERE {column} = ?", (run,)).fetchone()
    if row is None:
        raise CatalogError(f"{catalog}: run {run!r} is not registered")
    return int(row[0])


def _fit(row: tuple[Any, ...]) -> FitRecord:
    return FitRecord(
        row[0], row[1], json.loads(row[2]), row[3], json.loads(row[4]), json.loads(row[5]), row[6]
    )


_FIT_COLUMNS = "id, run, settings, package_version, summary, diagnostics, created_utc"


def record_fit(
    catalog: str | os.PathLike[str],
    *,
    run: int | str,
    settings: Mapping[str, Any],
    summary: Mapping[str, Any],
    diagnostics: Mapping[str, Any],
    package_version: str | None = None,
) -> int:
    """Record a fit of a registered run (one transaction); return the fit's row id.

    Parameters
    ----------
    catalog : path-like
        The catalog file.
    run : int or str
        The run's row id or run id.
    settings, summary, diagnostics : mapping
        JSON data: fit settings, posterior summaries, sampler diagnostics.
    package_version : str, optional
        Default: this bayestribo's version.

    Raises
    ------
    CatalogError
        If the run is not registered or a mapping is not JSON data.
    """
    if package_version is None:
        from bayestribo import __version__ as package_version
    key = settings_key(settings)
    summary_text, diagnostics_text = _json(summary, "summary"), _json(diagnostics, "diagnostics")
    with connect(catalog) as conn, transaction(conn):
        run_row = _run_row(conn, catalog, run)
        cursor = conn.execute(
            "INSERT INTO fits (run, settings, package_version, summary, diagnostics, "
            "created_utc) VALUES (?, ?, ?, ?, ?, ?)",
            (run_row, key, package_version, summary_text, diagnostics_text, _now()),
        )
        return int(cursor.lastrowid or 0)


def find_fit(
    catalog: str | os.PathLike[str],
    *,
    run: int | str,
    settings: Mapping[str, Any],
    package_version: str | None = None,
) -> FitRecord | None:
    """The latest fit of ``run`` with exactly these settings (and version, if given).

    Returns None if there is none, or if the run is not registered.
    """
    key = settings_key(settings)
    with connect(catalog) as conn:
        try:
            run_row = _run_row(conn, catalog, run)
        except CatalogError:
            return None
        query = f"SELECT {_FIT_COLUMNS} FROM fits WHERE run = ? AND settings = ?"
        args: tuple[Any, ...] = (run_row, key)
        if package_version is not None:
            query += " AND package_version = ?"
            args += (package_version,)
        row = conn.execute(query + " ORDER BY id DESC LIMIT 1", args).fetchone()
    return None if row is None else _fit(row)


def list_fits(catalog: str | os.PathLike[str], *, run: int | str | None = None) -> list[FitRecord]:
    """All fit records (of one run if given), in the order they were recorded."""
    with connect(catalog) as conn:
        if run is None:
            rows = conn.execute(f"SELECT {_FIT_COLUMNS} FROM fits ORDER BY id").fetchall()
        else:
            run_row = _run_row(conn, catalog, run)
            rows = conn.execute(
                f"SELECT {_FIT_COLUMNS} FROM fits WHERE run = ? ORDER BY id", (run_row,)
            ).fetchall()
    return [_fit(row) for row in rows]
