"""Backups of the records database (imucalib.records.backup; docs/records.md, "Backups").

A stand-in schema of two tables (units ← results, a foreign key, datetimes, floats, bytes,
decimals) on every available backend (tests/records/_backends.py): SQLite always, PostgreSQL
when IMUCALIB_TEST_PG_URL names a server.
"""

from __future__ import annotations

import datetime as dt
import decimal
import hashlib
import importlib.util
import json
import math
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
import sqlalchemy as sa

from imucalib.errors import InvalidInputError
from imucalib.records import backup as bk
from imucalib.records.backup import BackupCorruptError, backup, restore, verify_backup


def _load_backends():
    name = "imucalib_tests_records_backends"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(
            "_backends.py"))
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


backends = _load_backends()

META = sa.MetaData()
UNITS = sa.Table(
    "units", META,
    sa.Column("id", sa.Integer, primary_key=True),
    sa.Column("serial", sa.String(40), nullable=False, unique=True),
    sa.Column("received_utc", sa.DateTime(timezone=True), nullable=False),
)
RESULTS = sa.Table(
    "results", META,
    sa.Column("id", sa.Integer, primary_key=True),
    sa.Column("unit_id", sa.Integer, sa.ForeignKey("units.id"), nullable=False),
    sa.Column("measured_at", sa.DateTime, nullable=False),
    sa.Column("bias_mps2", sa.Float(53), nullable=False),
    sa.Column("scale_ppm", sa.Float(53)),
    sa.Column("price", sa.Numeric(12, 4)),
    sa.Column("digest", sa.LargeBinary),
    sa.Column("note", sa.Text),
)

#: Floats a text dump could spoil: 0.1, a subnormal, −0, huge, π's last digit, infinity.
FLOATS = [0.1, 5e-324, -0.0, 1.7976931348623157e308, math.pi, float("inf"), 1 / 3]


def _populate(url: str, units: int = 3, per_unit: int = 4) -> None:
    engine = sa.create_engine(url)
    META.create_all(engine)
    t0 = dt.datetime(2026, 3, 1, 8, 30, 15, 123456, tzinfo=dt.UTC)
    with engine.begin() as conn:
        conn.execute(UNITS.insert(), [
            {"id": u + 1, "serial": f"IMU-{u + 1:04d}", "received_utc": t0 + dt.timedelta(days=u)}
            for u in range(units)])
        conn.execute(RESULTS.insert(), [
            {"id": u * per_unit + k + 1, "unit_id": u + 1,
             "measured_at": dt.datetime(2026, 3, 2, 9, 0, 0, 250000) + dt.timedelta(minutes=k),
             "bias_mps2": FLOATS[(u * per_unit + k) % len(FLOATS)],
             "scale_ppm": None if k == 1 else 12.5 * k - 3e-9,
             "price": decimal.Decimal("1234.5678") if k == 0 else None,
             "digest": (bytes(range(256)) if k == 2
                        else hashlib.sha256(f"{u}.{k}".encode()).digest()),
             "note": "β-test ✓ \"quoted\"\nline" if k == 3 else None}
            for u in range(units) for k in range(per_unit)])
    engine.dispose()


def _all_rows(url: str) -> dict[str, list[tuple]]:
    engine = sa.create_engine(url)
    with engine.connect() as conn:
        out = {t.name: [tuple(r) for r in conn.execute(sa.select(t).order_by(t.c.id))]
               for t in (UNITS, RESULTS)}
    engine.dispose()
    return out


@pytest.fixture(params=sorted(backends.backend_urls()))
def backend(request) -> str:
    return request.param


@pytest.fixture
def source(backend, tmp_path):
    with backends.fresh_database(backend, tmp_path, "src") as url:
        _populate(url)
        yield url


@pytest.fixture
def recording(tmp_path) -> Path:
    path = tmp_path / "IMU-0001.p1.h5"
    path.write_bytes(bytes(range(256)) * 300 + b"end")
    return path


def _flip_byte(path: Path, at: int = 10) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x01
    path.write_bytes(bytes(data))


def test_values_read_back_to_the_same_python_values():
    values = [None, True, 7, -2**62, "β ✓", 0.1, -0.0, 5e-324, float("inf"), float("-inf"),
              dt.datetime(2026, 1, 2, 3, 4, 5, 678901, tzinfo=dt.timezone(dt.timedelta(hours=2))),
              dt.datetime(2026, 1, 2), dt.date(2026, 5, 6), dt.time(7, 8, 9, 10),
              dt.timedelta(seconds=1.5), b"\x00\xff", decimal.Decimal("-12.3400"),
              uuid.UUID(int=12345), {"a": [1, 2.5]}, [1, "x"]]
    text = json.dumps([bk._encode(v) for v in values], allow_nan=False)
    back = [bk._decode(v) for v in json.loads(text)]
    assert back == values
    assert [type(v) for v in back] == [type(v) for v in values]
    assert math.copysign(1.0, back[6]) == -1.0
    assert math.isnan(bk._decode(json.loads(json.dumps(bk._encode(float("nan"))))))
    with pytest.raises(InvalidInputError, match="object"):
        bk._encode(object())


