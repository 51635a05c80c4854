"""Signed rows: a station key's signature on every new row (docs/records.md, "Signing").

Every chained table gains ``hash_version`` (1 for the rows already there, which keep their
hash: their C, Eq. (R.3), leaves the three new columns out), ``key_id`` and ``signature``
(both empty for those rows); a new chained table ``signing_keys`` holds the public keys. No
existing value changes, so a 0002 database opens with every row's hash as it was.

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-29
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None

_TABLES = ("units", "stations", "equipment", "runs", "results", "reviews", "users",
           "user_events")


def _signature_columns() -> list[sa.Column]:
    return [sa.Column("hash_version", sa.Integer(), nullable=False, server_default="1"),
            sa.Column("key_id", sa.Integer(), nullable=True),
            sa.Column("signature", sa.Text(), nullable=False, server_default="")]


def upgrade() -> None:
    """Add the signature columns and create ``signing_keys``."""
    for table in _TABLES:
        for column in _signature_columns():
            op.add_column(table, column)
    op.create_table(
        "signing_keys",
        sa.Column("id", sa.Integer(), autoincrement=False, nullable=False),
        sa.Column("seq", sa.Integer(), nullable=False),
        sa.Column("prev_hash", sa.String(64), nullable=False),
        sa.Column("row_hash", sa.String(64), nullable=False),
        sa.Column("created_utc", sa.DateTime(timezone=True), nullable=False),
        *_signature_columns(),
        sa.Column("public_key", sa.String(64), nullable=False),
        sa.Column("fingerprint", sa.String(16), nullable=False),
        sa.Column("previous_key_id", sa.Integer(), nullable=True),
        sa.Column("endorsement", sa.Text(), nullable=False),
        sa.Column("reason", sa.Text(), nullable=False),
        sa.Column("heads_json", sa.Text(), nullable=False),
        sa.PrimaryKeyConstraint("id", name="pk_signing_keys"),
        sa.UniqueConstraint("seq", name="uq_signing_keys_seq"))


def downgrade() -> None:
    """Drop them again (never run by imucalib itself: records are not deleted)."""
    op.drop_table("signing_keys")
    for table in _TABLES:
        with op.batch_alter_table(table) as batch:
            for name in ("signature", "key_id", "hash_version"):
                batch.drop_column(name)
