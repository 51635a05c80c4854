"""The station's web page: passwords, the audit trail, web sessions, the station lock.

Two new chained tables (``user_credentials``, ``audit_events``) and two tables of working
state that are not records (``web_sessions``, ``station_locks``; docs/web.md). No existing
table changes, so every row recorded before keeps its hash.

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-29
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None

_TZ = sa.DateTime(timezone=True)


def _chain(table: str) -> list[sa.Column | sa.Constraint]:
    """Return the chain and signature columns of a chained table, with its keys."""
    return [
        sa.Column("id", sa.Integer(), autoincrement=False, nullable=False),
        sa.Column("seq", sa.Integer(), nullable=False),
        sa.Column("prev_hash", sa.String(64), nullable=False),
        sa.Column("row_hash", sa.String(64), nullable=False),
        sa.Column("created_utc", _TZ, nullable=False),
        sa.Column("hash_version", sa.Integer(), nullable=False, server_default="1"),
        sa.Column("key_id", sa.Integer(), nullable=True),
        sa.Column("signature", sa.Text(), nullable=False, server_default=""),
        sa.PrimaryKeyConstraint("id", name=f"pk_{table}"),
        sa.UniqueConstraint("seq", name=f"uq_{table}_seq"),
    ]


def upgrade() -> None:
    """Create the four tables."""
    op.create_table(
        "user_credentials", *_chain("user_credentials"),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("password_hash", sa.Text(), nullable=False),
        sa.Column("by_user", sa.String(200), nullable=False),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"],
                                name="fk_user_credentials_user_id_users"))
    op.create_index("ix_user_credentials_user_id", "user_credentials", ["user_id"])
    op.create_table(
        "audit_events", *_chain("audit_events"),
        sa.Column("actor", sa.String(200), nullable=False),
        sa.Column("action", sa.String(40), nullable=False),
        sa.Column("station", sa.String(200), nullable=False),
        sa.Column("run_ref", sa.String(200), nullable=False),
        sa.Column("details_json", sa.Text(), nullable=False))
    op.create_index("ix_audit_events_action", "audit_events", ["action"])
    op.create_index("ix_audit_events_run_ref", "audit_events", ["run_ref"])
    op.create_table(
        "web_sessions",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("token_hash", sa.String(64), nullable=False),
        sa.Column("user_name", sa.String(200), nullable=False),
        sa.Column("created_utc", _TZ, nullable=False),
        sa.Column("expires_utc", _TZ, nullable=False),
        sa.Column("csrf_token", sa.String(64), nullable=False),
        sa.PrimaryKeyConstraint("id", name="pk_web_sessions"),
        sa.UniqueConstraint("token_hash", name="uq_web_sessions_token_hash"))
    op.create_index("ix_web_sessions_user_name", "web_sessions", ["user_name"])
    op.create_table(
        "station_locks",
        sa.Column("station", sa.String(200), nullable=False),
        sa.Column("holder", sa.String(200), nullable=False),
        sa.Column("since_utc", _TZ, nullable=True),
        sa.Column("requested_by", sa.String(200), nullable=False),
        sa.Column("requested_utc", _TZ, nullable=True),
        sa.PrimaryKeyConstraint("station", name="pk_station_locks"))


def downgrade() -> None:
    """Drop them again (never run by imucalib itself: records are not deleted)."""
    for table in ("station_locks", "web_sessions", "audit_events", "user_credentials"):
        op.drop_table(table)
