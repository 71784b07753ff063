"""The `DroneLink` interface: one connected vehicle, its link state, telemetry and commands.

Implementations: `mavlink.MavlinkLink` (MAVLink 2 over pymavlink, to a real vehicle, SITL
or `proxima sim-drone`) and `memory.MemoryLink` (the same commands to a simulated
vehicle inside this process, for tests). The interface keeps pymavlink out of the
controller, the safety rules and the console. Every command returns a `CommandResult`
that says what the vehicle answered; nothing is assumed.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field

from proxima.types import LinkState


class LinkError(RuntimeError):
    """The link could not be opened or did not hear the vehicle in time."""


@dataclass(frozen=True)
class Telemetry:
    """The newest known state of a vehicle. Positions are local NED metres from the
    vehicle's origin (x north, y east, z down); angles in radians; `received` is the
    `time.monotonic()` of the newest message that went into it."""

    received: float
    system_id: int
    autopilot: str  # "ardupilot", "px4" or "unknown"
    mode: str
    armed: bool
    landed: str  # "on_ground", "in_air", "takeoff", "landing", "unknown"
    position: tuple[float, float, float] | None = None
    velocity: tuple[float, float, float] | None = None
    attitude: tuple[float, float, float] | None = None  # roll, pitch, yaw
    battery_pct: float | None = None
    battery_voltage: float | None = None
    global_position: tuple[float, float, float] | None = None  # lat, lon, alt AMSL
    relative_alt: float | None = None
    position_target: tuple[float, float, float] | None = None
    home: tuple[float, float, float] | None = None  # lat, lon, alt AMSL
    status_text: str = ""

    @property
    def altitude(self) -> float | None:
        """Height above the local origin in metres (-z), if the position is known."""
        return None if self.position is None else -self.position[2]

    @property
    def yaw(self) -> float:
        return 0.0 if self.attitude is None else self.attitude[2]

    @property
    def flying(self) -> bool:
        return self.landed in ("in_air", "takeoff", "landing")

    def distance_to(self, target: tuple[float, float, float]) -> float:
        """Straight-line distance from the vehicle to a local NED point (inf if unknown)."""
        if self.position is None:
            return math.inf
        return math.dist(self.position, target)


@dataclass(frozen=True)
class CommandResult:
    """What happened to one command.

    `ack` is the vehicle's COMMAND_ACK result in lower case ("accepted", "denied",
    "failed", "unsupported", "temporarily_rejected", "in_progress"), or: "echoed" (a
    position target the vehicle reported back), "sent" (a message MAVLink does not
    acknowledge, and no echo came), "timeout" (no answer after every retry),
    "link_lost" / "not_connected" (nothing was sent), "invalid" (an argument that is not
    a number that can be flown, such as NaN: nothing was sent). `confirmed` is True only
    when the vehicle itself answered.
    """

    action: str
    ack: str
    ok: bool
    attempts: int = 0
    latency_s: float | None = None
    confirmed: bool = False
    sent: dict = field(default_factory=dict)
    detail: str = ""

    def to_dict(self) -> dict:
        return {
            "action": self.action,
            "ack": self.ack,
            "ok": self.ok,
            "attempts": self.attempts,
            "latency_s": self.latency_s,
            "confirmed": self.confirmed,
            "sent": self.sent,
            "detail": self.detail,
        }


class DroneLink(ABC):
    """One vehicle behind a connection. Implementations own their connection in one
    thread; every method here is safe to call from any thread. Command methods block
    until the vehicle answered or the retries ran out."""

    name: str
    gesture_control: bool = False  # set by the controller; shown in the link's state
    emergency_stopped: bool = False  # likewise: stopped until a supervisor resumes it

    @abstractmethod
    def connect(self, timeout: float = 10.0) -> None:
        """Open the connection and wait for the vehicle's first heartbeat.

        Raises:
            LinkError: the connection could not be opened or no heartbeat came in time.
        """

    @abstractmethod
    def close(self) -> None:
        """Stop the link thread and close the connection (idempotent)."""

    @property
    @abstractmethod
    def state(self) -> LinkState:
        """CONNECTING until the first heartbeat, OK while heartbeats arrive, LOST after
        the configured silence."""

    @abstractmethod
    def telemetry(self) -> Telemetry | None:
        """The newest telemetry, or None before the first heartbeat."""

    @abstractmethod
    def guided_mode(self) -> str:
        """The vehicle's name for the mode that follows external position targets
        (ArduPilot GUIDED, PX4 OFFBOARD)."""

    @abstractmethod
    def holding_modes(self) -> frozenset[str]:
        """The vehicle's modes in which it only holds its position: from these, and only
        these, a gesture may take it into `guided_mode()`."""

    @abstractmethod
    def set_mode(self, mode: str) -> CommandResult:
        """Switch to a flight mode by the autopilot's own name (e.g. "GUIDED", "LOITER")."""

    @abstractmethod
    def enter_guided(self) -> CommandResult:
        """Enter the mode that follows external position targets: GUIDED on ArduPilot,
        OFFBOARD on PX4 (after starting the setpoint stream it needs)."""

    @abstractmethod
    def arm(self) -> CommandResult:
        """Arm the motors."""

    @abstractmethod
    def disarm(self, force: bool = False) -> CommandResult:
        """Disarm the motors; `force` stops them even in flight (the vehicle falls)."""

    @abstractmethod
    def takeoff(self, altitude_m: float) -> CommandResult:
        """Guided mode, arm, take off to `altitude_m` above the origin."""

    @abstractmethod
    def goto_local(
        self, north: float, east: float, down: float, yaw: float | None = None
    ) -> CommandResult:
        """Fly to an absolute local NED point (SET_POSITION_TARGET_LOCAL_NED)."""

    @abstractmethod
    def hold(self) -> CommandResult:
        """Stop and hold the current position."""

    @abstractmethod
    def change_speed(self, speed_m_s: float) -> CommandResult:
        """Set the horizontal speed used for position targets (MAV_CMD_DO_CHANGE_SPEED)."""

    @abstractmethod
    def land(self) -> CommandResult:
        """Land where the vehicle is (MAV_CMD_NAV_LAND)."""

    def wait_for(
        self, predicate: Callable[[Telemetry], bool], timeout: float, poll: float = 0.02
    ) -> Telemetry | None:
        """Poll telemetry until `predicate` holds; the matching telemetry, or None after
        `timeout` seconds (or when the link is lost)."""
        deadline = time.monotonic() + timeout
        while True:
            tel = self.telemetry()
            if tel is not None and predicate(tel):
                return tel
            if time.monotonic() >= deadline or self.state == LinkState.LOST:
                return None
            time.sleep(poll)

    def __enter__(self) -> DroneLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
