"""Where the records database is, how it is connected to, and how its schema is brought up to date.

Contents
--------
:data:`ENV_VAR`
    ``IMUCALIB_DB``: the database URL when none is given.
:func:`default_url`, :func:`resolve_url`
    The URL rules (docs/records.md, "Where the database is").
:func:`make_engine`
    An engine; for SQLite every connection gets WAL mode, a busy timeout and foreign keys, and
    a write transaction begins with ``BEGIN IMMEDIATE`` (docs/records.md, "Concurrency").
:func:`upgrade`, :func:`head_revision`
    Alembic's ``upgrade head`` run in code (no ``alembic.ini``); a database whose revision this
    software does not know is refused (it is newer).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Final

from sqlalchemy import Engine, create_engine, event, inspect, text
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError, NoSuchModuleError, OperationalError
from sqlalchemy.exc import DBAPIError as _DBAPIError

from imucalib.errors import RecordsError

__all__ = ["BUSY_TIMEOUT_MS", "ENV_VAR", "default_url", "head_revision", "make_engine",
           "resolve_url", "safe_url", "upgrade"]

ENV_VAR: Final = "IMUCALIB_DB"
#: How long an SQLite connection waits for another writer's lock before failing. [ms]
BUSY_TIMEOUT_MS: Final = 30_000
#: Execution option naming the statement that begins a transaction on SQLite.
BEGIN_OPTION: Final = "imucalib_sqlite_begin"
MIGRATIONS: Final = Path(__file__).resolve().parent / "migrations"
#: The newest revision in ``migrations/versions`` (what :func:`head_revision` finds): a database
#: already there is opened without importing Alembic (a third of a second; a test checks that
#: the two agree).
HEAD_REVISION: Final = "0004"


def _make_folder(folder: Path, url: str) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RecordsError(f"cannot open the records database {safe_url(url)}: expected a "
                           f"folder {folder} that can be created, got {exc}") from exc


def default_url() -> str:
    """Return ``sqlite:///<user data dir>/records.db``, creating the folder (platformdirs)."""
    import platformdirs

    folder = Path(platformdirs.user_data_dir("imucalib"))
    _make_folder(folder, str(folder / "records.db"))
    return f"sqlite:///{folder / 'records.db'}"


def resolve_url(url: str | None = None) -> str:
    """Return the database URL: `url`, else ``$IMUCALIB_DB``, else the configuration's.

    The laboratory configuration's ``[records] database`` (:mod:`imucalib.config`), else
    :func:`default_url`. A bare file path (no ``://``) is taken as an SQLite file.
    """
    chosen = url or os.environ.get(ENV_VAR)
    if not chosen:
        from imucalib.config import load_config  # read only when no URL was given

        chosen = load_config().records.database or default_url()
    if "://" not in chosen:
        chosen = f"sqlite:///{Path(chosen).expanduser().resolve()}"
    return chosen


def safe_url(url: str) -> str:
    """Return `url` with its password hidden (for messages)."""
    try:
        return make_url(url).render_as_string(hide_password=True)
    except ArgumentError:
        return url


def _sqlite_listeners(engine: Engine) -> None:
    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_connection: Any, _record: Any) -> None:
        dbapi_connection.isolation_level = None  # SQLAlchemy's "begin" event issues BEGIN
        cursor = dbapi_connection.cursor()
        cursor.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        cursor.execute("PRAGMA journal_mode = WAL")
        cursor.execute("PRAGMA foreign_keys = ON")
        cursor.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Any) -> None:
        conn.exec_driver_sql(conn.get_execution_options().get(BEGIN_OPTION, "BEGIN"))


def make_engine(url: str) -> Engine:
    """Return an engine for `url` (SQLite: WAL, busy timeout, foreign keys, explicit BEGIN).

    Raises
    ------
    RecordsError
        A URL that cannot be parsed or names a driver that is not installed.
    """
    try:
        parsed = make_url(url)
        if parsed.get_backend_name() == "sqlite":
            database = parsed.database or ""
            if database and database != ":memory:" and not database.startswith("file:"):
                _make_folder(Path(database).expanduser().parent, url)
            engine = create_engine(parsed, connect_args={"timeout": BUSY_TIMEOUT_MS / 1000})
            _sqlite_listeners(engine)
            return engine
        return create_engine(parsed, pool_pre_ping=True)
    except (ArgumentError, NoSuchModuleError, ImportError) as exc:
        raise RecordsError(f"records database URL must be a SQLAlchemy URL such as "
                           f"sqlite:///records.db or postgresql+psycopg://user@host/db; got "
                           f"{safe_url(url)!r} ({exc})") from exc


