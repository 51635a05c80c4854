"""The databases the records tests run on: SQLite always, PostgreSQL when one is named.

``IMUCALIB_TEST_PG_URL`` (set by ``.ci/run``, or by hand after ``scripts/postgres.sh start``)
names a PostgreSQL server; every test gets a database of its own there, dropped afterwards.
Import this file by its path (``tests/records/conftest.py`` may belong to another module).
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import sqlalchemy as sa

PG_ENV = "IMUCALIB_TEST_PG_URL"


def backend_urls() -> dict[str, str | None]:
    """Backend name → server URL (None: SQLite, a file per database) of the available ones."""
    out: dict[str, str | None] = {"sqlite": None}
    if os.environ.get(PG_ENV):
        out["postgresql"] = os.environ[PG_ENV]
    return out


@contextmanager
def fresh_database(backend: str, folder: Path, name: str = "db") -> Iterator[str]:
    """The URL of a new, empty database on `backend` (SQLite: in WAL mode, under `folder`)."""
    if backend == "sqlite":
        path = folder / f"{name}.sqlite3"
        engine = sa.create_engine(f"sqlite:///{path}")
        with engine.connect() as conn:
            conn.exec_driver_sql("PRAGMA journal_mode=WAL")
        engine.dispose()
        yield f"sqlite:///{path}"
        return
    server = backend_urls()[backend]
    assert server is not None, backend
    db = f"imucalib_test_{name}_{uuid.uuid4().hex[:12]}"
    admin = sa.create_engine(server, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.exec_driver_sql(f'CREATE DATABASE "{db}"')
    try:
        yield sa.make_url(server).set(database=db).render_as_string(hide_password=False)
    finally:
        with admin.connect() as conn:
            conn.exec_driver_sql(f'DROP DATABASE IF EXISTS "{db}" WITH (FORCE)')
        admin.dispose()
