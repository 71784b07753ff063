"""The newest known state of every stream and drone, kept from bus events so a browser
that connects (or a REST call) gets a full picture at once, before the next event."""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Any

from proxima.events import EventBus
from proxima.types import Event

# Event types that describe one drone (their `drone` field, else `stream`, names it).
DRONE_TYPES = frozenset({"drone_state", "drone", "link", "link_state", "safety", "estop"})


def event_drone(event: Event) -> str:
    """The drone an event concerns: its `drone` field, else its `stream` field."""
    return str(getattr(event, "drone", "") or event.stream)


class LiveState:
    """A bus listener that keeps the latest per-stream and per-drone values; cheap enough
    to run on the publisher's thread."""

    def __init__(self, bus: EventBus, command_history: int = 200) -> None:
        self._lock = threading.Lock()
        self._streams: dict[str, dict[str, Any]] = {}
        self._drones: dict[str, dict[str, Any]] = {}
        self._commands: deque[dict[str, Any]] = deque(maxlen=command_history)
        self._handovers: deque[dict[str, Any]] = deque(maxlen=50)
        self.driving_stream: str | None = None
        self.active = True
        bus.add_listener(self._on_event)

    def _stream(self, name: str) -> dict[str, Any]:
        return self._streams.setdefault(name, {"stream": name})

    def _on_event(self, event: Event) -> None:
        if not self.active:
            return
        kind = event.type
        now = time.time()
        with self._lock:
            if kind == "pose":
                s = self._stream(event.stream)
                s["pose_t"] = event.t
                s["sight"] = str(getattr(event, "sight", "none"))
                s["pose_wall"] = now
            elif kind == "gesture":
                s = self._stream(event.stream)
                s["gesture"] = getattr(event, "gesture", "")
                s["gesture_confidence"] = float(getattr(event, "confidence", 0.0))
                s["withheld"] = list(getattr(event, "withheld", []))
            elif kind == "action":
                s = self._stream(event.stream)
                s["action"] = getattr(event, "action", "")
                s["action_confidence"] = float(getattr(event, "confidence", 0.0))
            elif kind == "arming":
                s = self._stream(event.stream)
                s["armed"] = bool(getattr(event, "armed", False))
                s["arming_reason"] = getattr(event, "reason", "")
            elif kind == "stream":
                s = self._stream(event.stream)
                s["state"] = getattr(event, "state", "")
                s["state_detail"] = getattr(event, "detail", "")
            elif kind == "handover":
                self.driving_stream = getattr(event, "to_stream", None) or None
                self._handovers.append(event.to_dict())
            elif kind == "command":
                self._commands.append({**event.to_dict(), "wall": now})
            elif kind in DRONE_TYPES:
                d = self._drones.setdefault(event_drone(event), {})
                d.update(event.to_dict())
                d["wall"] = now

    def streams(self) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {k: dict(v) for k, v in self._streams.items()}

    def drones(self) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {k: dict(v) for k, v in self._drones.items()}

    def commands(self) -> list[dict[str, Any]]:
        """Commands seen on the bus since start, newest first."""
        with self._lock:
            return list(reversed(self._commands))

    def handovers(self) -> list[dict[str, Any]]:
        with self._lock:
            return list(reversed(self._handovers))
