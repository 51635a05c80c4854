"""Fixtures of the web tests: a records database with one user per role, the app, clients.

The records database is a fresh SQLite file, and a fresh PostgreSQL database too when
IMUCALIB_TEST_PG_URL names a server (as tests/records does). Passwords are hashed with a cheap
argon2 cost here (the cost is not what these tests check).
"""

from __future__ import annotations

import importlib.util
import os
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

PG_ENV = "IMUCALIB_TEST_PG_URL"


def _load(name: str) -> Any:
    """Import the helper module ``tests/web/<name>.py`` by its path (the tests import-mode is
    ``importlib``: the folder is no package); the fixtures below hand the modules over."""
    path = Path(__file__).with_name(f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"web_tests_{name}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


fake = _load("_fake_supervisor")
helpers = _load("_web")
live_helpers = _load("_live_server")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "records_url" in metafunc.fixturenames:
        metafunc.parametrize("records_url",
                             ["sqlite", "postgresql"] if os.environ.get(PG_ENV) else ["sqlite"],
                             indirect=True)


@pytest.fixture(autouse=True)
def _isolated(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Key folders under the test's own config dir; a cheap argon2 cost."""
    from imucalib.records import access

    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.delenv("IMUCALIB_RECORDS_SIGNING", raising=False)
    monkeypatch.delenv("IMUCALIB_DB", raising=False)
    # with IMUCALIB_DB unset the default database is under the user's data dir: the test's own
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setattr(access, "ARGON2_PARAMS",
                        {"time_cost": 1, "memory_cost": 1024, "parallelism": 1})


@pytest.fixture
def records_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'records.db'}"
        return
    from sqlalchemy import create_engine, text
    from sqlalchemy.engine import make_url

    url = make_url(os.environ[PG_ENV])
    if url.drivername == "postgresql":
        url = url.set(drivername="postgresql+psycopg")
    admin_url = url.render_as_string(hide_password=False)
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
def supervisor(tmp_path: Path) -> Any:
    sup = fake.FakeSupervisor(tmp_path / "runs")
    sup.add()
    return sup


@pytest.fixture
def web_app(records_url: str, tmp_path: Path, supervisor: Any) -> Iterator[Any]:
    from imucalib.web.app import create_app

    helpers.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    app = create_app(records_url, tmp_path / "runs", supervisor, plans_dir=plans,
                     station="bench-1")
    yield app
    app.state.web.close()


@pytest.fixture
def web() -> Any:
    """The helpers module (tests/web/_web.py)."""
    return helpers


@pytest.fixture
def live() -> Any:
    """The live server and chromium helpers module (tests/web/_live_server.py)."""
    return live_helpers


@pytest.fixture
def browser(web_app: Any) -> Any:
    """`browser(role)`: a logged-in client (None: no session)."""
    return lambda role: helpers.Browser(web_app, role)
