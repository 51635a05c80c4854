"""Where the database is, its migrations, and the errors of opening one."""

from __future__ import annotations

import pytest
from sqlalchemy import create_engine, inspect, text

from imucalib.errors import RecordsError
from imucalib.records import engine as records_engine
from imucalib.records import open_records, resolve_url


def test_url_rules(monkeypatch, tmp_path):
    monkeypatch.setenv("IMUCALIB_DB", "postgresql+psycopg://lab@db/records")
    assert resolve_url("sqlite:///x.db") == "sqlite:///x.db"
    assert resolve_url() == "postgresql+psycopg://lab@db/records"
    monkeypatch.delenv("IMUCALIB_DB")
    monkeypatch.setattr("platformdirs.user_data_dir", lambda app: str(tmp_path / "data" / app))
    assert resolve_url() == f"sqlite:///{tmp_path / 'data' / 'imucalib' / 'records.db'}"
    assert (tmp_path / "data" / "imucalib").is_dir()
    assert resolve_url(str(tmp_path / "r.db")) == f"sqlite:///{tmp_path / 'r.db'}"


def test_default_database_is_created_in_the_data_directory(monkeypatch, tmp_path):
    monkeypatch.delenv("IMUCALIB_DB", raising=False)
    monkeypatch.setattr("platformdirs.user_data_dir", lambda app: str(tmp_path / app))
    with open_records() as rec:
        assert rec.units() == []
    assert (tmp_path / "imucalib" / "records.db").is_file()


def test_sqlite_connections_are_wal_with_a_busy_timeout(tmp_path):
    with open_records(f"sqlite:///{tmp_path / 'r.db'}") as rec, rec.engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert conn.exec_driver_sql("PRAGMA busy_timeout").scalar() == \
            records_engine.BUSY_TIMEOUT_MS
        assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1


def test_migration_creates_exactly_the_models(records_url):
    from alembic.autogenerate import compare_metadata
    from alembic.migration import MigrationContext

    from imucalib.records.schema import Base

    open_records(records_url).close()
    engine = create_engine(records_url)
    with engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), Base.metadata)
        version = conn.execute(text("SELECT version_num FROM alembic_version")).scalar()
    engine.dispose()
    assert diff == []
    assert version == records_engine.head_revision()


def test_the_head_revision_constant_is_alembics_head():
    """``HEAD_REVISION`` lets an up-to-date database open without Alembic: a new migration
    must move it (else such a database would be left at the old revision)."""
    assert records_engine.HEAD_REVISION == records_engine.head_revision()


def test_a_newer_schema_is_refused(records_url):
    open_records(records_url).close()
    engine = create_engine(records_url)
    with engine.begin() as conn:
        conn.execute(text("UPDATE alembic_version SET version_num = '9999'"))
    engine.dispose()
    head = records_engine.head_revision()
    with pytest.raises(RecordsError, match=rf"schema revision 9999, newer than this software "
                                           rf"knows \(newest {head}\); upgrade imucalib"):
        open_records(records_url)


def test_unreachable_and_malformed_urls_are_named(tmp_path):
    with pytest.raises(RecordsError, match=r"cannot open the records database "
                                           r"postgresql\+psycopg://lab:\*\*\*@127.0.0.1:9/x"):
        open_records("postgresql+psycopg://lab:secret@127.0.0.1:9/x")
    with pytest.raises(RecordsError, match="must be a SQLAlchemy URL"):
        open_records("nosuchdriver://x/y")
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    with pytest.raises(RecordsError, match="cannot open the records database"):
        open_records(f"sqlite:///{blocked / 'r.db'}")


def test_reopening_keeps_the_records(records_url, make_result):
    with open_records(records_url) as rec:
        run = rec.record_run(plan_name="p")
        rec.record_result(run, make_result("IMU-1"))
    with open_records(records_url) as rec:
        assert [h.serial for h in rec.history("IMU-1")] == ["IMU-1"]
        assert rec.verify() == []


def test_a_revision_0001_database_is_upgraded_with_its_records_intact(records_url, make_result,
                                                                      monkeypatch):
    """A database made by the first schema (no users) opens: the users tables are added and
    every row recorded before keeps its hash (docs/records.md, "The schema")."""
    from alembic import command

    from imucalib.records.api import Records

    engine = records_engine.make_engine(records_url)
    with engine.connect() as conn, conn.begin():
        command.upgrade(records_engine._alembic_config(conn), "0001")
    old = Records(engine)                       # the records as imucalib wrote them at 0001
    monkeypatch.setattr("imucalib.records.users.check_operator", lambda _s, op: op)  # no users
    lab = old.add_station("lab 1")
    table = old.add_equipment(lab, "rate table", serial="T-1", certificate="C-1")
    run = old.record_run(plan_name="p1", operator="ana", station=lab, equipment=[table])
    rid = old.record_result(run, make_result("IMU-1"), passed=True)
    with engine.begin() as conn:                # a review as revision 0001 stored it
        conn.execute(text("INSERT INTO reviews (id, seq, prev_hash, row_hash, created_utc, "
                          "result_id, reviewer, reviewed_utc, approved, comment) SELECT 1, 1, "
                          "'', '', created_utc, id, 'bo', created_utc, (1 = 1), 'ok' "
                          "FROM results"))
    with engine.connect() as conn:
        assert conn.execute(text("SELECT version_num FROM alembic_version")).scalar() == "0001"
        assert not inspect(conn).has_table("users")
    engine.dispose()
    _rehash_reviews(records_url)
    with open_records(records_url) as rec:
        before = {h.table: h for h in rec.heads()}
        assert rec.verify(recordings=False) == []
        assert rec.users() == [] and before["users"].seq == 0
        assert rec.release_status(rid).decision == "approve"
        rec.add_user("Ada Admin", "AA", "admin")
        rec.add_user("Rae Reviewer", "RR", "reviewer", by="Ada Admin")
        rec.review(rid, "Rae Reviewer", approved=True)
        assert rec.release_status(rid).released
        after = {h.table: h for h in rec.heads()}
        assert all(after[t] == before[t] for t in ("units", "stations", "equipment", "runs",
                                                   "results"))
        assert rec.verify(recordings=False) == []
    engine = create_engine(records_url)
    with engine.connect() as conn:
        version = conn.execute(text("SELECT version_num FROM alembic_version")).scalar()
    engine.dispose()
    assert version == records_engine.head_revision()


def _rehash_reviews(url):
    """Give the hand-inserted review its chain hash (Eq. (R.1)), as 0001's code did."""
    from sqlalchemy.orm import Session

    from imucalib.records.canonical import GENESIS
    from imucalib.records.chain import expected_hash
    from imucalib.records.schema import Review

    engine = create_engine(url)
    with Session(engine) as session:
        row = session.get(Review, 1)
        row.prev_hash = GENESIS
        row.row_hash = expected_hash(session, row, GENESIS)
        session.commit()
    engine.dispose()
