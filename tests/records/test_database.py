"""Where the database is, its migrations, and the errors of opening one."""

from __future__ import annotations

import pytest
from sqlalchemy import create_engine, text

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


def test_a_newer_schema_is_refused(records_url):
    open_records(records_url).close()
    engine = create_engine(records_url)
    with engine.begin() as conn:
        conn.execute(text("UPDATE alembic_version SET version_num = '9999'"))
    engine.dispose()
    with pytest.raises(RecordsError, match=r"schema revision 9999, newer than this software "
                                           r"knows \(newest 0001\); upgrade imucalib"):
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
