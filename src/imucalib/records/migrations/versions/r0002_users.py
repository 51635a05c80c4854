"""Users and their state changes: the people who act on the records (docs/records.md).

Two new chained tables; no existing table changes, so every row recorded under revision 0001
keeps its hash.

Revision ID: 0002
Revises: 0001
Create Date: 2026-12-01
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None

_TZ = sa.DateTime(timezone=True)


def _chain() -> list[sa.Column]:
    """Return the chain columns of every chained table (imucalib.records.schema._Chained)."""
    return [
        sa.Column("id", sa.Integer(), autoincrement=False, nullable=False),
        sa.Column("seq", sa.Integer(), nullable=False),
        sa.Column("prev_hash", sa.String(64), nullable=False),
        sa.Column("row_hash", sa.String(64), nullable=False),
        sa.Column("created_utc", _TZ, nullable=False),
    ]


def _keys(table: str) -> list[sa.Constraint]:
    return [sa.PrimaryKeyConstraint("id", name=f"pk_{table}"),
            sa.UniqueConstraint("seq", name=f"uq_{table}_seq")]


def upgrade() -> None:
    """Create ``users`` and ``user_events``."""
    op.create_table(
        "users", *_chain(),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("initials", sa.String(20), nullable=False),
        sa.Column("role", sa.String(20), nullable=False),
        sa.Column("added_by", sa.String(200), nullable=False),
        *_keys("users"), sa.UniqueConstraint("name", name="uq_users_name"))
    op.create_table(
        "user_events", *_chain(),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("event", sa.String(20), nullable=False),
        sa.Column("reason", sa.Text(), nullable=False),
        sa.Column("by_user", sa.String(200), nullable=False),
        *_keys("user_events"),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"],
                                name="fk_user_events_user_id_users"))
    op.create_index("ix_user_events_user_id", "user_events", ["user_id"])


def downgrade() -> None:
    """Drop the tables (never run by imucalib itself: records are not deleted)."""
    op.drop_table("user_events")
    op.drop_table("users")
