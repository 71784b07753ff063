"""Alarms the console raises from drone telemetry, beside the ones the drone links and
the controller publish (link lost, operator lost, emergency stop): low battery (a
warning at `server.battery_warn_pct`, critical at `server.battery_critical_pct`) and a
drone that lands or returns on its own (an autopilot failsafe: the mode turned to
LAND or RTL in flight with no land, abort or emergency stop commanded in the seconds
before). Each is published as a `drone_alarm` with a severity, written to the server's
log and to the audit trail (`alarm.raise`, actor `console`), and kept for `hello`.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

from proxima.drone.events import CommandResultEvent, DroneAlarmEvent, DroneStateEvent
from proxima.events import EventBus
from proxima.types import Event

log = logging.getLogger(__name__)

# Modes an autopilot flies on its own to end a flight (ArduPilot, PX4 names).
LANDING_MODES = frozenset({"LAND", "RTL", "SMART_RTL", "AUTO.LAND", "AUTO.RTL", "AUTO_RTL"})
# Actions after which a landing is the console's own doing.
COMMANDED = frozenset({"land", "abort", "hold"})
COMMANDED_WITHIN_S = 10.0


@dataclass
class _DroneWatch:
    battery_level: str = ""  # "", "warning", "critical"
    mode: str = ""
    flying: bool = False
    commanded_at: float = -1e9


class AlarmMonitor:
    """A bus listener deriving alarms from `drone_state` (cheap; runs on the publisher's
    thread and publishes from it)."""

    def __init__(
        self,
        bus: EventBus,
        warn_pct: float = 20.0,
        critical_pct: float = 10.0,
        audit: Any = None,  # proxima.api.audit.Audit
        history: int = 100,
    ) -> None:
        self.bus = bus
        self.warn_pct = warn_pct
        self.critical_pct = critical_pct
        self.audit = audit
        self._lock = threading.Lock()
        self._drones: dict[str, _DroneWatch] = {}
        self._recent: deque[DroneAlarmEvent] = deque(maxlen=history)
        bus.add_listener(self._on_event)

    def recent(self) -> list[DroneAlarmEvent]:
        """Every alarm seen on the bus since start (raised and cleared), newest first."""
        with self._lock:
            return list(reversed(self._recent))

    def _on_event(self, event: Event) -> None:
        if isinstance(event, DroneAlarmEvent):
            with self._lock:
                self._recent.append(event)
            return
        if isinstance(event, CommandResultEvent):
            if event.action in COMMANDED or event.command == "emergency_stop":
                with self._lock:
                    self._watch(event.drone).commanded_at = time.monotonic()
            return
        if isinstance(event, DroneStateEvent):
            for alarm in self._check(event):
                self._raise(alarm)

    def _watch(self, drone: str) -> _DroneWatch:
        return self._drones.setdefault(drone, _DroneWatch())

    def _check(self, s: DroneStateEvent) -> list[DroneAlarmEvent]:
        out: list[DroneAlarmEvent] = []
        drone = s.drone or s.stream
        with self._lock:
            w = self._watch(drone)
            if s.battery_pct is not None:
                pct = float(s.battery_pct)
                level = (
                    "critical"
                    if pct <= self.critical_pct
                    else "warning"
                    if pct <= self.warn_pct
                    else ""
                )
                if level != w.battery_level:
                    if level:
                        limit = self.critical_pct if level == "critical" else self.warn_pct
                        out.append(self._alarm(
                            drone, "battery_low", level,
                            f"{drone}: battery {pct:.0f}% (at or below {limit:.0f}%)",
                        ))  # fmt: skip
                    else:
                        out.append(self._alarm(
                            drone, "battery_low", "warning",
                            f"{drone}: battery {pct:.0f}%, above {self.warn_pct:.0f}% again",
                            active=False,
                        ))  # fmt: skip
                    w.battery_level = level
            mode = s.mode or ""
            if (
                mode in LANDING_MODES
                and w.mode not in LANDING_MODES
                and w.flying
                and time.monotonic() - w.commanded_at > COMMANDED_WITHIN_S
            ):
                out.append(self._alarm(
                    drone, "failsafe_landing", "critical",
                    f"{drone}: switched to {mode} on its own (autopilot failsafe"
                    f"{', battery low' if w.battery_level else ''}): not commanded",
                ))  # fmt: skip
            if mode:
                w.mode = mode
            # Climbing and descending count: a failsafe can fire during the take-off, and
            # the vehicle may report "landing" a message before its mode says LAND.
            w.flying = s.landed in ("in_air", "takeoff", "landing")
        return out

    @staticmethod
    def _alarm(
        drone: str, kind: str, severity: str, message: str, active: bool = True
    ) -> DroneAlarmEvent:
        return DroneAlarmEvent(t=time.time(), stream=drone, drone=drone, kind=kind,
                               message=message, active=active, severity=severity)  # fmt: skip

    def _raise(self, alarm: DroneAlarmEvent) -> None:
        level = logging.WARNING if alarm.active else logging.INFO
        log.log(level, "alarm %s (%s): %s", alarm.kind, alarm.severity, alarm.message)
        if self.audit is not None:
            self.audit.record(
                "alarm.raise" if alarm.active else "alarm.clear",
                actor="console",
                target=alarm.drone,
                kind=alarm.kind,
                severity=alarm.severity,
                message=alarm.message,
            )
        self.bus.publish(alarm)
