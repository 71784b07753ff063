"""What a scenario keeps: the timeline of decisions and the vehicles' flight paths.

`TimelineRecorder` listens on the bus (a fast synchronous listener) and keeps, in
scenario time (`FlightClock.now()`), every recognised gesture (runs of the same raw
classification per stream), every filtered action that became confident, handover,
arming change, command, acknowledgement and outcome from the drone controller, drone
alarm and stream state change. `PathRecorder` samples each vehicle's telemetry at
20 Hz of wall clock for the flight-path plot.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from proxima.drone.events import CommandResultEvent, DroneAlarmEvent
from proxima.drone.link import DroneLink, Telemetry
from proxima.events import (
    ActionEvent,
    ArmingEvent,
    CommandEvent,
    EventBus,
    GestureEvent,
    HandoverEvent,
    StreamEvent,
)
from proxima.types import Event


def _r(x: float | None, nd: int = 3) -> float | None:
    return None if x is None else round(float(x), nd)


class TimelineRecorder:
    """Collects the scenario's timeline from one or more buses (see the module)."""

    def __init__(self, now: Callable[[], float], scope: str = "") -> None:
        self.now = now
        self.scope = scope
        self._lock = threading.Lock()
        self.entries: list[dict[str, Any]] = []
        self._runs: dict[str, dict[str, Any]] = {}  # open gesture run per stream
        self._last_action: dict[str, str] = {}
        self._tracked: set[tuple[str, str, int | None, str]] = set()  # awaiting an outcome

    def attach(self, bus: EventBus, scope: str = "") -> None:
        """Record the events of `bus`; `scope` (e.g. the drone a bus belongs to) is added
        to each entry when several buses feed one timeline."""
        bus.add_listener(lambda e: self._on_event(e, scope))

    def add(self, entry: dict[str, Any]) -> None:
        """Add an entry of the scenario's own (pre-flight, camera framing, ...)."""
        with self._lock:
            self.entries.append(entry)

    def _on_event(self, event: Event, scope: str) -> None:
        entry = self._entry(event, scope)
        if entry is None:
            return
        if scope:
            entry["scope"] = scope
        with self._lock:
            self.entries.append(entry)

    def _entry(self, e: Event, scope: str) -> dict[str, Any] | None:
        t = _r(e.t)
        if isinstance(e, GestureEvent):
            key = f"{scope}/{e.stream}"
            with self._lock:
                run = self._runs.get(key)
                if run is not None and run["gesture"] == e.gesture:
                    run["until"] = t
                    run["n"] += 1
                    run["confidence"] = max(run["confidence"], e.confidence)
                    return None
                run = {
                    "t": t,
                    "kind": "gesture",
                    "stream": e.stream,
                    "gesture": e.gesture,
                    "until": t,
                    "n": 1,
                    "confidence": e.confidence,
                }
                self._runs[key] = run
            return run
        if isinstance(e, ActionEvent):
            key = f"{scope}/{e.stream}"
            with self._lock:
                previous = self._last_action.get(key, "")
                self._last_action[key] = e.action
            if not e.action or e.action == previous:
                return None
            return {
                "t": t,
                "kind": "action",
                "stream": e.stream,
                "action": e.action,
                "confidence": e.confidence,
            }
        if isinstance(e, HandoverEvent):
            return {
                "t": t,
                "kind": "handover",
                "from_stream": e.from_stream,
                "to_stream": e.to_stream,
                "reason": e.reason,
            }
        if isinstance(e, ArmingEvent):
            return {
                "t": t,
                "kind": "arming",
                "stream": e.stream,
                "armed": e.armed,
                "reason": e.reason,
            }
        if isinstance(e, CommandEvent):
            return {
                "t": t,
                "kind": "command",
                "stream": e.stream,
                "command": e.command,
                "drone": e.drone,
            }
        if isinstance(e, CommandResultEvent):
            now = _r(self.now())
            common = {
                "t": now,
                "command_t": _r(e.gesture_t),
                "drone": e.drone,
                "stream": e.stream,
                "command": e.command,
                "action": e.action,
            }
            tracked = (scope, e.drone, e.log_id, e.command)
            with self._lock:
                if e.status == "done" and tracked in self._tracked:
                    self._tracked.discard(tracked)
                    return {**common, "kind": "outcome", "outcome": e.outcome}
                if e.status == "sent" and not e.outcome:
                    self._tracked.add(tracked)
            return {
                **common,
                "kind": "ack",
                "status": e.status,
                "ack": e.ack,
                "outcome": e.outcome,
                "reason": e.reason,
                "latency_ms": _r(e.latency_s * 1000.0, 2) if e.latency_s is not None else None,
            }
        if isinstance(e, DroneAlarmEvent):
            return {
                "t": _r(self.now()),
                "kind": "alarm",
                "drone": e.drone,
                "alarm": e.kind,
                "message": e.message,
            }
        if isinstance(e, StreamEvent):
            return {
                "t": t,
                "kind": "stream",
                "stream": e.stream,
                "state": e.state,
                "detail": e.detail,
            }
        return None

    def timeline(self) -> list[dict[str, Any]]:
        """Every entry, in scenario time (stable for equal times)."""
        with self._lock:
            entries = [dict(e) for e in self.entries]
        return sorted(entries, key=lambda e: e["t"] if e["t"] is not None else -1e9)


