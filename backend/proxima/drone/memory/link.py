"""`MemoryLink`: the MAVLink commands to a simulated vehicle inside this process.

The same command layer as `MavlinkLink` (`mavlink.actions.MavlinkActions`: the same
autopilot policies, the same `sent` records) meets the same simulated vehicle as
`proxima sim-drone` (`sim.Vehicle`, executed by `sim.handlers.vehicle_command`); only
the wire is gone. There is no thread: the vehicle's physics catch up with the link's
clock whenever the link is used, and with a `ManualClock` time passes only when the test
says so, so a flight of seconds takes microseconds and lands where it must. The PX4
setpoint stream is replayed at `setpoint_hz` as the physics advance.

It is the test double of the controller's unit tests; the link itself (bytes, UDP,
retries, heartbeats) is tested against real simulator processes.
"""

from __future__ import annotations

import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

from proxima.drone.link import CommandResult, LinkError, Telemetry
from proxima.drone.mavlink.actions import MavlinkActions
from proxima.drone.mavlink.autopilot import Autopilot, for_heartbeat
from proxima.drone.mavlink.config import LinkConfig
from proxima.drone.mavlink.protocol import LANDED_STATES, RESULTS, mav
from proxima.drone.mavlink.setpoint import Setpoint
from proxima.drone.memory.clock import Clock, WallClock
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.handlers import Command, vehicle_command
from proxima.drone.sim.vehicle import Vehicle
from proxima.types import LinkState


