"""Alembic environment: always run programmatically by `proxima.store.migrations`, which
hands over an open connection; every table module in store/ registers on one Base."""

from __future__ import annotations

from alembic import context

from proxima.store.migrations import target_metadata

connection = context.config.attributes["connection"]
context.configure(
    connection=connection,
    target_metadata=target_metadata(),
    render_as_batch=True,  # SQLite cannot ALTER most things in place
    compare_type=True,
)
with context.begin_transaction():
    context.run_migrations()
