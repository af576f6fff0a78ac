"""Results catalog: schema version, transactional registration, look-ups."""

from __future__ import annotations

import sqlite3
import threading

import pytest

from bayestribo.campaign.catalog import (
    SCHEMA_VERSION,
    CatalogError,
    connect,
    find_run,
    list_runs,
    register_run,
    transaction,
)
from bayestribo.errors import BayestriboError

SHA_A = "a" * 64
SHA_B = "0123456789abcdef" * 4


def test_new_catalog_has_versioned_schema_with_runs_and_fits(tmp_path):
    db = tmp_path / "sub" / "catalog.sqlite"
    with connect(db):
        pass
    conn = sqlite3.connect(db)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION == 1
    tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    assert {"runs", "fits"} <= tables
    fits = [r[1] for r in conn.execute("PRAGMA table_info(fits)")]
    assert fits == [
        "id",
        "run",
        "settings",
        "package_version",
        "summary",
        "diagnostics",
        "created_utc",
    ]
    runs = [r[1] for r in conn.execute("PRAGMA table_info(runs)")]
    assert runs == ["id", "run_id", "path", "sha256", "metadata", "registered_utc"]


def test_register_and_find(tmp_path):
    db = tmp_path / "c.sqlite"
    meta = {"run_id": "r1", "load_N": 0.31, "gaps": [{"start_sample": 3}]}
    first = register_run(db, path=tmp_path / "r1.csv", sha256=SHA_A, metadata=meta)
    second = register_run(db, path=tmp_path / "r2.csv", sha256=SHA_B, metadata={"run_id": "r2"})
    assert (first, second) == (1, 2)
    record = find_run(db, run_id="r1")
    assert record is not None
    assert record.metadata == meta and record.sha256 == SHA_A and record.id == 1
    assert record.path == str((tmp_path / "r1.csv").resolve())
    assert find_run(db, sha256=SHA_B).run_id == "r2"
    assert find_run(db, id=2).run_id == "r2"
    assert find_run(db, run_id="nope") is None
    assert [r.run_id for r in list_runs(db)] == ["r1", "r2"]


def test_registering_the_same_file_twice_is_idempotent(tmp_path):
    db = tmp_path / "c.sqlite"
    a = register_run(db, path="x.csv", sha256=SHA_A, metadata={"run_id": "r1"})
    b = register_run(db, path="x.csv", sha256=SHA_A, metadata={"run_id": "r1"})
    assert a == b and len(list_runs(db)) == 1


def test_conflicts_are_errors_and_leave_the_catalog_unchanged(tmp_path):
    db = tmp_path / "c.sqlite"
    register_run(db, path="x.csv", sha256=SHA_A, metadata={"run_id": "r1"})
    with pytest.raises(CatalogError, match="registered already with another file"):
        register_run(db, path="y.csv", sha256=SHA_B, metadata={"run_id": "r1"})
    with pytest.raises(CatalogError, match="registered already as run 'r1'"):
        register_run(db, path="x.csv", sha256=SHA_A, metadata={"run_id": "r9"})
    assert len(list_runs(db)) == 1


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"sha256": "abc", "metadata": {"run_id": "r"}}, "sha256: expected 64"),
        ({"sha256": "z" * 64, "metadata": {"run_id": "r"}}, "sha256: expected 64"),
        ({"sha256": SHA_A, "metadata": {}}, "missing the 'run_id'"),
        ({"sha256": SHA_A, "metadata": {"run_id": "r", "x": float("nan")}}, "JSON"),
        ({"sha256": SHA_A, "metadata": {"run_id": "r", "x": object()}}, "JSON"),
    ],
)
def test_bad_records_name_the_field(tmp_path, kwargs, match):
    with pytest.raises(CatalogError, match=match):
        register_run(tmp_path / "c.sqlite", path="x.csv", **kwargs)
    assert issubclass(CatalogError, BayestriboError)


def test_find_run_needs_exactly_one_key(tmp_path):
    with pytest.raises(CatalogError, match="exactly one"):
        find_run(tmp_path / "c.sqlite")
    with pytest.raises(CatalogError, match="exactly one"):
        find_run(tmp_path / "c.sqlite", run_id="a", id=1)


def test_newer_schema_and_non_sqlite_files_are_refused(tmp_path):
    db = tmp_path / "new.sqlite"
    conn = sqlite3.connect(db)
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    conn.close()
    with pytest.raises(CatalogError, match="newer than this bayestribo"):
        find_run(db, id=1)
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"this is not a database" * 100)
    with pytest.raises(CatalogError, match="not an SQLite catalog"):
        list_runs(junk)


def test_failed_transaction_is_rolled_back(tmp_path):
    db = tmp_path / "c.sqlite"
    with pytest.raises(RuntimeError), connect(db) as conn, transaction(conn):
        conn.execute(
            "INSERT INTO runs (run_id, path, sha256, metadata, registered_utc) "
            "VALUES ('r', 'p', ?, '{}', 't')",
            (SHA_A,),
        )
        raise RuntimeError("crash in the middle of a write")
    assert list_runs(db) == []


def test_concurrent_writers_all_land(tmp_path):
    db = tmp_path / "c.sqlite"
    with connect(db):
        pass
    errors = []

    def work(i: int) -> None:
        try:
            register_run(db, path=f"{i}.csv", sha256=f"{i:064x}", metadata={"run_id": f"r{i}"})
        except Exception as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert sorted(r.run_id for r in list_runs(db)) == [f"r{i}" for i in range(8)]
