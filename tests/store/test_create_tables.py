"""Opening a new database file from two processes at once."""

from __future__ import annotations

from pathlib import Path

from sqlalchemy import event, inspect

from proxima.store.base import Base, make_engine
from proxima.store.training import TrainingRun, TrainingStore


def test_a_table_another_process_made_meanwhile_is_not_an_error(tmp_path: Path) -> None:
    """The race two `proxima fl simulate` runs hit on a fresh file: both look, both find
    training_runs missing, one creates it first. Here a second engine creates the table
    between this store's look and its CREATE (SQLAlchemy's before_create hook), as the
    other process did; the store opens and works."""
    path = tmp_path / "race.db"
    table = Base.metadata.tables[TrainingRun.__tablename__]
    other = make_engine(path)

    made: list[bool] = []

    def meanwhile(target: object, connection: object, **_: object) -> None:
        if not made:  # once; this hook fires for the other engine's CREATE too
            made.append(True)
            Base.metadata.create_all(other, tables=[table])

    event.listen(table, "before_create", meanwhile)
    try:
        store = TrainingStore(path)
    finally:
        event.remove(table, "before_create", meanwhile)
    store.create_run("r1", engine="simulation", params={}, rounds_total=1, started_by="test")
    assert made and inspect(other).has_table(table.name)
    assert [r["id"] for r in store.list_runs()] == ["r1"]
