"""The DroneLink commands in MAVLink terms, under the vehicle's autopilot policy.

`MavlinkActions` turns each DroneLink method into COMMAND_LONGs and position targets
(what is sent, in what order, what counts as confirmed) and leaves how they travel to
its subclasses: `MavlinkLink` puts them on a pymavlink connection, `MemoryLink` hands
them to a simulated vehicle in the same process. Both therefore log the same `sent`
records and answer with the same acks.
"""

from __future__ import annotations

import math
import time
from abc import abstractmethod
from typing import Any

from proxima.drone.link import CommandResult, DroneLink, Telemetry
from proxima.drone.mavlink.autopilot import Autopilot
from proxima.drone.mavlink.config import LinkConfig
from proxima.drone.mavlink.protocol import (
    FORCE_DISARM_MAGIC,
    ZERO_PADDED_COMMANDS,
    command_name,
    mav,
)
from proxima.drone.mavlink.setpoint import Setpoint
from proxima.types import LinkState


class MavlinkActions(DroneLink):
    """DroneLink over MAVLink commands; subclasses supply the transport primitives."""

    cfg: LinkConfig

    def __init__(self, config: LinkConfig | None) -> None:
        self.cfg = config or LinkConfig()
        if self.cfg.setpoint_hz <= 2.0:
            raise ValueError("setpoint_hz must be above 2 Hz (PX4 leaves OFFBOARD otherwise)")

    # --- what a transport supplies ---------------------------------------------------------
    @abstractmethod
    def _policy(self) -> Autopilot:
        """The autopilot policy of the vehicle heard (ArduPilot before any heartbeat)."""

    @abstractmethod
    def _vehicle_type(self) -> int:
        """The vehicle's MAV_TYPE from its heartbeat."""

    @abstractmethod
    def _closed(self) -> bool:
        """Whether `close()` was called."""

    @abstractmethod
    def _has_vehicle(self) -> bool:
        """Whether a vehicle to address is known."""

    @abstractmethod
    def _command(
        self,
        action: str,
        command: int,
        params: list[float],
        sent: dict,
        timeout: float,
        retries: int,
    ) -> CommandResult:
        """Send one COMMAND_LONG (7 params) and wait for its COMMAND_ACK."""

    @abstractmethod
    def _set_stream(self, setpoint: Setpoint | None) -> None:
        """Stream `setpoint` (sent at once, then at `setpoint_hz`), or stop streaming."""

    @abstractmethod
    def _streaming(self) -> bool:
        """Whether a position target is being streamed."""

    @abstractmethod
    def _send_once(self, setpoint: Setpoint) -> None:
        """Send one position target."""

    @abstractmethod
    def _echo(self) -> tuple[float, tuple[float, float, float] | None]:
        """When (on `_now()`'s clock) the vehicle last reported its position target, and
        that target."""

    @abstractmethod
    def _acknowledged(self, **fields: Any) -> None:
        """Record what an accepted COMMAND_ACK established (the vehicle's own answer),
        so that callers need not wait up to a second for the next heartbeat to show it."""

    def _now(self) -> float:
        """The clock waits are measured on."""
        return time.monotonic()

    def _pause(self, seconds: float) -> None:
        """Let `seconds` pass (the vehicle keeps flying meanwhile)."""
        time.sleep(seconds)

    # --- the autopilot's facts ---------------------------------------------------------------
    @property
    def autopilot(self) -> str:
        """The autopilot heard: "ardupilot" or "px4"."""
        return self._policy().name

    def guided_mode(self) -> str:
        return self._policy().guided_mode

    def holding_modes(self) -> frozenset[str]:
        return self._policy().holding_modes

    # --- commands --------------------------------------------------------------------------
    def command_long(
        self,
        action: str,
        command: int,
        params: list[float] | tuple[float, ...] = (),
        *,
        timeout: float | None = None,
        retries: int | None = None,
    ) -> CommandResult:
        """Send COMMAND_LONG and wait for its COMMAND_ACK, resending (with an increasing
        `confirmation`) after each `timeout` up to `retries` times. Params not given are
        sent as the autopilot expects an unused one (`Autopilot.unused_param`)."""
        pad = 0.0 if command in ZERO_PADDED_COMMANDS else self._policy().unused_param
        p = [float(x) for x in params] + [pad] * (7 - len(params))
        sent = {"msg": "COMMAND_LONG", "command": command_name(command), "params": p}
        refusal = self._refusal(action, sent)
        if refusal is not None:
            return refusal
        return self._command(
            action,
            command,
            p,
            sent,
            self.cfg.ack_timeout_s if timeout is None else timeout,
            self.cfg.retries if retries is None else retries,
        )

    def _refusal(self, action: str, sent: dict) -> CommandResult | None:
        """Why nothing can be sent now, or None."""
        if self.state == LinkState.LOST:
            return CommandResult(
                action, "link_lost", False, sent=sent, detail="link lost: nothing sent"
            )
        if self.state != LinkState.OK or not self._has_vehicle():
            return CommandResult(
                action, "not_connected", False, sent=sent, detail="no heartbeat yet: nothing sent"
            )
        if self._closed():
            return CommandResult(action, "not_connected", False, sent=sent, detail="closed")
        return None

    def set_mode(self, mode: str) -> CommandResult:
        mode = mode.upper()
        tel = self.telemetry()
        if tel is None:
            return CommandResult(f"mode {mode}", "not_connected", False)
        policy = self._policy()
        params = policy.mode_params(mode, self._vehicle_type())
        if params is None:
            return CommandResult(
                f"mode {mode}", "unknown_mode", False, detail=f"{policy.label} has no mode {mode!r}"
            )
        result = self.command_long(f"mode {mode}", mav.MAV_CMD_DO_SET_MODE, params)
        if result.ok:
            self._acknowledged(mode=mode)
        return result

    def enter_guided(self) -> CommandResult:
        tel = self.telemetry()
        if tel is None:
            return CommandResult("enter_guided", "not_connected", False)
        policy = self._policy()
        if not policy.streams_setpoints:
            return self.set_mode(policy.guided_mode)
        if tel.position is None:
            return CommandResult(
                "enter_guided",
                "no_position",
                False,
                detail=f"{policy.guided_mode} needs a local position to hold",
            )
        if not self._streaming():
            self._set_stream(Setpoint(tel.position, tel.yaw))
            self._pause(3.5 / self.cfg.setpoint_hz)  # the stream must run before the switch
        return self.set_mode(policy.guided_mode)

    def arm(self) -> CommandResult:
        result = self.command_long("arm", mav.MAV_CMD_COMPONENT_ARM_DISARM, [1])
        if result.ok:
            self._acknowledged(armed=True)
        return result

    def disarm(self, force: bool = False) -> CommandResult:
        self._set_stream(None)
        magic = FORCE_DISARM_MAGIC if force else 0
        action = "force_disarm" if force else "disarm"
        result = self.command_long(action, mav.MAV_CMD_COMPONENT_ARM_DISARM, [0, magic])
        if result.ok:
            self._acknowledged(armed=False)
        return result

    def takeoff(self, altitude_m: float) -> CommandResult:
        if not (math.isfinite(altitude_m) and altitude_m > 0):
            return _invalid("takeoff", f"altitude must be a positive number, got {altitude_m}")
        tel = self.telemetry()
        if tel is None:
            return CommandResult("takeoff", "not_connected", False)
        policy = self._policy()
        altitude = policy.takeoff_altitude(tel, altitude_m)
        if altitude is None:
            return CommandResult(
                "takeoff",
                "no_position",
                False,
                detail=f"{policy.label} takeoff needs the home altitude",
            )
        steps = [self.enter_guided, self.arm] if policy.takeoff_in_guided else [self.arm]
        if policy.hold_mode is not None and tel.mode not in policy.holding_modes:
            # PX4 arms from its holding modes only (as MAVSDK does: Hold before arming
            # after a landing or an RTL).
            steps.insert(0, lambda: self.set_mode(str(policy.hold_mode)))
        for step in steps:
            result = step()
            if not result.ok:
                return CommandResult(
                    "takeoff",
                    result.ack,
                    False,
                    result.attempts,
                    result.latency_s,
                    result.confirmed,
                    result.sent,
                    f"{result.action} failed: {result.detail}",
                )
        return self.command_long(
            "takeoff", mav.MAV_CMD_NAV_TAKEOFF, policy.takeoff_params(altitude)
        )

    def goto_local(
        self, north: float, east: float, down: float, yaw: float | None = None
    ) -> CommandResult:
        if not all(math.isfinite(v) for v in (north, east, down, 0.0 if yaw is None else yaw)):
            return _invalid("goto", f"target ({north}, {east}, {down}, yaw {yaw}) not finite")
        sent = {
            "msg": "SET_POSITION_TARGET_LOCAL_NED",
            "frame": "LOCAL_NED",
            "x": north,
            "y": east,
            "z": down,
            "yaw": yaw,
        }
        refusal = self._refusal("goto", sent)
        if refusal is not None:
            return refusal
        tel = self.telemetry()
        guided = self.guided_mode()
        if tel is not None and tel.mode != guided:
            return CommandResult(
                "goto",
                "wrong_mode",
                False,
                sent=sent,
                detail=f"vehicle in {tel.mode}, not {guided}: call enter_guided() first; "
                "nothing sent",
            )
        target = (float(north), float(east), float(down))
        t0 = self._now()
        if self._policy().streams_setpoints:
            self._set_stream(Setpoint(target, yaw))
        else:
            self._send_once(Setpoint(target, yaw))
        deadline = t0 + self.cfg.echo_timeout_s
        while self._now() < deadline:
            echo_at, echo = self._echo()
            if echo_at > t0 and echo is not None and math.dist(echo, target) < 0.05:
                return CommandResult("goto", "echoed", True, 1, self._now() - t0, True, sent)
            self._pause(0.005)
        return CommandResult(
            "goto",
            "sent",
            True,
            1,
            None,
            False,
            sent,
            "no POSITION_TARGET_LOCAL_NED echo: unconfirmed",
        )

    def hold(self) -> CommandResult:
        tel = self.telemetry()
        if tel is None:
            return CommandResult("hold", "not_connected", False)
        policy = self._policy()
        if policy.hold_mode is not None:
            self._set_stream(None)
            return self.set_mode(policy.hold_mode)
        if tel.position is None:
            return self.set_mode(policy.brake_mode)
        if tel.mode != policy.guided_mode:
            result = self.set_mode(policy.guided_mode)
            if not result.ok:
                return result
        stop = _stopping_point(tel, self.cfg.brake_accel_m_s2)
        result = self.goto_local(*stop)
        return CommandResult(
            "hold",
            result.ack,
            result.ok,
            result.attempts,
            result.latency_s,
            result.confirmed,
            result.sent,
            result.detail,
        )

    def change_speed(self, speed_m_s: float) -> CommandResult:
        if not (math.isfinite(speed_m_s) and speed_m_s > 0):
            return _invalid("change_speed", f"speed must be a positive number, got {speed_m_s}")
        return self.command_long("change_speed", mav.MAV_CMD_DO_CHANGE_SPEED, [1, speed_m_s, -1])

    def land(self) -> CommandResult:
        self._set_stream(None)
        return self.command_long(
            "land", mav.MAV_CMD_NAV_LAND, [0, 0, 0, math.nan, math.nan, math.nan, 0]
        )


def _invalid(action: str, detail: str) -> CommandResult:
    """A command refused before sending: its arguments cannot be flown."""
    return CommandResult(action, "invalid", False, detail=f"{detail}; nothing sent")


def _stopping_point(tel: Telemetry, accel: float) -> tuple[float, float, float]:
    """Where a vehicle braking at `accel` stops from its current velocity."""
    assert tel.position is not None
    a = max(accel, 0.1)
    vel = tel.velocity or (0.0, 0.0, 0.0)
    n, e, d = (p + v * abs(v) / (2 * a) for p, v in zip(tel.position, vel, strict=True))
    return n, e, d
