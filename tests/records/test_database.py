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


def _insert_v1(conn, model, values, **children):
    """Append a row as revision 0002 wrote it: hash version 1, unsigned (Eq. (R.1))."""
    from datetime import UTC, datetime

    from sqlalchemy import MetaData, Table, insert

    from imucalib.records.canonical import GENESIS, chain_hash, content_of

    table = model.__table__
    head = conn.execute(text(f"SELECT seq, row_hash FROM {table.name} ORDER BY seq DESC "
                             "LIMIT 1")).first()
    seq = 1 if head is None else head[0] + 1
    prev = GENESIS if head is None else head[1]
    values = {**values, "id": seq, "seq": seq,
              "created_utc": datetime(2026, 1, seq, 8, 0, tzinfo=UTC)}
    row_hash = chain_hash(prev, content_of(table, {**values, "hash_version": 1}, **children))
    as_0002 = Table(table.name, MetaData(), autoload_with=conn)   # no signature columns yet
    conn.execute(insert(as_0002).values(**values, prev_hash=prev, row_hash=row_hash))
    return seq


def test_a_revision_0002_database_is_upgraded_with_its_records_intact(records_url):
    """A database made before signing opens: its rows keep their hashes (hash version 1,
    noted as unsigned), new rows are signed, and a row downgraded later is found
    (docs/records.md, "Signing")."""
    from alembic import command

    from imucalib.records.schema import Result, ResultParameter, Review, Run, Station, Unit

    engine = records_engine.make_engine(records_url)
    with engine.connect() as conn, conn.begin():
        command.upgrade(records_engine._alembic_config(conn), "0002")
    with engine.begin() as conn:
        lab = _insert_v1(conn, Station, {"name": "lab 1", "location": ""})
        unit = _insert_v1(conn, Unit, {"serial": "IMU-1", "model": "", "maker": "",
                                       "specification_json": "{}"})
        run = _insert_v1(conn, Run, {"plan_name": "p1", "plan_hash": "", "procedure": "p1",
                                     "recording_path": "", "recording_sha256": "",
                                     "environment_json": "{}", "operator": "ana",
                                     "software_version": "0.1", "station_id": lab},
                         equipment=[])
        params = [{"name": "accel_b_x", "std": 0.001, "unit": "m/s^2", "value": 0.01}]
        rid = _insert_v1(conn, Result, {"run_id": run, "unit_id": unit, "procedure": "p1",
                                        "model": "per-axis", "passed": False,
                                        "verification_json": "{}", "document_json": "{}",
                                        "version": 1, "amendment_reason": ""},
                         parameters=params)
        conn.execute(ResultParameter.__table__.insert().values(result_id=rid, **params[0]))
        from datetime import UTC, datetime

        _insert_v1(conn, Review, {"result_id": rid, "reviewer": "bo", "approved": False,
                                  "reviewed_utc": datetime(2026, 1, 2, tzinfo=UTC),
                                  "comment": "bias too large"})
    engine.dispose()
    with open_records(records_url) as rec:
        before = {h.table: h for h in rec.heads()}
        report = rec.verify_report(recordings=False)
        assert report.problems == ()
        assert any("reviews: 1 row(s) unsigned, made before signing" in n for n in report.notes)
        assert rec.history("IMU-1")[0].passed is False
        rec.add_unit("IMU-2")                                 # the first signed row
        after = {h.table: h for h in rec.heads()}
        assert all(after[t] == before[t] for t in ("stations", "runs", "results", "reviews"))
        report = rec.verify_report(recordings=False)
        assert report.problems == ()
        assert [(k.key_id, k.trusted, k.rows) for k in report.keys] == [
            (1, True, {"signing_keys": 1, "units": 1})]
        _downgrade_last_unit(rec)
        problems = rec.verify(recordings=False)
        assert ("units", 2, "unsigned") in [(p.table, p.key, p.kind) for p in problems]
    engine = create_engine(records_url)
    with engine.connect() as conn:
        version = conn.execute(text("SELECT version_num FROM alembic_version")).scalar()
    engine.dispose()
    assert version == records_engine.head_revision() == "0004"


def _downgrade_last_unit(rec):
    """An intruder re-hashes the newest unit as an unsigned (hash version 1) row."""
    from sqlalchemy.orm import Session

    from imucalib.records.canonical import chain_hash, content_of
    from imucalib.records.schema import Unit

    with Session(rec.engine) as session:
        row = session.get(Unit, 2)
        values = {c.name: getattr(row, c.key) for c in Unit.__table__.columns}
        values.update(hash_version=1, key_id=None, signature="", model="forged")
        forged = chain_hash(row.prev_hash, content_of(Unit.__table__, values))
    with rec.engine.begin() as conn:
        conn.execute(text("UPDATE units SET hash_version = 1, key_id = NULL, signature = '', "
                          "model = 'forged', row_hash = :h WHERE seq = 2"), {"h": forged})


def test_a_dropped_alembic_version_is_one_clear_error(records_url):
    open_records(records_url).close()
    engine = create_engine(records_url)
    with engine.begin() as conn:
        conn.execute(text("DROP TABLE alembic_version"))
    engine.dispose()
    with pytest.raises(RecordsError, match="holds records tables but no alembic_version"):
        open_records(records_url)
