"""Small operations the revisions share, written to be safe on databases that were
created before they were versioned."""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op


def has_table(name: str) -> bool:
    return sa.inspect(op.get_bind()).has_table(name)


def has_column(table: str, column: str) -> bool:
    return any(c["name"] == column for c in sa.inspect(op.get_bind()).get_columns(table))


def create_table_if_missing(name: str, *columns: sa.Column) -> None:
    """Create a table (and the indexes its columns ask for) unless it exists already."""
    if has_table(name):
        return
    plain = []
    indexed = []
    for col in columns:
        if col.index:
            indexed.append(col.name)
            col.index = None
        plain.append(col)
    op.create_table(name, *plain)
    for col_name in indexed:
        op.create_index(f"ix_{name}_{col_name}", name, [col_name])


def add_column_if_missing(table: str, column: sa.Column) -> None:
    if not has_column(table, column.name):
        with op.batch_alter_table(table) as batch:
            batch.add_column(column)
