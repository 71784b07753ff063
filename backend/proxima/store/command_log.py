"""The durable command log: every drone command, the gesture that caused it, what was
sent, the vehicle's acknowledgement and the outcome. One row per command; the drone
controller writes it (status "pending") before anything is sent and updates it as the
answer and the outcome arrive, so a crash leaves a row that says how far the command got."""

from __future__ import annotations

import json
import math
import threading
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from sqlalchemy import DateTime, Engine, Float, Integer, String, Text, select
from sqlalchemy.orm import Mapped, mapped_column

from proxima.store.base import Base, create_tables, make_engine, make_sessionmaker


def utcnow() -> datetime:
    return datetime.now(UTC)


class CommandRecord(Base):
    """One command to one drone."""

    __tablename__ = "command_log"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utcnow)
    drone: Mapped[str] = mapped_column(String(64), index=True)
    source: Mapped[str] = mapped_column(String(16))  # gesture, api, cli, watchdog
    command: Mapped[str] = mapped_column(String(32))  # gesture name or e.g. emergency_stop
    stream: Mapped[str] = mapped_column(String(64), default="")
    gesture_t: Mapped[float | None] = mapped_column(Float, nullable=True)  # stream time
    confidence: Mapped[float | None] = mapped_column(Float, nullable=True)
    action: Mapped[str] = mapped_column(String(32), default="")
    status: Mapped[str] = mapped_column(String(16), default="pending")
    reason: Mapped[str] = mapped_column(Text, default="")
    sent: Mapped[str | None] = mapped_column(Text, nullable=True)  # JSON of what was sent
    ack: Mapped[str | None] = mapped_column(String(32), nullable=True)
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    ack_latency_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    outcome: Mapped[str | None] = mapped_column(String(32), nullable=True)
    sent_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    acked_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    completed_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for column in self.__table__.columns:
            value = getattr(self, column.name)
            if isinstance(value, datetime):  # SQLite drops the zone; every time is UTC
                value = (value if value.tzinfo else value.replace(tzinfo=UTC)).isoformat()
            elif column.name == "sent" and value:
                value = json.loads(value)
            out[column.name] = value
        return out


_FIELDS = {c.name for c in CommandRecord.__table__.columns} - {"id"}


class CommandLog:
    """Writes and reads the command log; safe to share between threads."""

    def __init__(self, engine_or_path: Engine | str | Path) -> None:
        self.engine = (
            engine_or_path if isinstance(engine_or_path, Engine) else make_engine(engine_or_path)
        )
        create_tables(self.engine, [Base.metadata.tables[CommandRecord.__tablename__]])
        self._session = make_sessionmaker(self.engine)
        self._lock = threading.Lock()

    def add(self, **fields: Any) -> int:
        """Insert a row; returns its id. `sent` may be a dict (stored as JSON)."""
        row = CommandRecord(**self._clean(fields))
        with self._lock, self._session() as session, session.begin():
            session.add(row)
            session.flush()
            return row.id

    def update(self, row_id: int, **fields: Any) -> None:
        """Change fields of an existing row (ack, outcome, timestamps)."""
        clean = self._clean(fields)
        with self._lock, self._session() as session, session.begin():
            row = session.get(CommandRecord, row_id)
            if row is None:
                raise KeyError(f"command log has no row {row_id}")
            for key, value in clean.items():
                setattr(row, key, value)

    def get(self, row_id: int) -> dict[str, Any] | None:
        with self._session() as session:
            row = session.get(CommandRecord, row_id)
            return None if row is None else row.to_dict()

    def recent(
        self, limit: int = 100, drone: str | None = None, status: str | None = None
    ) -> list[dict[str, Any]]:
        """The newest rows first, of one drone and one status when given."""
        query = select(CommandRecord).order_by(CommandRecord.id.desc()).limit(limit)
        if drone is not None:
            query = query.where(CommandRecord.drone == drone)
        if status is not None:
            query = query.where(CommandRecord.status == status)
        with self._session() as session:
            return [row.to_dict() for row in session.scalars(query)]

    @staticmethod
    def _clean(fields: dict[str, Any]) -> dict[str, Any]:
        unknown = set(fields) - _FIELDS
        if unknown:
            raise TypeError(f"command log has no field(s) {sorted(unknown)}")
        out = dict(fields)
        if isinstance(out.get("sent"), dict | list):
            out["sent"] = json.dumps(_finite(out["sent"]), default=str, allow_nan=False)
        return out


def _finite(value: Any) -> Any:
    """JSON without NaN/inf (MAVLink uses NaN for "unset"; browsers cannot parse it)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value
