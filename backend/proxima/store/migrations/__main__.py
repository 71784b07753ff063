"""`python -m proxima.store.migrations -m MESSAGE --db SCRATCH.db`: autogenerate a new
revision against the table models (review it, then make its create_table calls
`create_table_if_missing` so unversioned databases are adopted)."""

from __future__ import annotations

import argparse

from alembic import command

from proxima.store.base import make_engine
from proxima.store.migrations import config, upgrade


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m proxima.store.migrations")
    parser.add_argument("-m", "--message", required=True)
    parser.add_argument("--db", required=True, help="a scratch SQLite file (brought to head)")
    args = parser.parse_args()
    engine = make_engine(args.db)
    upgrade(engine)
    cfg = config()
    with engine.begin() as conn:
        cfg.attributes["connection"] = conn
        command.revision(cfg, message=args.message, autogenerate=True)


if __name__ == "__main__":
    main()