def test_a_backup_in_two_places_is_complete_and_verified(backend, source, recording, tmp_path):
    a, b = tmp_path / "disk" / "bk", tmp_path / "share" / "bk"
    manifests = backup(source, [a, b], recordings=[recording])
    assert [m.dest for m in manifests] == [a, b]
    assert verify_backup(a) == [] and verify_backup(b) == []
    ma, mb = manifests
    assert ma.files == mb.files and ma.tables == mb.tables
    assert [(t.name, t.rows) for t in ma.tables] == [("units", 3), ("results", 12)]
    assert ma.database_kind == backend and ma.schema_revision is None
    assert ma.recordings == ("recordings/IMU-0001.p1.h5",)
    rec = ma.files["recordings/IMU-0001.p1.h5"]
    assert rec.sha256 == hashlib.sha256(recording.read_bytes()).hexdigest()
    assert (b / "recordings" / recording.name).read_bytes() == recording.read_bytes()
    assert (bk.SQLITE_COPY in ma.files) == (backend == "sqlite")
    on_disk = json.loads((b / "manifest.json").read_text())
    assert on_disk["files"]["tables/results.jsonl"]["sha256"] == hashlib.sha256(
        (b / "tables" / "results.jsonl").read_bytes()).hexdigest()
    first = json.loads((a / "tables" / "results.jsonl").read_text().splitlines()[0])
    assert first["bias_mps2"] == 0.1 and "$bytes" in first["digest"]
    assert "$datetime" in first["measured_at"] and first["price"] == {"$decimal": "1234.5678"}
    with pytest.raises(InvalidInputError, match="not an empty folder"):
        backup(source, [a])


