"""Events the drone subsystem publishes on the bus.

`t` is wall-clock time (Unix seconds) for what the link observes, since a vehicle has no
stream time; a `CommandResultEvent` carries the gesture's stream time in `gesture_t`.
`stream` is the drone's name for link events and the camera stream for command results.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from proxima.types import Event


@dataclass(frozen=True, kw_only=True)
class DroneStateEvent(Event):
    """A vehicle's telemetry and link state (published about 10 times a second while the
    link is up, and on every link-state change). Position is local NED metres."""

    drone: str
    link: str  # LinkState value: "connecting", "ok", "lost"
    autopilot: str = "unknown"
    mode: str = ""
    armed: bool = False
    landed: str = "unknown"
    position: list[float] | None = None  # [north, east, down]
    velocity: list[float] | None = None
    attitude: list[float] | None = None  # [roll, pitch, yaw] radians
    battery_pct: float | None = None
    battery_voltage: float | None = None
    global_position: list[float] | None = None  # [lat, lon, alt AMSL]
    position_target: list[float] | None = None
    gesture_control: bool = False
    heard_age_s: float | None = None  # seconds since the vehicle's newest message
    stopped: bool = False  # emergency-stopped and not resumed: no gesture control
    type: str = field(default="drone_state", init=False)


@dataclass(frozen=True, kw_only=True)
class CommandResultEvent(Event):
    """What became of one command: refused by safety, sent and acknowledged (or not),
    and its outcome once known (reached, landed, ...). `log_id` is its command-log row."""

    drone: str
    command: str  # the gesture (or "emergency_stop", or a CLI action)
    action: str  # what the mapping made of it: move, hold, land, ...
    status: str  # "sent", "refused", "failed", "ignored", "done"
    ack: str = ""
    outcome: str = ""
    reason: str = ""
    gesture_t: float | None = None
    latency_s: float | None = None
    log_id: int | None = None
    type: str = field(default="command_result", init=False)


@dataclass(frozen=True, kw_only=True)
class DroneAlarmEvent(Event):
    """Something a supervisor must see now: link lost, operator lost, low battery,
    emergency stop. `kind` names it; `active` is False when it clears."""

    drone: str
    kind: str
    message: str
    active: bool = True
    severity: str = "warning"  # "warning" or "critical"
    type: str = field(default="drone_alarm", init=False)
