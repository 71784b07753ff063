"""COMMAND_LONG bookkeeping: one command of each kind in flight, its COMMAND_ACK, retries.

A COMMAND_ACK names only the command, not which send it answers, so commands of one
kind wait in line and only the first is on the wire. It is resent (with an increasing
`confirmation`) each time its per-attempt timeout passes, up to its retries; an
IN_PROGRESS answer extends the wait. Used only by the link's owner thread.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass

from proxima.drone.link import CommandResult
from proxima.drone.mavlink.protocol import RESULTS, command_name, mav


@dataclass
class PendingCommand:
    """One COMMAND_LONG a caller waits for through `future`."""

    action: str
    command: int
    params: list[float]
    future: Future[CommandResult]
    timeout: float
    retries: int
    attempts: int = 0
    first_sent: float = 0.0
    deadline: float = 0.0

    def sent(self) -> dict:
        """What was sent, as CommandResult.sent and the command log record it."""
        return {"msg": "COMMAND_LONG", "command": command_name(self.command), "params": self.params}


class CommandBook:
    """The commands waiting for their COMMAND_ACK. `transmit(p)` puts one attempt on the
    wire (its `attempts` is the confirmation number) and says whether it could."""

    def __init__(
        self, transmit: Callable[[PendingCommand], bool], in_progress_timeout_s: float
    ) -> None:
        self._transmit = transmit
        self.in_progress_timeout_s = in_progress_timeout_s
        self._lines: dict[int, list[PendingCommand]] = {}

    def add(self, p: PendingCommand, now: float) -> None:
        """Queue `p` behind any command of its kind; send it if it is the first."""
        line = self._lines.setdefault(p.command, [])
        line.append(p)
        if len(line) == 1:
            self._send(p, now)

    def on_ack(self, command: int, result: int, now: float) -> None:
        """A COMMAND_ACK for `command` answers the first of its line."""
        line = self._lines.get(command)
        if not line:
            return
        p = line[0]
        name = RESULTS.get(result, f"result_{result}")
        if result == mav.MAV_RESULT_IN_PROGRESS:
            p.deadline = now + self.in_progress_timeout_s
            return
        ok = result == mav.MAV_RESULT_ACCEPTED
        self._resolve(
            p,
            CommandResult(p.action, name, ok, p.attempts, now - p.first_sent, True, p.sent()),
            now,
        )

    def check(self, now: float) -> None:
        """Resend what timed out, give up on what ran out of retries."""
        for line in list(self._lines.values()):
            p = line[0]
            if now < p.deadline:
                continue
            if p.attempts <= p.retries:
                self._send(p, now)
            else:
                self._resolve(
                    p,
                    CommandResult(
                        p.action,
                        "timeout",
                        False,
                        p.attempts,
                        None,
                        False,
                        p.sent(),
                        f"no COMMAND_ACK after {p.attempts} attempts",
                    ),
                    now,
                )

    def next_deadline(self, now: float) -> float:
        """When `check` next has something to do (a second from now if nothing waits)."""
        deadlines = [line[0].deadline for line in self._lines.values() if line]
        return min(deadlines, default=now + 1.0)

    def fail_all(self, ack: str, detail: str) -> None:
        """Answer every waiting command with `ack` (the link was lost or closed)."""
        for line in self._lines.values():
            for p in line:
                if not p.future.done():
                    p.future.set_result(
                        CommandResult(
                            p.action, ack, False, p.attempts, sent=p.sent(), detail=detail
                        )
                    )
        self._lines.clear()

    def _send(self, p: PendingCommand, now: float) -> None:
        first = p.attempts == 0
        if not self._transmit(p):
            return
        if first:
            p.first_sent = now
        p.attempts += 1
        p.deadline = now + p.timeout

    def _resolve(self, p: PendingCommand, result: CommandResult, now: float) -> None:
        line = self._lines.get(p.command, [])
        if line and line[0] is p:
            line.pop(0)
        if not p.future.done():
            p.future.set_result(result)
        if line:
            self._send(line[0], now)
        else:
            self._lines.pop(p.command, None)