def test_a_flipped_byte_and_a_missing_file_are_named(source, recording, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    backup(source, [a, b], recordings=[recording])
    _flip_byte(b / "tables" / "results.jsonl")
    (b / "recordings" / recording.name).unlink()
    problems = verify_backup(b)
    assert len(problems) == 2, problems
    assert problems[0] == f"recordings/{recording.name}: missing"
    assert problems[1].startswith("tables/results.jsonl: changed")
    assert verify_backup(a) == []  # the other copy is intact
    (a / "manifest.json").unlink()
    assert verify_backup(a) == ["manifest.json: missing"]


def test_backup_reads_every_copy_back_and_names_a_bad_one(source, tmp_path, monkeypatch):
    real = bk._copy_hashed

    def flaky(src: Path, dst: Path):  # a disk that spoils what it writes into folder b
        digest = real(src, dst)
        if tmp_path / "b" in dst.parents and dst.name == "units.jsonl":
            _flip_byte(dst, 3)
        return digest

    monkeypatch.setattr(bk, "_copy_hashed", flaky)
    with pytest.raises(BackupCorruptError, match=r"tables/units\.jsonl: changed") as err:
        backup(source, [tmp_path / "a", tmp_path / "b"])
    assert err.value.dest == tmp_path / "b"


def test_restore_gives_identical_rows_and_recordings(backend, source, recording, tmp_path):
    backup(source, [tmp_path / "bk"], recordings=[recording])
    with backends.fresh_database(backend, tmp_path, "restored") as url:
        summary = restore(tmp_path / "bk", url, metadata=META,
                          recordings_dir=tmp_path / "restored-recordings")
        assert summary.rows == {"units": 3, "results": 12}
        assert summary.files == (tmp_path / "restored-recordings" / recording.name,)
        assert summary.files[0].read_bytes() == recording.read_bytes()
        want, got = _all_rows(source), _all_rows(url)
        assert got == want
        assert [math.copysign(1, r[3]) for r in got["results"]] == [
            math.copysign(1, r[3]) for r in want["results"]]  # −0 stays −0 where stored so
        # The keys' sequences continue after the loaded rows (PostgreSQL's serial columns).
        engine = sa.create_engine(url)
        with engine.begin() as conn:
            new_id = conn.execute(UNITS.insert().returning(UNITS.c.id), {
                "serial": "IMU-NEW", "received_utc": dt.datetime.now(dt.UTC)}).scalar()
        engine.dispose()
        assert new_id == 4
        with pytest.raises(InvalidInputError, match="empty database"):
            restore(tmp_path / "bk", url, metadata=META)


def test_restore_with_create_schema_refuses_another_revision(tmp_path):
    with backends.fresh_database("sqlite", tmp_path, "src") as src:
        _populate(src)
        engine = sa.create_engine(src)
        with engine.begin() as conn:
            conn.exec_driver_sql("CREATE TABLE alembic_version (version_num VARCHAR(32))")
            conn.exec_driver_sql("INSERT INTO alembic_version VALUES ('abc123')")
        engine.dispose()
        (m,) = backup(src, [tmp_path / "bk"])
    assert m.schema_revision == "abc123" and "alembic_version" not in [t.name for t in m.tables]

    def at(revision: str):
        def create_schema(engine: sa.Engine) -> None:
            META.create_all(engine)
            with engine.begin() as conn:
                conn.exec_driver_sql("CREATE TABLE alembic_version (version_num VARCHAR(32))")
                conn.exec_driver_sql(f"INSERT INTO alembic_version VALUES ('{revision}')")
        return create_schema

    with pytest.raises(InvalidInputError, match=r"revision abc123.*at def456"):
        restore(tmp_path / "bk", f"sqlite:///{tmp_path / 'r1.sqlite3'}",
                create_schema=at("def456"))
    summary = restore(tmp_path / "bk", f"sqlite:///{tmp_path / 'r2.sqlite3'}",
                      create_schema=at("abc123"))
    assert summary.rows == {"units": 3, "results": 12} and summary.schema_revision == "abc123"
    with pytest.raises(InvalidInputError, match="exactly one"):
        restore(tmp_path / "bk", f"sqlite:///{tmp_path / 'r3.sqlite3'}")


def test_restore_refuses_a_corrupted_backup_and_loads_nothing(backend, source, tmp_path):
    backup(source, [tmp_path / "bk"])
    _flip_byte(tmp_path / "bk" / "tables" / "units.jsonl", 20)
    with backends.fresh_database(backend, tmp_path, "restored") as url:
        with pytest.raises(BackupCorruptError, match=r"tables/units\.jsonl: changed"):
            restore(tmp_path / "bk", url, metadata=META)
        engine = sa.create_engine(url)
        assert sa.inspect(engine).get_table_names() == []
        engine.dispose()


WRITER = """
import sys, datetime as dt, sqlalchemy as sa
engine = sa.create_engine(sys.argv[1])
print("ready", flush=True)
sys.stdin.readline()
with engine.begin() as conn:
    conn.exec_driver_sql("INSERT INTO units (id, serial, received_utc) VALUES (100, 'IMU-0100', "
                         "'2026-03-09 10:00:00')")
    conn.exec_driver_sql("INSERT INTO results (id, unit_id, measured_at, bias_mps2) "
                         "VALUES (1000, 100, '2026-03-09 10:00:00', 0.5)")
print("committed", flush=True)
"""


def test_a_backup_taken_while_another_process_writes_is_consistent(backend, source, tmp_path):
    # Another process commits a new unit and its result right after the backup has read the
    # units and before it reads the results: a dump outside one snapshot would then hold a
    # result whose unit is missing.
    writer = subprocess.Popen([sys.executable, "-c", WRITER, source], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    assert writer.stdout is not None and writer.stdin is not None
    assert writer.stdout.readline().strip() == "ready"
    fired: list[str] = []

    def after_execute(conn, cursor, statement, parameters, context, executemany):
        if not fired and "FROM units" in statement:
            fired.append(statement)
            writer.stdin.write("go\n")
            writer.stdin.flush()
            fired.append(writer.stdout.readline().strip())

    sa.event.listen(sa.Engine, "after_cursor_execute", after_execute)
    try:
        (m,) = backup(source, [tmp_path / "bk"])
    finally:
        sa.event.remove(sa.Engine, "after_cursor_execute", after_execute)
        writer.wait(timeout=30)
    assert writer.returncode == 0 and fired[1] == "committed", fired
    assert len(_all_rows(source)["units"]) == 4  # the writer's unit is in the database …
    dump = {t: [json.loads(line) for line in (tmp_path / "bk" / "tables" / f"{t}.jsonl")
                .read_text().splitlines()] for t in ("units", "results")}
    unit_ids = {r["id"] for r in dump["units"]}
    assert unit_ids == {1, 2, 3}  # … but not in the snapshot, and neither is its result
    assert {r["unit_id"] for r in dump["results"]} <= unit_ids
    assert [(t.name, t.rows) for t in m.tables] == [("units", 3), ("results", 12)]
    if backend == "sqlite":  # the byte copy is of the same snapshot, foreign keys intact
        copy = sa.create_engine(f"sqlite:///{tmp_path / 'bk' / bk.SQLITE_COPY}")
        with copy.connect() as conn:
            assert conn.exec_driver_sql("SELECT count(*) FROM results").scalar() == 12
            assert conn.exec_driver_sql("PRAGMA foreign_key_check").fetchall() == []
        copy.dispose()
