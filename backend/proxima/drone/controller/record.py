"""What the controller writes down about each command: its command-log row and its
`CommandResultEvent`s.

A row is written (status "pending") before anything is sent (`begin`), completed when
the vehicle answered or the command was refused (`finish`), and given its outcome once
the vehicle got there or not (`outcome`), so a crash leaves a row that says how far the
command got. Every step is also published on the bus.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING, Any

from proxima.drone.events import CommandResultEvent, DroneAlarmEvent
from proxima.drone.link import CommandResult
from proxima.events import CommandEvent
from proxima.store.command_log import CommandLog
from proxima.types import Event

if TYPE_CHECKING:
    from proxima.drone.controller.outcomes import TrackedCommand

# Statuses that are also the command's final outcome.
_FINAL = ("refused", "ignored", "failed")


@dataclass(frozen=True)
class ControlOutcome:
    """What the controller did with one command. `status`: "sent" (the vehicle
    accepted it), "failed" (sent, the vehicle refused or never answered), "refused"
    (safety or mapping stopped it: nothing sent), "ignored" (nothing to do), "done"
    (handled without a message, e.g. arming gesture control), "pending" (an emergency
    stop waiting for its confirmation)."""

    drone: str
    command: str
    action: str
    status: str
    reason: str = ""
    result: CommandResult | None = None
    log_id: int | None = None
    target: tuple[float, float, float] | None = None

    @property
    def sent(self) -> bool:
        return self.status in ("sent", "failed")


@dataclass
class CommandContext:
    """Where one command came from (the identity of its log row), and its row once
    written."""

    drone: str
    source: str  # gesture, api, cli, watchdog
    command: str
    stream: str = ""
    gesture_t: float | None = None
    confidence: float | None = None
    log_id: int | None = None
    started: datetime | None = field(default=None, compare=False)

    def row(self) -> dict[str, Any]:
        return {
            "drone": self.drone,
            "source": self.source,
            "command": self.command,
            "stream": self.stream,
            "gesture_t": self.gesture_t,
            "confidence": self.confidence,
        }


class CommandRecorder:
    """Writes the command log (if any) and publishes results and alarms."""

    def __init__(self, log: CommandLog | None, publish: Callable[[Event], None]) -> None:
        self.log = log
        self.publish = publish

    def begin(self, ctx: CommandContext, action: str) -> None:
        """Write the command's row (status "pending") before anything is sent."""
        if self.log is not None:
            ctx.log_id = self.log.add(**ctx.row(), action=action, status="pending")
        ctx.started = datetime.now(UTC)

    def finish(
        self,
        event: CommandEvent,
        ctx: CommandContext,
        action: str,
        status: str,
        reason: str,
        *,
        result: CommandResult | None = None,
        outcome: str | None = None,
        target: tuple[float, float, float] | None = None,
    ) -> ControlOutcome:
        """Complete the row with what happened and publish it; the ControlOutcome."""
        if outcome is None and status in _FINAL:
            outcome = status
        log_id = ctx.log_id
        if self.log is not None:
            now = datetime.now(UTC)
            fields: dict[str, Any] = ctx.row()
            fields.update(action=action, status=status, reason=reason, outcome=outcome)
            if result is not None:
                sent_at = ctx.started or now
                if result.latency_s is not None:
                    sent_at = now - timedelta(seconds=result.latency_s)
                fields.update(
                    sent=result.sent or None,
                    ack=result.ack,
                    attempts=result.attempts,
                    sent_at=sent_at if status in ("sent", "failed") else None,
                    acked_at=now if result.confirmed else None,
                )
                if result.latency_s is not None:
                    fields["ack_latency_ms"] = result.latency_s * 1000.0
            if outcome is not None and outcome not in _FINAL:
                fields["completed_at"] = now
            if log_id is None:
                log_id = self.log.add(**fields)
            else:
                self.log.update(log_id, **fields)
        out = ControlOutcome(
            event.drone, event.command, action, status, reason, result, log_id, target
        )
        self.publish(
            CommandResultEvent(
                t=event.t,
                stream=event.stream,
                drone=event.drone,
                command=event.command,
                action=action,
                status=status,
                ack=result.ack if result else "",
                outcome=outcome or "",
                reason=reason,
                gesture_t=event.t,
                latency_s=result.latency_s if result else None,
                log_id=log_id,
            )
        )
        return out

    def outcome(self, drone: str, item: TrackedCommand, outcome: str) -> None:
        """A tracked command's outcome: into its row, and published (status "done")."""
        if self.log is not None and item.log_id is not None:
            self.log.update(item.log_id, outcome=outcome, completed_at=datetime.now(UTC))
        self.publish(
            CommandResultEvent(
                t=item.gesture_t,
                stream=item.stream,
                drone=drone,
                command=item.command,
                action=item.action,
                status="done",
                outcome=outcome,
                gesture_t=item.gesture_t,
                log_id=item.log_id,
            )
        )

    def alarm(self, drone: str, kind: str, message: str) -> None:
        """Publish an alarm. A drone's alarm is also its stream's (the console shows it
        on that tile); drone "" is the controller itself."""
        self.publish(
            DroneAlarmEvent(t=time.time(), stream=drone, drone=drone, kind=kind, message=message)
        )
