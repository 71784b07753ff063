"""Schema migrations: an old database keeps its rows, the newest schema matches the
table models of every store module, and databases made before versioning are adopted."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from api_helpers import laser_clip

from proxima.ingest import read_landmark_csv
from proxima.store import migrations
from proxima.store.base import Base, make_engine, make_sessionmaker
from proxima.store.samples import Sample, add_sample, review_sample
from proxima.store.users import User, authenticate, create_user


def _schema_diff(engine) -> list:  # type: ignore[no-untyped-def]
    with engine.connect() as conn:
        ctx = MigrationContext.configure(conn, opts={"compare_type": True})
        return compare_metadata(ctx, migrations.target_metadata())


def test_head_matches_every_table_model(tmp_path: Path) -> None:
    engine = make_engine(tmp_path / "new.db")
    migrations.upgrade(engine)
    assert migrations.current_revision(engine) == migrations.head_revision()
    assert _schema_diff(engine) == []
    tables = set(migrations.target_metadata().tables)
    assert {
        "users",
        "user_sessions",
        "samples",
        "command_log",
        "training_runs",
        "training_rounds",
        "training_client_results",
        "audit_log",
    } <= tables
    migrations.upgrade(engine)  # idempotent


def test_old_database_keeps_its_rows(tmp_path: Path) -> None:
    path = tmp_path / "old.db"
    engine = make_engine(path)
    migrations.upgrade(engine, "0001")  # the first released schema
    assert migrations.current_revision(engine) == "0001"
    track = read_landmark_csv(laser_clip("land_f"))
    with make_sessionmaker(engine)() as db:
        create_user(db, "chief", "correct-horse-battery", "supervisor")
        s = add_sample(
            db,
            stream="front",
            drone="main",
            xyz=track.xyz[:45],
            visibility=track.visibility[:45],
            times=np.arange(45) / 30.0,
            created_by="chief",
        )
        review_sample(db, s, status="kept", label="land", by="chief")
    engine.dispose()
    before = sqlite3.connect(path).execute("select count(*) from samples").fetchone()

    engine = make_engine(path)
    migrations.upgrade(engine)
    assert migrations.current_revision(engine) == migrations.head_revision()
    assert _schema_diff(engine) == []
    with make_sessionmaker(engine)() as db:
        assert authenticate(db, "chief", "correct-horse-battery") is not None
        rows = db.query(Sample).all()
        assert (len(rows),) == before
        arr = rows[0].arrays()
        np.testing.assert_array_equal(arr.xyz, track.xyz[:45].astype(np.float32))
        assert rows[0].label == "land" and rows[0].status == "kept"


def test_unversioned_database_is_adopted(tmp_path: Path) -> None:
    # Tables made by create_all (as a subsystem's own code may do) before migrations ran.
    engine = make_engine(tmp_path / "legacy.db")
    Base.metadata.create_all(engine, tables=[User.__table__])
    with make_sessionmaker(engine)() as db:
        create_user(db, "chief", "correct-horse-battery", "supervisor")
    migrations.upgrade(engine)
    assert _schema_diff(engine) == []
    with make_sessionmaker(engine)() as db:
        assert db.query(User).count() == 1
