"""The console's live picture, reduced from bus events in this one place: the newest state
of every stream (`StreamLive`), which stream drives, each drone's newest telemetry, and
the commands decided since start.

A browser gets it whole in `hello` when it connects and then, for a stream, the new
`StreamLive` each time an event changes it (the hub's `stream_live` message), so the
browser keeps no copy of this reducer; `GET /api/streams`, `/drones` and
`/commands/live` return the same values.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Literal

from proxima.drone.events import DroneStateEvent
from proxima.events import (
    ActionEvent,
    ArmingEvent,
    CommandEvent,
    EventBus,
    GestureEvent,
    HandoverEvent,
    PoseEvent,
    StreamEvent,
)
from proxima.types import Event

# Event types that browsers get only through `StreamLive` (the hub does not forward them).
STATE_ONLY_TYPES = frozenset(
    cls.type for cls in (GestureEvent, ActionEvent, ArmingEvent, StreamEvent, HandoverEvent)
)


@dataclass(frozen=True)
class StreamLive:
    """The newest recognition state of one stream (what its tile on the Live page shows)."""

    state: str = ""  # StreamEvent.state: connecting, live, stalled, reconnecting, ended
    state_detail: str = ""
    sight: str | None = None  # PoseEvent.sight of the newest pose; None before the first
    pose_t: float | None = None  # stream time of the newest pose
    gesture: str = ""  # GestureEvent: the newest raw classification
    gesture_confidence: float = 0.0
    withheld: tuple[str, ...] = ()  # gestures that may not be the action (hand unseen, arm down)
    action: str = ""  # ActionEvent: the filtered decision, "" below the threshold
    action_confidence: float = 0.0
    armed: bool = False  # ArmingEvent
    arming_reason: str = ""


@dataclass(frozen=True, kw_only=True)
class StreamLiveMessage:
    """The hub's message when a stream's state changed: all of it (newest wins per
    stream) and whether the stream drives the decisions now."""

    stream: str
    driving: bool
    live: StreamLive
    # The newest handover's reason (operator_acquired, higher_priority_sees_operator,
    # operator_lost, ...): why the driving stream drives, or why none does.
    handover_reason: str = ""
    type: Literal["stream_live"] = "stream_live"


@dataclass(frozen=True, kw_only=True)
class LiveCommand:
    """A command decided on the bus: a `CommandEvent`'s fields and `ts`, the wall time
    the console saw it (so an entry reads like the hub's `command` message)."""

    t: float
    stream: str
    command: str
    drone: str
    ts: float
    type: Literal["command"] = "command"


class LiveState:
    """A bus listener that keeps the latest per-stream and per-drone values; cheap enough
    to run on the publisher's thread."""

    def __init__(self, bus: EventBus, command_history: int = 200) -> None:
        self._lock = threading.Lock()
        self._streams: dict[str, StreamLive] = {}
        self._drones: dict[str, DroneStateEvent] = {}
        self._commands: deque[LiveCommand] = deque(maxlen=command_history)
        self._driving: str | None = None
        self._handover_reason = ""
        self._watchers: list[Callable[[str], None]] = []
        self.active = True
        bus.add_listener(self._on_event)

    def watch(self, callback: Callable[[str], None]) -> None:
        """Call `callback(stream)` after an event changed what `stream_message(stream)`
        says (a new pose time alone does not count). It runs on the publisher's thread,
        after the change, so it must only note the name and return."""
        with self._lock:
            self._watchers.append(callback)

    def _on_event(self, event: Event) -> None:
        if not self.active:
            return
        with self._lock:
            changed = self._apply(event)
            watchers = list(self._watchers) if changed else []
        for name in changed:
            for callback in watchers:
                callback(name)

    def _apply(self, event: Event) -> tuple[str, ...]:
        """Fold one event in; returns the streams whose message it changed."""
        match event:
            case PoseEvent():
                return self._update(event.stream, sight=event.sight, pose_t=event.t)
            case GestureEvent():
                return self._update(
                    event.stream,
                    gesture=event.gesture,
                    gesture_confidence=float(event.confidence),
                    withheld=tuple(event.withheld),
                )
            case ActionEvent():
                return self._update(
                    event.stream, action=event.action, action_confidence=float(event.confidence)
                )
            case ArmingEvent():
                return self._update(event.stream, armed=event.armed, arming_reason=event.reason)
            case StreamEvent():
                return self._update(event.stream, state=event.state, state_detail=event.detail)
            case HandoverEvent():
                before, self._driving = self._driving, event.to_stream or None
                self._handover_reason = event.reason
                return tuple(dict.fromkeys(n for n in (before, self._driving) if n))
            case CommandEvent():
                entry = LiveCommand(
                    t=event.t,
                    stream=event.stream,
                    command=event.command,
                    drone=event.drone,
                    ts=time.time(),
                )
                self._commands.append(entry)
            case DroneStateEvent():
                self._drones[event.drone or event.stream] = event
        return ()

    def _update(self, name: str, **changes: object) -> tuple[str, ...]:
        old = self._streams.get(name)
        new = replace(old or StreamLive(), **changes)  # type: ignore[arg-type]
        self._streams[name] = new
        shown = old is None or replace(new, pose_t=old.pose_t) != old
        return (name,) if shown else ()

    @property
    def driving_stream(self) -> str | None:
        """The stream whose recognition drives the decisions (the newest handover's)."""
        with self._lock:
            return self._driving

    def stream_message(self, name: str) -> StreamLiveMessage:
        """The hub's `stream_live` message for `name`, as of now."""
        with self._lock:
            live = self._streams.get(name, StreamLive())
            return StreamLiveMessage(
                stream=name,
                driving=self._driving == name,
                live=live,
                handover_reason=self._handover_reason,
            )

    @property
    def handover_reason(self) -> str:
        """Why the driving stream drives (or none does), from the newest handover."""
        with self._lock:
            return self._handover_reason

    def streams(self) -> dict[str, StreamLive]:
        with self._lock:
            return dict(self._streams)

    def drones(self) -> dict[str, DroneStateEvent]:
        """Each drone's newest `drone_state` event."""
        with self._lock:
            return dict(self._drones)

    def commands(self) -> list[LiveCommand]:
        """Commands seen on the bus since start, newest first."""
        with self._lock:
            return list(reversed(self._commands))
