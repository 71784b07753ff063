"""Fixtures of the federated tests: a real console sample store with a good and a corrupt
sample for the front drone (the fast run config is in fl_helpers.py)."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest


@pytest.fixture(scope="session")
def sample_store(tmp_path_factory, laser_clips) -> tuple[Path, int, int]:
    """A sample store (the console's real tables) with two kept samples for drone
    `front`: a good 90-frame `land` sequence and one whose landmark bytes are corrupt.
    Returns (db path, good sample id, corrupt sample id)."""
    from proxima.store.base import Base, make_engine, make_sessionmaker
    from proxima.store.samples import Sample, add_sample, review_sample

    path = tmp_path_factory.mktemp("samples") / "console.db"
    engine = make_engine(path)
    Base.metadata.create_all(engine, tables=[Sample.__table__])
    clip = next(c for c in laser_clips if c.gesture == "land" and c.view == "f")
    ids = []
    with make_sessionmaker(engine)() as db:
        for _ in range(2):
            s = add_sample(db, stream="front", drone="front", xyz=clip.xyz[:90],
                           visibility=clip.visibility[:90], times=np.arange(90) / 30.0,
                           created_by="chief")  # fmt: skip
            review_sample(db, s, status="kept", label="land", by="chief")
            ids.append(s.id)
    engine.dispose()
    with sqlite3.connect(path) as conn:  # damage the second one on disk
        conn.execute("update samples set xyz = ? where id = ?", (b"\x00\x01garbage", ids[1]))
    return path, ids[0], ids[1]
