"""Alarms the console raises from drone telemetry, beside the ones the drone links and
the controller publish (link lost, operator lost, emergency stop): low battery (a
warning at `server.battery_warn_pct`, critical at `server.battery_critical_pct`) and a
drone that lands or returns on its own (an autopilot failsafe: the mode turned to
LAND or RTL in flight with no land, abort or emergency stop commanded in the seconds
before), and a drone near or outside the geofence (a warning beyond GEOFENCE_WARN of
`safety.geofence_radius_m` from home or of `safety.max_altitude_m`, critical outside:
the safety rules refuse targets outside it, but wind, a failsafe or a manual pilot can
still take a drone there). Each is published as a `drone_alarm` with a severity,
written to the server's log and to the audit trail (`alarm.raise`, actor `console`),
and kept for `hello`.
"""

from __future__ import annotations

import logging
import math
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
GEOFENCE_WARN = 0.9  # share of the fence's radius or ceiling that warns


@dataclass
class _DroneWatch:
    battery_level: str = ""  # "", "warning", "critical"
    fence_level: str = ""  # the same levels for the geofence
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
        geofence_radius_m: float | None = None,
        max_altitude_m: float | None = None,
    ) -> None:
        self.bus = bus
        self.warn_pct = warn_pct
        self.critical_pct = critical_pct
        self.geofence_radius_m = geofence_radius_m
        self.max_altitude_m = max_altitude_m
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
            fence = self._fence(drone, w, s.position)
            if fence is not None:
                out.append(fence)
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

    def _fence(
        self, drone: str, w: _DroneWatch, position: list[float] | None
    ) -> DroneAlarmEvent | None:
        """The geofence alarm when `position` (local NED, home at the origin, as the
        safety rules take it) changes level, else None."""
        if position is None or len(position) < 3:
            return None
        radius = math.hypot(position[0], position[1])
        altitude = -position[2]
        shares = []
        if self.geofence_radius_m:
            shares.append((radius / self.geofence_radius_m, f"{radius:.1f} m from home "
                           f"(fence radius {self.geofence_radius_m:.0f} m)"))  # fmt: skip
        if self.max_altitude_m:
            shares.append((altitude / self.max_altitude_m, f"{altitude:.1f} m up "
                           f"(ceiling {self.max_altitude_m:.0f} m)"))  # fmt: skip
        if not shares:
            return None
        share, what = max(shares)
        level = "critical" if share > 1.0 else "warning" if share > GEOFENCE_WARN else ""
        if level == w.fence_level:
            return None
        w.fence_level = level
        if not level:
            back = f"{drone}: back inside the geofence, {what}"
            return self._alarm(drone, "geofence", "warning", back, active=False)
        where = "outside the geofence" if level == "critical" else "near the geofence"
        return self._alarm(drone, "geofence", level, f"{drone}: {where}, {what}")

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
