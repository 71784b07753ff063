"""Flight safety rules that every gesture command passes before it reaches a vehicle.

- Gesture control per drone: nothing is sent unless the operator armed it (have_command).
- Geofence: a move's target must stay within `geofence_radius_m` of the home point and
  between `min_altitude_m` and `max_altitude_m`; a single step is at most `max_step_m`.
- Rate limit: motion commands to one drone at least `min_interval_s` apart. Commands
  that only make a drone safer (hold, abort, land) are never rate-limited.
- Operator watchdog: no stream saw the operator for `operator_lost_s` -> hover.
- Emergency stop: `request()` gives a token, `confirm(token)` within `estop_confirm_s`
  executes it, once; one accidental click does nothing.
"""

from __future__ import annotations

import math
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from pydantic import BaseModel, ConfigDict, Field, model_validator

RATE_LIMITED = frozenset({"move", "change_speed", "resume_speed"})


class SafetyConfig(BaseModel):
    """The limits; defaults suit proximal flight a few metres from the operator. This is
    the `[safety]` section of `proxima.settings.Settings` as it is."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    geofence_radius_m: float = Field(30.0, gt=0, description="targets stay this near home")
    min_altitude_m: float = Field(1.0, ge=0, description="lowest target altitude (land below)")
    max_altitude_m: float = Field(20.0, gt=0, description="highest target altitude")
    max_step_m: float = Field(3.0, gt=0, description="longest single move")
    min_interval_s: float = Field(1.0, ge=0, description="least time between motion commands")
    operator_lost_s: float = Field(
        5.0, gt=0, description="hover when no stream saw the operator for this long"
    )
    estop_confirm_s: float = Field(
        10.0, gt=0, description="an emergency stop must be confirmed within this"
    )

    @model_validator(mode="after")
    def _check_band(self) -> SafetyConfig:
        if not self.min_altitude_m < self.max_altitude_m:
            raise ValueError("SafetyConfig needs 0 <= min_altitude_m < max_altitude_m")
        return self


@dataclass(frozen=True)
class Verdict:
    ok: bool
    reason: str = ""


OK = Verdict(True)


class EmergencyStopError(PermissionError):
    """A confirmation with an unknown, used or expired token (or for another drone)."""


@dataclass(frozen=True)
class EmergencyStopRequest:
    token: str
    drone: str
    kind: str  # "land" (controlled descent) or "kill" (motors off: the drone falls)
    expires_at: float  # on the gate's clock
    confirm_within_s: float


class SafetyGate:
    """The state the rules need (armed drones, last command times, operator sightings,
    pending emergency stops). Thread-safe; time comes from `clock` (monotonic seconds)."""

    def __init__(
        self, config: SafetyConfig | None = None, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.cfg = config or SafetyConfig()
        self.clock = clock
        self._lock = threading.Lock()
        self._armed: set[str] = set()
        # Emergency-stopped drones: gesture control cannot arm them until a supervisor
        # resumes them (`clear_stop`).
        self._stopped: set[str] = set()
        self._last_sent: dict[str, float] = {}
        self._operator_seen: dict[str, float] = {}
        self._estops: dict[str, EmergencyStopRequest] = {}

    # --- gesture control --------------------------------------------------------------
    def arm_control(self, drone: str) -> bool:
        """Arm gesture control of `drone`; False (nothing armed) while it is stopped."""
        with self._lock:
            if drone in self._stopped:
                return False
            self._armed.add(drone)
            return True

    def mark_stopped(self, drone: str) -> None:
        """An emergency stop was confirmed: disarm it and keep it disarmed."""
        with self._lock:
            self._stopped.add(drone)
            self._armed.discard(drone)

    def clear_stop(self, drone: str) -> bool:
        """A supervisor resumed `drone`; returns whether it was stopped. Gesture control
        stays disarmed until the next have_command."""
        with self._lock:
            was = drone in self._stopped
            self._stopped.discard(drone)
            return was

    def is_stopped(self, drone: str) -> bool:
        with self._lock:
            return drone in self._stopped

    def disarm_control(self, drone: str) -> None:
        with self._lock:
            self._armed.discard(drone)

    def is_armed(self, drone: str) -> bool:
        with self._lock:
            return drone in self._armed

    # --- motion -----------------------------------------------------------------------
    def check_move(
        self,
        step: tuple[float, float, float],
        target: tuple[float, float, float],
        home: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> Verdict:
        """Max step, geofence radius and altitude band for a move to local NED `target`."""
        c = self.cfg
        length = math.sqrt(sum(s * s for s in step))
        if length > c.max_step_m + 1e-9:
            return Verdict(False, f"step {length:.2f} m exceeds max_step_m {c.max_step_m:.2f}")
        radius = math.hypot(target[0] - home[0], target[1] - home[1])
        if radius > c.geofence_radius_m:
            return Verdict(
                False,
                f"geofence: target {radius:.1f} m from home exceeds radius "
                f"{c.geofence_radius_m:.1f} m",
            )
        altitude = home[2] - target[2]
        if altitude > c.max_altitude_m:
            return Verdict(
                False,
                f"geofence: target altitude {altitude:.1f} m above "
                f"max_altitude_m {c.max_altitude_m:.1f}",
            )
        if altitude < c.min_altitude_m:
            return Verdict(
                False,
                f"geofence: target altitude {altitude:.1f} m below "
                f"min_altitude_m {c.min_altitude_m:.1f} (use land)",
            )
        return OK

    def check_rate(self, drone: str, action: str) -> Verdict:
        if action not in RATE_LIMITED:
            return OK
        with self._lock:
            last = self._last_sent.get(drone)
        if last is not None:
            since = self.clock() - last
            if since < self.cfg.min_interval_s:
                return Verdict(
                    False,
                    f"rate limit: {since:.2f} s since the last command, "
                    f"min_interval_s is {self.cfg.min_interval_s:.2f}",
                )
        return OK

    def note_sent(self, drone: str) -> None:
        with self._lock:
            self._last_sent[drone] = self.clock()

    # --- operator watchdog --------------------------------------------------------------
    def note_operator(self, stream: str, visible: bool) -> None:
        """Record one pose observation of a stream; only visible ones reset the timer."""
        with self._lock:
            if visible:
                self._operator_seen[stream] = self.clock()
            else:
                self._operator_seen.setdefault(stream, -math.inf)

    def operator_lost(self) -> bool:
        """True when streams exist and none saw the operator for `operator_lost_s`."""
        with self._lock:
            if not self._operator_seen:
                return False
            newest = max(self._operator_seen.values())
        return self.clock() - newest > self.cfg.operator_lost_s

    # --- emergency stop -----------------------------------------------------------------
    def request_emergency_stop(self, drone: str, kind: str = "land") -> EmergencyStopRequest:
        """First step: a token that `confirm_emergency_stop` needs within the window."""
        if kind not in ("land", "kill"):
            raise ValueError(f"emergency stop kind must be 'land' or 'kill', got {kind!r}")
        window = self.cfg.estop_confirm_s
        req = EmergencyStopRequest(
            secrets.token_urlsafe(16), drone, kind, self.clock() + window, window
        )
        with self._lock:
            now = self.clock()
            self._estops = {t: r for t, r in self._estops.items() if r.expires_at > now}
            self._estops[req.token] = req
        return req

    def confirm_emergency_stop(self, token: str, drone: str | None = None) -> EmergencyStopRequest:
        """Second step: the request the token belongs to, consumed.

        Raises:
            EmergencyStopError: unknown or already used token, a token for another drone
                than `drone`, or the window passed.
        """
        with self._lock:
            req = self._estops.get(token)
            if req is not None and drone is not None and req.drone != drone:
                raise EmergencyStopError(
                    f"emergency-stop token was issued for {req.drone!r}, not {drone!r}"
                )
            self._estops.pop(token, None)
        if req is None:
            raise EmergencyStopError("unknown or already used emergency-stop token")
        if self.clock() > req.expires_at:
            raise EmergencyStopError(
                f"emergency-stop confirmation came after {req.confirm_within_s:.0f} s; "
                "request it again"
            )
        return req
