"""The decision path for one controlled drone, fed by every stream that watches the
operator: arbiter -> debounce -> arming -> commands.

`CommandController` is plain, single-threaded and deterministic: it consumes
`StreamUpdate`s in stream-time order (the engine's merge guarantees the order) and returns
the events they cause. Only the driving stream's actions count, and only while it sees
the operator (at least partly); every command goes to the controlled drone, whichever
stream saw the gesture.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from proxima.control.arbiter import Handover, PriorityArbiter, Sight
from proxima.control.arming import Arming
from proxima.control.config import ControlSettings
from proxima.control.gate import CommandGate
from proxima.events import ArmingEvent, CommandEvent, HandoverEvent
from proxima.types import Event

SAFE_COMMAND = "hover"  # sent when armed control loses the operator everywhere


@dataclass(frozen=True, eq=False)
class WindowEvidence:
    """One classified window as cross-stream fusion reads it (`proxima.engine.fusion`):
    the classifier's `probs` over `labels`, its calibrated log-probabilities `log_probs`,
    the stream's `weight` (how well the window sees the operator's arms, 0 = nothing),
    the gestures the hand evidence `withheld`, and whether the stream's own filter was
    emptied since its previous window (`restarted`)."""

    labels: tuple[str, ...]
    probs: np.ndarray
    log_probs: np.ndarray
    weight: float
    withheld: tuple[str, ...] = ()
    restarted: bool = False


@dataclass(frozen=True)
class StreamUpdate:
    """What one stream knows at stream time `t`: how it sees the operator and, on frames
    where it classified a window, its filtered action ("" = nothing confident; None = no
    new decision in this frame). `ended` marks the stream's last update. `evidence` is
    the classified window for fusion across streams (None when fusion is off)."""

    stream: str
    t: float
    sight: Sight
    action: str | None = None
    confidence: float = 0.0
    ended: bool = False
    evidence: WindowEvidence | None = None


class CommandController:
    """Arbitrates the streams, debounces, applies arming and emits the events."""

    def __init__(
        self,
        streams: Sequence[str],
        drone: str,
        settings: ControlSettings | None = None,
    ) -> None:
        self.settings = settings or ControlSettings()
        s = self.settings
        self.drone = drone
        self.arbiter = PriorityArbiter(streams, hold_s=s.hold_s, regain_s=s.regain_s)
        self.gate = CommandGate(
            debounce_s=s.debounce_s,
            confirm=s.confirm,
            release_s=s.release_s,
            repeat_s=s.repeat_s,
            confirm_by_command=s.confirm_by_command,
        )
        self.arming = Arming(idle_disarm_s=s.idle_disarm_s)
        self.now = float("-inf")

    @property
    def active(self) -> str:
        """The stream that drives the decisions now ("" when none sees the operator)."""
        return self.arbiter.active

    def process(self, update: StreamUpdate) -> list[Event]:
        """Consume one update; return the handover, arming and command events it caused.

        Raises:
            ValueError: the update names a stream the controller does not know.
        """
        t = max(self.now, update.t)  # a late update from a stalled live stream
        self.now = t
        events: list[Event] = []
        if update.ended:
            handover = self.arbiter.end(update.stream, t)
        else:
            handover = self.arbiter.observe(update.stream, t, update.sight)
        if handover is not None:
            events.extend(self._on_handover(handover))
        if self.arming.check_idle(t):
            events.append(ArmingEvent(t=t, stream=self.active, armed=False, reason="idle"))
        if (
            update.action is not None
            and not update.ended
            and update.sight >= Sight.PARTIAL
            and update.stream == self.active
        ):
            command = self.gate.step(t, update.action, self.arming.allows)
            if command is not None:
                events.extend(self._send(t, update.stream, command))
        return events

    def _send(self, t: float, stream: str, command: str) -> list[Event]:
        events: list[Event] = [CommandEvent(t=t, stream=stream, command=command, drone=self.drone)]
        change = self.arming.on_command(t, command)
        if change is not None:
            armed, reason = change
            events.append(ArmingEvent(t=t, stream=stream, armed=armed, reason=reason))
        return events

    def _on_handover(self, h: Handover) -> list[Event]:
        events: list[Event] = [
            HandoverEvent(
                t=h.t,
                stream=h.to_stream,
                from_stream=h.from_stream,
                to_stream=h.to_stream,
                reason=h.reason,
            )
        ]
        self.gate.restart_streak()
        if not h.to_stream:
            if self.arming.armed:
                # Nobody sees the operator: hold position, never guess.
                events.append(
                    CommandEvent(t=h.t, stream="", command=SAFE_COMMAND, drone=self.drone)
                )
                self.arming.disarm()
                events.append(ArmingEvent(t=h.t, stream="", armed=False, reason=h.reason))
        elif h.from_stream and self.settings.rearm_on_handover and self.arming.disarm():
            events.append(ArmingEvent(t=h.t, stream=h.to_stream, armed=False, reason="handover"))
        return events