def _alembic_config(connection: Any) -> Any:
    from alembic.config import Config

    config = Config()
    config.set_main_option("script_location", str(MIGRATIONS))
    config.attributes["connection"] = connection
    return config


def head_revision() -> str:
    """Return the newest schema revision this software knows."""
    from alembic.script import ScriptDirectory

    head = ScriptDirectory.from_config(_alembic_config(None)).get_current_head()
    assert head is not None
    return head


def _current_revisions(engine: Engine) -> list[str]:
    with engine.connect() as conn:
        if not inspect(conn).has_table("alembic_version"):
            return []
        return [row[0] for row in conn.execute(text("SELECT version_num FROM alembic_version"))]


#: Attempts of a schema upgrade that met a database busy with another opener.
UPGRADE_ATTEMPTS: Final = 12
#: Tables every records database made by imucalib has (revision 0001 on).
_RECORDS_TABLES: Final = ("units", "results", "runs")


def _transient(exc: BaseException) -> bool:
    text = str(getattr(exc, "orig", None) or exc).lower()
    return "locked" in text or "busy" in text or "deadlock" in text


def upgrade(engine: Engine) -> None:
    """Bring the schema to the newest revision (Alembic ``upgrade head``, run in code).

    Safe against a concurrent opener: a database that another process is creating or
    upgrading at the same instant ("database is locked") is waited for and tried again.

    Raises
    ------
    RecordsError
        The database cannot be reached, it carries a schema revision this software does not
        know (made by a newer imucalib), or it holds records tables without Alembic's
        ``alembic_version`` (its revision cannot be told).
    """
    import time

    for attempt in range(UPGRADE_ATTEMPTS):
        try:
            _upgrade_once(engine)
            return
        except (OperationalError, _DBAPIError) as exc:
            if not _transient(exc) or attempt == UPGRADE_ATTEMPTS - 1:
                url = safe_url(engine.url.render_as_string(hide_password=False))
                raise RecordsError(f"cannot open the records database {url}: expected a "
                                   f"reachable database, got "
                                   f"{str(exc.orig or exc).splitlines()[0]}") from exc
            time.sleep(min(0.02 * 2 ** attempt, 1.0))


def _upgrade_once(engine: Engine) -> None:
    url = safe_url(engine.url.render_as_string(hide_password=False))
    current = _current_revisions(engine)
    if current == [HEAD_REVISION]:  # up to date: no Alembic to import
        return
    if not current:
        with engine.connect() as conn:    # (another opener may have just made it all)
            names = set(inspect(conn).get_table_names())
        current = _current_revisions(engine)
        if current == [HEAD_REVISION]:
            return
        if not current and names & set(_RECORDS_TABLES):
            raise RecordsError(f"the records database {url} holds records tables but no "
                               "alembic_version table, so its schema revision cannot be told "
                               "(the table was dropped?): expected a database made by "
                               "imucalib; restore it from a backup (imucalib records restore)")
    from alembic import command
    from alembic.script import ScriptDirectory

    script = ScriptDirectory.from_config(_alembic_config(None))
    known = {rev.revision for rev in script.walk_revisions()}
    unknown = [rev for rev in current if rev not in known]
    if unknown:
        raise RecordsError(f"the records database {url} has schema revision {unknown[0]}, "
                           f"newer than this software knows (newest {head_revision()}); "
                           "upgrade imucalib (or its alembic_version was changed)")
    if current == [script.get_current_head()]:
        return
    with engine.connect() as conn:
        conn.execution_options(**{BEGIN_OPTION: "BEGIN IMMEDIATE"})  # one migrator at a time
        with conn.begin():
            if engine.dialect.name == "postgresql":
                conn.execute(text("SELECT pg_advisory_xact_lock(7252001)"))
            command.upgrade(_alembic_config(conn), "head")
