"""Alembic environment of the records database.

:func:`imucalib.records.engine.upgrade` builds the Alembic configuration in code and passes an
open connection in ``config.attributes["connection"]``; no ``alembic.ini`` is needed. Run by
hand, ``alembic -x url=sqlite:///records.db upgrade head`` (with ``script_location`` pointing
here) opens the URL given.
"""

from __future__ import annotations

from alembic import context
from sqlalchemy import create_engine

from imucalib.records.schema import Base

config = context.config
target_metadata = Base.metadata


def _run(connection: object) -> None:
    context.configure(connection=connection, target_metadata=target_metadata,  # type: ignore[arg-type]
                      render_as_batch=True)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    """Run the migrations on the connection given, or on the URL of ``-x url=…``."""
    connection = config.attributes.get("connection")
    if connection is not None:
        _run(connection)
        return
    url = context.get_x_argument(as_dictionary=True).get("url") or config.get_main_option(
        "sqlalchemy.url")
    engine = create_engine(str(url))
    with engine.connect() as conn:
        _run(conn)
    engine.dispose()


if context.is_offline_mode():
    raise SystemExit("the records migrations run online only (imucalib.records.open_records)")
run_migrations_online()
