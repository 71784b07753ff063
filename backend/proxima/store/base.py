"""The declarative base every table module registers on, and the engine factory.

Each subsystem keeps its tables in its own module here (command_log.py, training.py,
samples.py, users.py); all of them share one SQLite file so the console can join them.
"""

from __future__ import annotations

from pathlib import Path

from sqlalchemy import Engine, Table, create_engine, event
from sqlalchemy.engine.interfaces import DBAPIConnection
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import DeclarativeBase, sessionmaker


class Base(DeclarativeBase):
    pass


def make_engine(url_or_path: str | Path) -> Engine:
    """An engine for a SQLite file path (or any SQLAlchemy URL), with WAL and foreign keys
    on so that several threads (engine, link, API) can write without 'database locked'."""
    url = str(url_or_path)
    if "://" not in url:
        Path(url).parent.mkdir(parents=True, exist_ok=True)
        url = f"sqlite:///{url}"
    engine = create_engine(url, connect_args={"check_same_thread": False}, future=True)
    if engine.dialect.name == "sqlite":

        @event.listens_for(engine, "connect")
        def _pragmas(dbapi_conn: DBAPIConnection, _record: object) -> None:
            cur = dbapi_conn.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA foreign_keys=ON")
            cur.execute("PRAGMA busy_timeout=5000")
            cur.close()

    return engine


def create_tables(engine: Engine, tables: list[Table]) -> None:
    """Create the tables that do not exist yet. Two processes opening one new file at
    once (e.g. two `proxima fl simulate` runs) can both see a table missing and both
    create it; the loser's "already exists" means that table is there, so look again
    (at most once per table: each retry finds one more of them made)."""
    for attempt in range(len(tables) + 1):
        try:
            Base.metadata.create_all(engine, tables=tables)
            return
        except OperationalError as exc:
            if "already exists" not in str(exc) or attempt == len(tables):
                raise


def make_sessionmaker(engine: Engine) -> sessionmaker:
    return sessionmaker(engine, expire_on_commit=False, future=True)
