"""The `records_url` fixture: a fresh SQLite file always; a fresh PostgreSQL database too when
IMUCALIB_TEST_PG_URL names a server (a URL with rights to create databases).

The PostgreSQL parameter is only collected when the variable is set (pytest_generate_tests), so
no test is skipped: what runs, runs on every backend available.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from imucalib.models.result import CalibrationResult, Provenance, triad_parameter_names

PG_ENV = "IMUCALIB_TEST_PG_URL"


def backends() -> list[str]:
    return ["sqlite", "postgresql"] if os.environ.get(PG_ENV) else ["sqlite"]


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "records_url" in metafunc.fixturenames:
        metafunc.parametrize("records_url", backends(), indirect=True)


def _pg_admin_url() -> str:
    from sqlalchemy.engine import make_url

    url = make_url(os.environ[PG_ENV])
    if url.drivername == "postgresql":
        url = url.set(drivername="postgresql+psycopg")
    return url.render_as_string(hide_password=False)


@pytest.fixture(autouse=True)
def _signing_folders(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Key folders of PostgreSQL databases under the test's own config dir, not the user's."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.delenv("IMUCALIB_RECORDS_SIGNING", raising=False)


@pytest.fixture
def records_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'records.db'}"
        return
    from sqlalchemy import create_engine, text
    from sqlalchemy.engine import make_url

    admin_url = _pg_admin_url()
    name = f"imucalib_test_{uuid.uuid4().hex[:16]}"
    admin = create_engine(admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    try:
        yield make_url(admin_url).set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


@pytest.fixture
def records(records_url: str):
    from imucalib.records import open_records

    rec = open_records(records_url)
    yield rec
    rec.close()


def small_result(serial: str = "IMU-7", bias: float = 0.01, *, procedure: str = "p1",
                 seed: int = 0) -> CalibrationResult:
    """A per-axis accelerometer + gyro result with known values (12 parameters)."""
    names = (*triad_parameter_names("accel", "per-axis"),
             *triad_parameter_names("gyro", "per-axis"))
    k = len(names)
    rng = np.random.default_rng(seed)
    values = np.array([1.0 + 1e-3 * i for i in range(3)] + [bias, -bias, 2 * bias]
                      + [1.0 - 1e-3 * i for i in range(3)] + [1e-4, 2e-4, -3e-4])
    a = rng.normal(size=(k, k)) * 1e-4
    units = {n: ("1" if "_K_" in n else ("m/s^2" if n.startswith("accel") else "rad/s"))
             for n in names}
    return CalibrationResult(
        sensor_id=serial, procedure=procedure, model="per-axis", param_names=names,
        values=values, covariance=a @ a.T, units=units,
        provenance=Provenance(plan_hash="ab" * 32, recording="run.h5",
                              software_version="0.1.0", created_utc="2026-11-23T00:00:00Z"),
        notes=("hand-made",))


@pytest.fixture
def make_result():
    """The :func:`small_result` factory."""
    return small_result


@pytest.fixture
def recording_file(tmp_path: Path) -> Path:
    """A stand-in recording file with known bytes."""
    path = tmp_path / "run.h5"
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8)
    return path
