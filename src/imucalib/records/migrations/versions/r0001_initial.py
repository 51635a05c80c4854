"""The initial records schema: units, stations, equipment, runs, results, reviews.

Revision ID: 0001
Revises:
Create Date: 2026-11-27
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
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
    """Create the tables."""
    op.create_table(
        "units", *_chain(),
        sa.Column("serial", sa.String(200), nullable=False),
        sa.Column("model", sa.String(200), nullable=False),
        sa.Column("maker", sa.String(200), nullable=False),
        sa.Column("specification_json", sa.Text(), nullable=False),
        sa.Column("recal_interval_days", sa.Integer(), nullable=True),
        *_keys("units"), sa.UniqueConstraint("serial", name="uq_units_serial"))
    op.create_table(
        "stations", *_chain(),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("location", sa.String(400), nullable=False),
        *_keys("stations"), sa.UniqueConstraint("name", name="uq_stations_name"))
    op.create_table(
        "equipment", *_chain(),
        sa.Column("station_id", sa.Integer(), nullable=True),
        sa.Column("kind", sa.String(100), nullable=False),
        sa.Column("model", sa.String(200), nullable=False),
        sa.Column("serial", sa.String(200), nullable=False),
        sa.Column("certificate", sa.String(200), nullable=False),
        sa.Column("calibrated_on", sa.Date(), nullable=True),
        sa.Column("due_on", sa.Date(), nullable=True),
        sa.Column("replaces_id", sa.Integer(), nullable=True),
        *_keys("equipment"),
        sa.UniqueConstraint("replaces_id", name="uq_equipment_replaces_id"),
        sa.ForeignKeyConstraint(["station_id"], ["stations.id"],
                                name="fk_equipment_station_id_stations"),
        sa.ForeignKeyConstraint(["replaces_id"], ["equipment.id"],
                                name="fk_equipment_replaces_id_equipment"))
    op.create_table(
        "runs", *_chain(),
        sa.Column("plan_name", sa.String(200), nullable=False),
        sa.Column("plan_hash", sa.String(64), nullable=False),
        sa.Column("procedure", sa.String(50), nullable=False),
        sa.Column("recording_path", sa.Text(), nullable=False),
        sa.Column("recording_sha256", sa.String(64), nullable=False),
        sa.Column("environment_json", sa.Text(), nullable=False),
        sa.Column("operator", sa.String(200), nullable=False),
        sa.Column("software_version", sa.String(50), nullable=False),
        sa.Column("station_id", sa.Integer(), nullable=True),
        sa.Column("started_utc", _TZ, nullable=True),
        sa.Column("ended_utc", _TZ, nullable=True),
        *_keys("runs"),
        sa.ForeignKeyConstraint(["station_id"], ["stations.id"],
                                name="fk_runs_station_id_stations"))
    op.create_index("ix_runs_plan_name", "runs", ["plan_name"])
    op.create_index("ix_runs_plan_hash", "runs", ["plan_hash"])
    op.create_table(
        "run_equipment",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("run_id", sa.Integer(), nullable=False),
        sa.Column("equipment_id", sa.Integer(), nullable=False),
        sa.PrimaryKeyConstraint("id", name="pk_run_equipment"),
        sa.ForeignKeyConstraint(["run_id"], ["runs.id"], name="fk_run_equipment_run_id_runs"),
        sa.ForeignKeyConstraint(["equipment_id"], ["equipment.id"],
                                name="fk_run_equipment_equipment_id_equipment"))
    op.create_index("ix_run_equipment_run_id", "run_equipment", ["run_id"])
    op.create_table(
        "results", *_chain(),
        sa.Column("run_id", sa.Integer(), nullable=False),
        sa.Column("unit_id", sa.Integer(), nullable=False),
        sa.Column("procedure", sa.String(50), nullable=False),
        sa.Column("model", sa.String(50), nullable=False),
        sa.Column("passed", sa.Boolean(), nullable=True),
        sa.Column("verification_json", sa.Text(), nullable=False),
        sa.Column("document_json", sa.Text(), nullable=False),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("replaces_id", sa.Integer(), nullable=True),
        sa.Column("amendment_reason", sa.Text(), nullable=False),
        *_keys("results"),
        sa.UniqueConstraint("replaces_id", name="uq_results_replaces_id"),
        sa.ForeignKeyConstraint(["run_id"], ["runs.id"], name="fk_results_run_id_runs"),
        sa.ForeignKeyConstraint(["unit_id"], ["units.id"], name="fk_results_unit_id_units"),
        sa.ForeignKeyConstraint(["replaces_id"], ["results.id"],
                                name="fk_results_replaces_id_results"))
    op.create_index("ix_results_run_id", "results", ["run_id"])
    op.create_index("ix_results_unit_id", "results", ["unit_id"])
    op.create_table(
        "result_parameters",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("result_id", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(100), nullable=False),
        sa.Column("value", sa.Float(), nullable=False),
        sa.Column("std", sa.Float(), nullable=False),
        sa.Column("unit", sa.String(50), nullable=False),
        sa.PrimaryKeyConstraint("id", name="pk_result_parameters"),
        sa.ForeignKeyConstraint(["result_id"], ["results.id"],
                                name="fk_result_parameters_result_id_results"))
    op.create_index("ix_result_parameters_result_id", "result_parameters", ["result_id"])
    op.create_table(
        "reviews", *_chain(),
        sa.Column("result_id", sa.Integer(), nullable=False),
        sa.Column("reviewer", sa.String(200), nullable=False),
        sa.Column("reviewed_utc", _TZ, nullable=False),
        sa.Column("approved", sa.Boolean(), nullable=False),
        sa.Column("comment", sa.Text(), nullable=False),
        *_keys("reviews"),
        sa.ForeignKeyConstraint(["result_id"], ["results.id"],
                                name="fk_reviews_result_id_results"))
    op.create_index("ix_reviews_result_id", "reviews", ["result_id"])


def downgrade() -> None:
    """Drop the tables (never run by imucalib itself: records are not deleted)."""
    for table in ("reviews", "result_parameters", "results", "run_equipment", "runs",
                  "equipment", "stations", "units"):
        op.drop_table(table)
