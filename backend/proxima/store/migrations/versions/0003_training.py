"""Federated training runs, rounds and per-drone results (proxima.store.training).

Revision ID: 0003
Revises: 0002
Create Date: 2025-11-22
"""

import sqlalchemy as sa
from alembic import op

from proxima.store.migrations.helpers import create_table_if_missing

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def _run_fk() -> sa.Column:
    return sa.Column(
        "run_id",
        sa.String(64),
        sa.ForeignKey("training_runs.id", ondelete="CASCADE"),
        nullable=False,
        index=True,
    )


def upgrade() -> None:
    create_table_if_missing(
        "training_runs",
        sa.Column("id", sa.String(64), primary_key=True),
        sa.Column("created_at", sa.Float(), nullable=False),
        sa.Column("started_at", sa.Float(), nullable=True),
        sa.Column("finished_at", sa.Float(), nullable=True),
        sa.Column("status", sa.String(16), nullable=False, index=True),
        sa.Column("engine", sa.String(16), nullable=False),
        sa.Column("params", sa.Text(), nullable=False),
        sa.Column("rounds_total", sa.Integer(), nullable=False),
        sa.Column("rounds_done", sa.Integer(), nullable=False),
        sa.Column("final_accuracy", sa.Float(), nullable=True),
        sa.Column("checkpoint", sa.Text(), nullable=True),
        sa.Column("model_card", sa.Text(), nullable=True),
        sa.Column("detail", sa.Text(), nullable=False),
        sa.Column("started_by", sa.String(64), nullable=False),
        sa.Column("flwr_run_id", sa.String(32), nullable=True),
        sa.Column("promoted_at", sa.Float(), nullable=True),
    )
    create_table_if_missing(
        "training_rounds",
        sa.Column("id", sa.Integer(), primary_key=True),
        _run_fk(),
        sa.Column("round", sa.Integer(), nullable=False),
        sa.Column("global_accuracy", sa.Float(), nullable=True),
        sa.Column("global_loss", sa.Float(), nullable=True),
        sa.Column("train_loss", sa.Float(), nullable=True),
        sa.Column("clients_ok", sa.Integer(), nullable=False),
        sa.Column("clients_failed", sa.Integer(), nullable=False),
        sa.Column("duration_s", sa.Float(), nullable=False),
        sa.Column("created_at", sa.Float(), nullable=False),
    )
    create_table_if_missing(
        "training_client_results",
        sa.Column("id", sa.Integer(), primary_key=True),
        _run_fk(),
        sa.Column("round", sa.Integer(), nullable=False),
        sa.Column("client", sa.String(64), nullable=False),
        sa.Column("phase", sa.String(16), nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("loss", sa.Float(), nullable=True),
        sa.Column("accuracy", sa.Float(), nullable=True),
        sa.Column("train_loss", sa.Float(), nullable=True),
        sa.Column("samples", sa.Integer(), nullable=True),
        sa.Column("duration_s", sa.Float(), nullable=True),
        sa.Column("detail", sa.Text(), nullable=False),
        sa.Column("created_at", sa.Float(), nullable=False),
    )


def downgrade() -> None:
    op.drop_table("training_client_results")
    op.drop_table("training_rounds")
    op.drop_table("training_runs")