class MemoryLink(MavlinkActions):
    """A simulated vehicle (`sim` says which autopilot and how it flies) behind the
    DroneLink interface, on `clock` (real time by default). Besides DroneLink: `cut()`
    and `restore()` the link, `sent` (every message it would have put on the wire) and
    `vehicle` (the simulated vehicle itself, to look at)."""

    def __init__(
        self,
        name: str = "memory",
        sim: SimConfig | None = None,
        *,
        clock: Clock | None = None,
        config: LinkConfig | None = None,
    ) -> None:
        super().__init__(config)
        self.name = name
        self.sim = sim or SimConfig()
        self.clock: Clock = clock or WallClock()
        self._lock = threading.RLock()
        self._t = self.clock.now()  # the vehicle's time: physics have run up to here
        self._vehicle = Vehicle(self.sim, clock=lambda: self._t, on_text=self._on_text)
        self._state = LinkState.CONNECTING
        self._closed_flag = False
        self._setpoint: Setpoint | None = None
        self._next_setpoint = 0.0
        self._last_target: tuple[float, float, float] | None = None
        self._frozen: Telemetry | None = None  # what was known when the link was cut
        self._status_text = ""
        self.sent: list[dict[str, Any]] = []
        self.sent_counts: Counter[str] = Counter()

    @property
    def vehicle(self) -> Vehicle:
        """The simulated vehicle itself, its physics run up to the clock's time."""
        with self._lock:
            self._advance()
            return self._vehicle

    # --- life cycle -------------------------------------------------------------------
    def connect(self, timeout: float = 10.0) -> None:
        if self._closed_flag:
            raise LinkError(f"{self.name}: closed")
        with self._lock:
            if self._state == LinkState.CONNECTING:
                self._state = LinkState.OK

    def close(self) -> None:
        self._closed_flag = True

    @property
    def state(self) -> LinkState:
        return self._state

    def cut(self) -> None:
        """The link goes silent, as after `lost_after_s` without a heartbeat: nothing
        more is sent, the setpoint stream stops, telemetry stays as it was."""
        with self._lock:
            self._frozen = self._snapshot()
            self._state = LinkState.LOST
            self._setpoint = None

    def restore(self) -> None:
        """The vehicle is heard again."""
        with self._lock:
            self._advance()
            self._frozen = None
            self._state = LinkState.OK

    def telemetry(self) -> Telemetry | None:
        with self._lock:
            if self._state == LinkState.CONNECTING:
                return None
            if self._frozen is not None:
                return self._frozen
            return self._snapshot()

    def sent_count(self) -> int:
        """How many messages this link has sent (no heartbeats exist here)."""
        return len(self.sent)

    def wait_for(
        self, predicate: Callable[[Telemetry], bool], timeout: float, poll: float = 0.02
    ) -> Telemetry | None:
        """As DroneLink.wait_for, on this link's clock (a ManualClock moves while waiting)."""
        deadline = self.clock.now() + timeout
        while True:
            tel = self.telemetry()
            if tel is not None and predicate(tel):
                return tel
            if self.clock.now() >= deadline or self.state == LinkState.LOST:
                return None
            self.clock.sleep(poll)

    # --- the transport primitives -------------------------------------------------------
    def _policy(self) -> Autopilot:
        return for_heartbeat(self._vehicle.fw.mav_autopilot)

    def _vehicle_type(self) -> int:
        return mav.MAV_TYPE_QUADROTOR

    def _closed(self) -> bool:
        return self._closed_flag

    def _has_vehicle(self) -> bool:
        return self._state != LinkState.CONNECTING

    def _now(self) -> float:
        return self.clock.now()

    def _pause(self, seconds: float) -> None:
        self.clock.sleep(seconds)

    def _command(
        self,
        action: str,
        command: int,
        params: list[float],
        sent: dict,
        timeout: float,
        retries: int,
    ) -> CommandResult:
        with self._lock:
            self._advance()
            t0 = time.perf_counter()
            self._record(sent)
            result = vehicle_command(self._vehicle, Command.of(command, params))
            latency = time.perf_counter() - t0
        if result is None:  # telemetry is read from the vehicle itself: no rates to set
            return CommandResult(
                action,
                "unsupported",
                False,
                1,
                latency,
                True,
                sent,
                "the in-memory vehicle has no telemetry streams",
            )
        ack = RESULTS.get(result, f"result_{result}")
        return CommandResult(action, ack, result == mav.MAV_RESULT_ACCEPTED, 1, latency, True, sent)

    def _set_stream(self, setpoint: Setpoint | None) -> None:
        with self._lock:
            self._advance()
            self._setpoint = setpoint
            if setpoint is not None:
                self._put(setpoint)
                self._next_setpoint = self._t + 1.0 / self.cfg.setpoint_hz

    def _streaming(self) -> bool:
        return self._setpoint is not None

    def _send_once(self, setpoint: Setpoint) -> None:
        with self._lock:
            self._advance()
            self._put(setpoint)

    def _echo(self) -> tuple[float, tuple[float, float, float] | None]:
        with self._lock:
            self._advance()
            target = self._vehicle.reported_target()
        return (self.clock.now(), target) if target is not None else (0.0, None)

    def _acknowledged(self, **fields: Any) -> None:
        """Nothing to do: telemetry is read from the vehicle itself, always current."""

    # --- the vehicle --------------------------------------------------------------------
    def _advance(self) -> None:
        """Run the physics (and the setpoint stream) up to the clock's time."""
        dt, interval = 1.0 / self.sim.physics_hz, 1.0 / self.cfg.setpoint_hz
        until = self.clock.now()
        while self._t + dt <= until + 1e-9:
            self._t += dt
            if self._setpoint is not None and self._t + 1e-9 >= self._next_setpoint:
                self._put(self._setpoint)
                self._next_setpoint = max(self._next_setpoint + interval, self._t)
            self._vehicle.step(dt)

    def _put(self, sp: Setpoint) -> None:
        """One SET_POSITION_TARGET_LOCAL_NED to the vehicle (none while the link is lost)."""
        if self._state != LinkState.OK:
            return
        self._record(
            {
                "msg": "SET_POSITION_TARGET_LOCAL_NED",
                "frame": "LOCAL_NED",
                "x": sp.position[0],
                "y": sp.position[1],
                "z": sp.position[2],
                "yaw": sp.yaw,
            }
        )
        self._vehicle.position_target(
            mav.MAV_FRAME_LOCAL_NED, sp.type_mask, sp.position, (0.0, 0.0, 0.0), sp.yaw or 0.0
        )
        sp.sent_at = self._t

    def _record(self, sent: dict[str, Any]) -> None:
        self.sent.append(sent)
        self.sent_counts[sent["msg"]] += 1

    def _on_text(self, text: str, severity: int) -> None:
        self._status_text = text[:50]

    def _snapshot(self) -> Telemetry:
        self._advance()
        v = self._vehicle
        target = v.reported_target()
        if target is not None:
            self._last_target = target  # like a link, the last reported target stays
        x, y, z = v.pos
        return Telemetry(
            received=self._t,
            system_id=self.sim.sysid,
            autopilot=self._policy().name,
            mode=v.mode,
            armed=v.armed,
            landed=LANDED_STATES.get(v.landed, "unknown"),
            position=(x, y, z),
            velocity=(v.vel[0], v.vel[1], v.vel[2]),
            attitude=v.attitude(),
            battery_pct=float(round(v.battery)),
            battery_voltage=int(v.battery_voltage() * 1000) / 1000.0,
            global_position=v.global_position(),
            relative_alt=-z,
            position_target=self._last_target,
            home=self.sim.home,
            status_text=self._status_text,
        )
