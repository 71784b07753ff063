"""Typed events, the one registry of their types, and the in-process bus that carries
them.

Every stage on the frame -> command path publishes here; the console, the JSONL writer
and the logs subscribe. Publishing never blocks: each subscriber has its own bounded
queue and, when it falls behind, loses its oldest events (counted in `dropped`), so a
slow browser can never stall recognition.

The recognition events are defined here; the drone link's, the federated runner's and
the console's own are in `drone/events.py`, `federated/events.py` and `api/events.py`.
`EVENT_TYPES` lists them all by their `type`: subscribing to a name missing from it is
an error, and the browser's types are generated from it (`python -m proxima.api.typegen`).
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from proxima.api.events import ModelEvent, RecordingEvent, ThumbnailEvent
from proxima.drone.events import CommandResultEvent, DroneAlarmEvent, DroneStateEvent
from proxima.federated.events import TrainingRoundEvent, TrainingRunEvent
from proxima.types import Event


@dataclass(frozen=True, kw_only=True)
class PoseEvent(Event):
    """The operator's pose in one frame of a stream (`xyz` is 33x3, normalised)."""

    xyz: list[list[float]]
    visibility: list[float]
    sight: str  # `Sight` name in lower case: "full" (feet included), "partial", "none"
    type: str = field(default="pose", init=False)


@dataclass(frozen=True, kw_only=True)
class GestureEvent(Event):
    """One raw classification of the last window of a stream. `withheld` names the
    gestures that may not be the filtered action while this is the newest window (the
    thumb gestures, when it does not see the operator's hand or that arm stays down;
    see control/evidence.py)."""

    gesture: str
    confidence: float
    probs: list[float]
    withheld: list[str] = field(default_factory=list)
    type: str = field(default="gesture", init=False)


@dataclass(frozen=True, kw_only=True)
class ActionEvent(Event):
    """The filtered (moving-average) decision of a stream; `action` is "" when no class
    passes the confidence threshold."""

    action: str
    confidence: float
    type: str = field(default="action", init=False)


@dataclass(frozen=True, kw_only=True)
class ArmingEvent(Event):
    armed: bool
    reason: str
    type: str = field(default="arming", init=False)


@dataclass(frozen=True, kw_only=True)
class HandoverEvent(Event):
    """The stream whose recognition drives the decisions changed."""

    from_stream: str
    to_stream: str
    reason: str
    type: str = field(default="handover", init=False)


@dataclass(frozen=True, kw_only=True)
class CommandEvent(Event):
    """A command decided for a drone. `command` is the gesture it came from; `stream` is
    the stream that saw the gesture, `drone` the drone it goes to."""

    command: str
    drone: str
    type: str = field(default="command", init=False)


@dataclass(frozen=True, kw_only=True)
class StreamEvent(Event):
    state: str
    detail: str = ""
    type: str = field(default="stream", init=False)


def _registry(*classes: type[Event]) -> Mapping[str, type[Event]]:
    by_name: dict[str, type[Event]] = {}
    for cls in classes:
        if cls.type in by_name:
            raise TypeError(
                f"{cls.__name__} and {by_name[cls.type].__name__} share the type {cls.type!r}"
            )
        by_name[cls.type] = cls
    return MappingProxyType(by_name)


# Every event type on the bus, by its `type` (also the WebSocket message's `type`).
EVENT_TYPES: Mapping[str, type[Event]] = _registry(
    PoseEvent,
    GestureEvent,
    ActionEvent,
    ArmingEvent,
    HandoverEvent,
    CommandEvent,
    StreamEvent,
    DroneStateEvent,
    CommandResultEvent,
    DroneAlarmEvent,
    TrainingRoundEvent,
    TrainingRunEvent,
    RecordingEvent,
    ThumbnailEvent,
    ModelEvent,
)


def check_types(types: Iterable[str]) -> frozenset[str]:
    """`types` as a set, each checked against `EVENT_TYPES`.

    Raises:
        ValueError: a name no event has (a subscriber that would never get anything).
    """
    names = frozenset(types)
    unknown = sorted(names - EVENT_TYPES.keys())
    if unknown:
        raise ValueError(
            f"no event type {', '.join(map(repr, unknown))}; known: {sorted(EVENT_TYPES)}"
        )
    return names


class Subscription:
    """A subscriber's bounded queue. Iterate it, or call `get`, from any thread."""

    def __init__(self, bus: EventBus, maxsize: int, types: frozenset[str] | None) -> None:
        self._bus = bus
        self._queue: deque[Event] = deque(maxlen=maxsize)
        self._cond = threading.Condition()
        self.types = types
        self.dropped = 0
        self.closed = False

    def _put(self, event: Event) -> None:
        with self._cond:
            if len(self._queue) == self._queue.maxlen:
                self.dropped += 1
            self._queue.append(event)
            self._cond.notify()

    def get(self, timeout: float | None = None) -> Event | None:
        """Next event, or None after `timeout` seconds (or once closed and empty)."""
        with self._cond:
            if not self._queue and not self.closed:
                self._cond.wait(timeout)
            return self._queue.popleft() if self._queue else None

    def drain(self) -> list[Event]:
        """Every queued event, without waiting."""
        with self._cond:
            items = list(self._queue)
            self._queue.clear()
            return items

    def close(self) -> None:
        self._bus._unsubscribe(self)
        with self._cond:
            self.closed = True
            self._cond.notify_all()

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class EventBus:
    """Fan-out of events to subscribers and listeners; thread-safe, never blocks."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._subs: list[Subscription] = []
        self._listeners: list[Callable[[Event], None]] = []

    def subscribe(self, maxsize: int = 1000, types: Iterable[str] | None = None) -> Subscription:
        """A queue of future events (only of `types`, if given).

        Raises:
            ValueError: a name in `types` that is no event type (see `EVENT_TYPES`).
        """
        sub = Subscription(self, maxsize, check_types(types) if types else None)
        with self._lock:
            self._subs.append(sub)
        return sub

    def add_listener(self, callback: Callable[[Event], None]) -> None:
        """Call `callback` synchronously on every event: only for fast, non-blocking work
        (appending to a file, counting); anything slower belongs in a Subscription."""
        with self._lock:
            self._listeners.append(callback)

    def _unsubscribe(self, sub: Subscription) -> None:
        with self._lock:
            if sub in self._subs:
                self._subs.remove(sub)

    def publish(self, event: Event) -> None:
        with self._lock:
            subs = list(self._subs)
            listeners = list(self._listeners)
        for callback in listeners:
            callback(event)
        for sub in subs:
            if sub.types is None or event.type in sub.types:
                sub._put(event)