@dataclass
class PathSample:
    """One telemetry sample: scenario time `t` (None before the streams started), the
    wall clock, local NED position, altitude, landed state and motor arming."""

    t: float | None
    wall: float
    position: tuple[float, float, float]
    landed: str
    armed: bool


@dataclass
class PathRecorder:
    """Samples every link's telemetry on a thread (20 Hz of wall clock)."""

    links: Mapping[str, DroneLink]
    now: Callable[[], float | None]
    period_s: float = 0.05
    samples: dict[str, list[PathSample]] = field(default_factory=dict)
    _stop: threading.Event = field(default_factory=threading.Event, init=False)
    _thread: threading.Thread | None = field(default=None, init=False)

    def start(self) -> PathRecorder:
        self.samples = {name: [] for name in self.links}
        self._thread = threading.Thread(target=self._run, name="path-recorder", daemon=True)
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            self.sample()

    def sample(self) -> None:
        """Take one sample of every vehicle now."""
        t = self.now()
        wall = time.monotonic()
        for name, link in self.links.items():
            tel: Telemetry | None = link.telemetry()
            if tel is None or tel.position is None:
                continue
            self.samples[name].append(PathSample(t, wall, tel.position, tel.landed, tel.armed))

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        self.sample()

    def as_time_series(self, start_wall: float) -> dict[str, list[list[float]]]:
        """Per drone: [t, north, east, down] rows; samples taken before the streams
        started get negative times from the wall clock (`start_wall`: when they did)."""
        out: dict[str, list[list[float]]] = {}
        for name, rows in self.samples.items():
            series = []
            for s in rows:
                t = s.t if s.t is not None else s.wall - start_wall
                series.append([round(t, 3), *(round(v, 3) for v in s.position)])
            out[name] = series
        return out


def telemetry_state(tel: Telemetry | None, link_state: str) -> dict[str, Any]:
    """A vehicle's state as JSON: local NED position, altitude, mode, motors, landed."""
    if tel is None:
        return {"link": link_state, "known": False}
    return {
        "link": link_state,
        "known": True,
        "position_ned": [round(v, 3) for v in tel.position] if tel.position else None,
        "altitude_m": _r(tel.altitude),
        "velocity_ned": [round(v, 3) for v in tel.velocity] if tel.velocity else None,
        "yaw_rad": _r(tel.yaw),
        "mode": tel.mode,
        "armed": tel.armed,
        "landed": tel.landed,
        "battery_pct": _r(tel.battery_pct, 1),
        "system_id": tel.system_id,
        "autopilot": tel.autopilot,
    }
