"""Federated training runs, their rounds and every drone's result in every round.

The ServerApp writes rounds and client results as they happen (in the deployment
engine it runs in its own process, so the database is how the console hears of them);
the run coordinator owns the run row (status, checkpoint, promotion) and turns new rows
into bus events for the console's live curves.
"""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, Float, ForeignKey, Integer, String, Text, delete, select
from sqlalchemy.orm import Mapped, mapped_column

from proxima.store.base import Base, create_tables, make_engine, make_sessionmaker

RUN_STATUSES = ("pending", "waiting", "running", "completed", "failed", "stopped")
FINISHED = ("completed", "failed", "stopped")


class TrainingRun(Base):
    """One federated run."""

    __tablename__ = "training_runs"

    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    created_at: Mapped[float] = mapped_column(Float, nullable=False)
    started_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    finished_at: Mapped[float | None] = mapped_column(Float, nullable=True)
    status: Mapped[str] = mapped_column(String(16), nullable=False, index=True)
    engine: Mapped[str] = mapped_column(String(16), nullable=False)  # simulation, deployment
    params: Mapped[str] = mapped_column(Text, nullable=False)  # JSON run config
    rounds_total: Mapped[int] = mapped_column(Integer, nullable=False)
    rounds_done: Mapped[int] = mapped_column(Integer, nullable=False, default=0)
    final_accuracy: Mapped[float | None] = mapped_column(Float, nullable=True)
    checkpoint: Mapped[str | None] = mapped_column(Text, nullable=True)
    model_card: Mapped[str | None] = mapped_column(Text, nullable=True)
    detail: Mapped[str] = mapped_column(Text, nullable=False, default="")
    started_by: Mapped[str] = mapped_column(String(64), nullable=False, default="")
    flwr_run_id: Mapped[str | None] = mapped_column(String(32), nullable=True)
    promoted_at: Mapped[float | None] = mapped_column(Float, nullable=True)


class TrainingRound(Base):
    """The global model after one round (round 0: the initial model)."""

    __tablename__ = "training_rounds"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[str] = mapped_column(
        String(64),
        ForeignKey("training_runs.id", ondelete="CASCADE"),
        nullable=False,
        index=True,
    )
    round: Mapped[int] = mapped_column(Integer, nullable=False)
    global_accuracy: Mapped[float | None] = mapped_column(Float, nullable=True)
    global_loss: Mapped[float | None] = mapped_column(Float, nullable=True)
    train_loss: Mapped[float | None] = mapped_column(Float, nullable=True)
    clients_ok: Mapped[int] = mapped_column(Integer, nullable=False, default=0)
    clients_failed: Mapped[int] = mapped_column(Integer, nullable=False, default=0)
    duration_s: Mapped[float] = mapped_column(Float, nullable=False, default=0.0)
    created_at: Mapped[float] = mapped_column(Float, nullable=False)


class TrainingClientResult(Base):
    """One drone's answer in one round: its metrics, or why it was left out."""

    __tablename__ = "training_client_results"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[str] = mapped_column(
        String(64),
        ForeignKey("training_runs.id", ondelete="CASCADE"),
        nullable=False,
        index=True,
    )
    round: Mapped[int] = mapped_column(Integer, nullable=False)
    client: Mapped[str] = mapped_column(String(64), nullable=False)
    phase: Mapped[str] = mapped_column(String(16), nullable=False)  # train, evaluate
    status: Mapped[str] = mapped_column(String(16), nullable=False)  # ok, failed, rejected
    loss: Mapped[float | None] = mapped_column(Float, nullable=True)
    accuracy: Mapped[float | None] = mapped_column(Float, nullable=True)
    train_loss: Mapped[float | None] = mapped_column(Float, nullable=True)
    samples: Mapped[int | None] = mapped_column(Integer, nullable=True)
    duration_s: Mapped[float | None] = mapped_column(Float, nullable=True)
    detail: Mapped[str] = mapped_column(Text, nullable=False, default="")
    created_at: Mapped[float] = mapped_column(Float, nullable=False)


