"""Outcome tracking: after a move, hold or landing was sent, watch the vehicle until it is
there ("reached", "landed"), gave up ("not_reached", "not_landed" after a deadline sized
to the distance), was overtaken by the next command ("superseded") or lost its link
("link_lost"). One tracked command per drone.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from proxima.drone.controller.record import CommandRecorder, ControlOutcome
from proxima.drone.link import DroneLink
from proxima.events import CommandEvent


@dataclass
class TrackedCommand:
    """A sent command whose outcome is not known yet."""

    log_id: int | None
    command: str
    action: str  # "move", "hold" or "land"
    gesture_t: float
    stream: str
    target: tuple[float, float, float] | None
    deadline: float  # on the tracker's clock


class OutcomeTracker:
    """Tracks one command per drone; `check()` settles what is settled (the watchdog
    calls it every few tens of milliseconds). Thread-safe."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        recorder: CommandRecorder,
        speeds: Mapping[str, float],
        arrive_tolerance_m: float,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.links = links
        self.recorder = recorder
        self.speeds = speeds  # each drone's commanded speed: sizes a move's deadline
        self.arrive_tolerance_m = arrive_tolerance_m
        self.clock = clock
        self._tracked: dict[str, TrackedCommand] = {}
        self._lock = threading.Lock()

    def track(
        self,
        event: CommandEvent,
        out: ControlOutcome,
        kind: str,
        target: tuple[float, float, float] | None,
        link: DroneLink,
    ) -> None:
        """Follow `out` (just sent) until its outcome; the drone's previous tracked
        command, if any, is superseded."""
        tel = link.telemetry()
        sent = out.result.sent if out.result is not None else {}
        if kind == "hold" and target is None and "x" in sent:
            target = (sent["x"], sent["y"], sent["z"])  # the hold point that was sent
        if kind == "land":
            alt = (tel.altitude or 0.0) if tel else 0.0
            timeout = 30.0 + alt / 0.3
        else:
            dist = tel.distance_to(target) if tel and target else 0.0
            timeout = 5.0 + 3.0 * dist / max(self.speeds[event.drone], 0.1)
        item = TrackedCommand(
            out.log_id,
            event.command,
            kind,
            event.t,
            event.stream,
            target,
            self.clock() + timeout,
        )
        with self._lock:
            old = self._tracked.get(event.drone)
            self._tracked[event.drone] = item
        if old is not None:
            self.recorder.outcome(event.drone, old, "superseded")

    def drop(self, drone: str, outcome: str) -> None:
        """End the drone's tracked command, if any, with `outcome` (e.g. "link_lost")."""
        with self._lock:
            item = self._tracked.pop(drone, None)
        if item is not None:
            self.recorder.outcome(drone, item, outcome)

    def check(self) -> None:
        """Publish the outcome of every tracked command that has one now."""
        now = self.clock()
        done: list[tuple[str, TrackedCommand, str]] = []
        with self._lock:
            for name, item in list(self._tracked.items()):
                tel = self.links[name].telemetry()
                outcome = None
                if tel is not None:
                    if item.action == "land":
                        if tel.landed == "on_ground" and not tel.armed:
                            outcome = "landed"
                    elif item.target is not None:
                        if tel.distance_to(item.target) < self.arrive_tolerance_m:
                            outcome = "reached"
                    else:
                        outcome = "done"
                if outcome is None and now > item.deadline:
                    outcome = "not_landed" if item.action == "land" else "not_reached"
                if outcome is not None:
                    del self._tracked[name]
                    done.append((name, item, outcome))
        for name, item, outcome in done:
            self.recorder.outcome(name, item, outcome)
