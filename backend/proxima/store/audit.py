"""The audit log: who did what to the system through the console, and when.

One row per supervisor action (stopping a drone, promoting a model, starting or
cancelling a run, keeping or deleting a sample, managing users) and per login event
(logins, failed and throttled attempts, logouts, password changes), with the outcome and
the client address. Rows are only ever added; `GET /api/audit` reads them.

Action names are `area.verb` (`AuditAction`); a new supervisor action adds its name here
and records itself through `proxima.api.audit.Audit`.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from sqlalchemy import Engine, Float, Integer, String, Text, select
from sqlalchemy.orm import Mapped, mapped_column

from proxima.store.base import Base, make_sessionmaker

MAX_LIMIT = 500


class AuditAction(StrEnum):
    LOGIN = "auth.login"
    LOGIN_FAILED = "auth.login_failed"
    LOGIN_THROTTLED = "auth.login_throttled"
    LOGOUT = "auth.logout"
    PASSWORD = "auth.password"
    USER_CREATE = "user.create"
    USER_DISABLE = "user.disable"
    DRONE_STOP_REQUEST = "drone.stop_request"
    DRONE_STOP = "drone.stop"
    DRONE_RESUME = "drone.resume"
    MODEL_PROMOTE = "model.promote"
    MODEL_ROLLBACK = "model.rollback"
    MODEL_PROMOTE_STREAM = "model.promote_stream"  # for one stream (a calibration)
    CALIBRATION_TRAIN = "calibration.train"
    RUN_START = "training.start"
    RUN_CANCEL = "training.cancel"
    RECORDING_START = "sample.record"
    SAMPLE_KEEP = "sample.keep"
    SAMPLE_DELETE = "sample.delete"
    ALARM_RAISE = "alarm.raise"  # by "console": a derived alarm (api/alarms.py)
    ALARM_CLEAR = "alarm.clear"


class AuditOutcome(StrEnum):
    OK = "ok"  # done
    REFUSED = "refused"  # the console or the subsystem said no (bad id, conflict, wrong password)
    FAILED = "failed"  # tried, and the subsystem failed


class AuditEntry(Base):
    __tablename__ = "audit_log"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    ts: Mapped[float] = mapped_column(Float, nullable=False, index=True)
    actor: Mapped[str] = mapped_column(String(64), nullable=False, index=True)
    action: Mapped[str] = mapped_column(String(64), nullable=False, index=True)
    target: Mapped[str] = mapped_column(String(256), nullable=False)
    outcome: Mapped[str] = mapped_column(String(16), nullable=False)
    client: Mapped[str] = mapped_column(String(64), nullable=False)
    detail: Mapped[str] = mapped_column(Text, nullable=False)  # a JSON object


@dataclass(frozen=True)
class AuditRecord:
    """One row of the audit log, as read back."""

    id: int
    ts: float
    actor: str
    action: str
    target: str
    outcome: str
    client: str
    detail: dict[str, Any]


class AuditLog:
    """The audit log in one database; safe to share between threads."""

    def __init__(self, engine: Engine) -> None:
        self._sessions = make_sessionmaker(engine)

    def record(
        self,
        *,
        actor: str,
        action: AuditAction | str,
        target: str = "",
        outcome: AuditOutcome | str = AuditOutcome.OK,
        client: str = "",
        detail: dict[str, Any] | None = None,
        ts: float | None = None,
    ) -> int:
        """Append one row (committed); returns its id. Long fields are cut to their
        column's length so a hostile user name cannot make the write fail."""
        row = AuditEntry(
            ts=time.time() if ts is None else ts,
            actor=actor[:64],
            action=str(action)[:64],
            target=target[:256],
            outcome=str(AuditOutcome(outcome)),
            client=client[:64],
            detail=json.dumps(detail or {}, default=str, sort_keys=True),
        )
        with self._sessions() as db:
            db.add(row)
            db.commit()
            return row.id

    def query(
        self,
        *,
        actor: str | None = None,
        action: str | None = None,
        target: str | None = None,
        outcome: str | None = None,
        since: float | None = None,
        until: float | None = None,
        before_id: int | None = None,
        limit: int = 100,
    ) -> list[AuditRecord]:
        """Rows newest first. `action` is a name (`drone.stop`) or an area (`drone`,
        every action of it); `since`/`until` bound the time (unix seconds, inclusive);
        `before_id` pages: pass the smallest id of the previous page.

        Raises:
            ValueError: `limit` outside 1..MAX_LIMIT.
        """
        if not 1 <= limit <= MAX_LIMIT:
            raise ValueError(f"limit must be 1..{MAX_LIMIT}, got {limit}")
        q = select(AuditEntry).order_by(AuditEntry.id.desc()).limit(limit)
        if actor is not None:
            q = q.where(AuditEntry.actor == actor)
        if action is not None:
            if "." in action:
                q = q.where(AuditEntry.action == action)
            else:
                q = q.where(AuditEntry.action.startswith(f"{action}.", autoescape=True))
        if target is not None:
            q = q.where(AuditEntry.target == target)
        if outcome is not None:
            q = q.where(AuditEntry.outcome == outcome)
        if since is not None:
            q = q.where(AuditEntry.ts >= since)
        if until is not None:
            q = q.where(AuditEntry.ts <= until)
        if before_id is not None:
            q = q.where(AuditEntry.id < before_id)
        with self._sessions() as db:
            return [_record(row) for row in db.scalars(q)]


def _record(row: AuditEntry) -> AuditRecord:
    try:
        detail = json.loads(row.detail)
    except json.JSONDecodeError:
        detail = {"raw": row.detail}
    return AuditRecord(
        id=row.id,
        ts=row.ts,
        actor=row.actor,
        action=row.action,
        target=row.target,
        outcome=row.outcome,
        client=row.client,
        detail=detail if isinstance(detail, dict) else {"value": detail},
    )