def _num(value: Any) -> float | None:
    """A finite float, or None (SQLite and JSON have no NaN)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _row(obj: Base, skip: tuple[str, ...] = ()) -> dict[str, Any]:
    return {c.name: getattr(obj, c.name) for c in obj.__table__.columns if c.name not in skip}


class TrainingStore:
    """Reads and writes runs, rounds and client results; safe to share between threads
    and between processes (SQLite WAL)."""

    TABLES = (TrainingRun, TrainingRound, TrainingClientResult)

    def __init__(self, engine_or_path: Engine | str | Path) -> None:
        self.engine = (
            engine_or_path if isinstance(engine_or_path, Engine) else make_engine(engine_or_path)
        )
        tables = [Base.metadata.tables[t.__tablename__] for t in self.TABLES]
        create_tables(self.engine, tables)
        self._session = make_sessionmaker(self.engine)
        self._lock = threading.Lock()

    # runs ------------------------------------------------------------------------------

    def create_run(
        self,
        run_id: str,
        *,
        engine: str,
        params: dict[str, Any],
        rounds_total: int,
        started_by: str = "",
    ) -> None:
        with self._lock, self._session() as db:
            db.add(
                TrainingRun(
                    id=run_id,
                    created_at=time.time(),
                    status="pending",
                    engine=engine,
                    params=json.dumps(params, sort_keys=True),
                    rounds_total=rounds_total,
                    rounds_done=0,
                    detail="",
                    started_by=started_by,
                )
            )
            db.commit()

    def update_run(self, run_id: str, **fields: Any) -> None:
        """Set columns of a run (`params` may be a dict).

        Raises:
            KeyError: no such run; ValueError: an unknown column or status.
        """
        allowed = {c.name for c in TrainingRun.__table__.columns} - {"id"}
        bad = set(fields) - allowed
        if bad:
            raise ValueError(f"unknown training_runs column(s): {sorted(bad)}")
        if "status" in fields and fields["status"] not in RUN_STATUSES:
            raise ValueError(f"unknown run status {fields['status']!r}")
        if isinstance(fields.get("params"), dict):
            fields["params"] = json.dumps(fields["params"], sort_keys=True)
        if "final_accuracy" in fields:
            fields["final_accuracy"] = _num(fields["final_accuracy"])
        with self._lock, self._session() as db:
            run = db.get(TrainingRun, run_id)
            if run is None:
                raise KeyError(f"no training run {run_id!r}")
            for k, v in fields.items():
                setattr(run, k, v)
            db.commit()

    def run_row(self, run_id: str) -> dict[str, Any] | None:
        with self._session() as db:
            run = db.get(TrainingRun, run_id)
            return self._run_dict(run) if run else None

    @staticmethod
    def _run_dict(run: TrainingRun) -> dict[str, Any]:
        out = _row(run)
        out["params"] = json.loads(run.params)
        return out

    def list_runs(self) -> list[dict[str, Any]]:
        """Every run, newest first (without rounds)."""
        with self._session() as db:
            q = select(TrainingRun).order_by(TrainingRun.created_at.desc())
            return [self._run_dict(r) for r in db.scalars(q)]

    def delete_run(self, run_id: str) -> None:
        with self._lock, self._session() as db:
            for table in (TrainingClientResult, TrainingRound):
                db.execute(delete(table).where(table.run_id == run_id))
            db.execute(delete(TrainingRun).where(TrainingRun.id == run_id))
            db.commit()

    # rounds and client results ------------------------------------------------------------

    def add_client_result(
        self,
        run_id: str,
        server_round: int,
        client: str,
        *,
        phase: str,
        status: str,
        loss: float | None = None,
        accuracy: float | None = None,
        train_loss: float | None = None,
        samples: int | None = None,
        duration_s: float | None = None,
        detail: str = "",
    ) -> None:
        with self._lock, self._session() as db:
            db.add(
                TrainingClientResult(
                    run_id=run_id,
                    round=server_round,
                    client=client,
                    phase=phase,
                    status=status,
                    loss=_num(loss),
                    accuracy=_num(accuracy),
                    train_loss=_num(train_loss),
                    samples=samples,
                    duration_s=_num(duration_s),
                    detail=detail,
                    created_at=time.time(),
                )
            )
            db.commit()

    def add_round(
        self,
        run_id: str,
        server_round: int,
        *,
        global_accuracy: float | None,
        global_loss: float | None,
        train_loss: float | None = None,
        clients_ok: int = 0,
        clients_failed: int = 0,
        duration_s: float = 0.0,
    ) -> None:
        with self._lock, self._session() as db:
            db.add(
                TrainingRound(
                    run_id=run_id,
                    round=server_round,
                    global_accuracy=_num(global_accuracy),
                    global_loss=_num(global_loss),
                    train_loss=_num(train_loss),
                    clients_ok=clients_ok,
                    clients_failed=clients_failed,
                    duration_s=float(duration_s),
                    created_at=time.time(),
                )
            )
            run = db.get(TrainingRun, run_id)
            if run is not None:
                run.rounds_done = max(run.rounds_done, server_round)
                run.final_accuracy = _num(global_accuracy)
            db.commit()

    def rounds(self, run_id: str, after: int = -1) -> list[dict[str, Any]]:
        """Rounds of a run later than `after`, each with its `clients` (list of dicts,
        train phase first) in round order."""
        with self._session() as db:
            rounds = list(
                db.scalars(
                    select(TrainingRound)
                    .where(TrainingRound.run_id == run_id, TrainingRound.round > after)
                    .order_by(TrainingRound.round)
                )
            )
            results = list(
                db.scalars(
                    select(TrainingClientResult)
                    .where(
                        TrainingClientResult.run_id == run_id, TrainingClientResult.round > after
                    )
                    .order_by(TrainingClientResult.id)
                )
            )
        by_round: dict[int, list[dict[str, Any]]] = {}
        for r in results:
            d = _row(r, ("id", "run_id", "round"))
            d["drone"] = d["client"]
            by_round.setdefault(r.round, []).append(d)
        out = []
        for rnd in rounds:
            d = _row(rnd, ("id", "run_id"))
            d["clients"] = by_round.get(rnd.round, [])
            out.append(d)
        return out

    def get_run(self, run_id: str) -> dict[str, Any] | None:
        """One run with all its rounds and per-client results, or None."""
        run = self.run_row(run_id)
        if run is None:
            return None
        run["rounds"] = self.rounds(run_id)
        return run
