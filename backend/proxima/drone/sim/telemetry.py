"""What the simulated vehicle reports: each telemetry message's encoder and its rate.

Rates start at `SimConfig.rate_hz` (HEARTBEAT at 1 Hz, HOME_POSITION only on request)
and follow SET_MESSAGE_INTERVAL; GET_MESSAGE_INTERVAL and REQUEST_MESSAGE are answered
here too. A new message is one more entry in `_ENCODERS`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

from proxima.drone.mavlink.protocol import POSITION_ONLY, mav
from proxima.drone.sim.vehicle import Vehicle


def _heartbeat(m: Any, v: Vehicle, t: int) -> None:
    base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    base |= mav.MAV_MODE_FLAG_STABILIZE_ENABLED | mav.MAV_MODE_FLAG_GUIDED_ENABLED
    if v.armed:
        base |= mav.MAV_MODE_FLAG_SAFETY_ARMED
    status = mav.MAV_STATE_ACTIVE if v.armed else mav.MAV_STATE_STANDBY
    m.heartbeat_send(
        mav.MAV_TYPE_QUADROTOR, v.fw.mav_autopilot, base, v.fw.custom_mode(v.mode), status
    )


def _sys_status(m: Any, v: Vehicle, t: int) -> None:
    sensors = 0x3FFF
    m.sys_status_send(
        sensors,
        sensors,
        sensors,
        250,
        int(v.battery_voltage() * 1000),
        int(v.battery_current() * 100),
        round(v.battery),
        0,
        0,
        0,
        0,
        0,
        0,
    )


def _attitude(m: Any, v: Vehicle, t: int) -> None:
    roll, pitch, yaw = v.attitude()
    m.attitude_send(t, roll, pitch, yaw, 0.0, 0.0, 0.0)


def _local_position(m: Any, v: Vehicle, t: int) -> None:
    m.local_position_ned_send(t, *v.pos, *v.vel)


def _global_position(m: Any, v: Vehicle, t: int) -> None:
    lat, lon, alt = v.global_position()
    vx, vy, vz = v.vel
    hdg = int(math.degrees(v.yaw) % 360 * 100)
    m.global_position_int_send(
        t,
        int(lat * 1e7),
        int(lon * 1e7),
        int(alt * 1000),
        int(-v.pos[2] * 1000),
        int(vx * 100),
        int(vy * 100),
        int(vz * 100),
        hdg,
    )


def _extended_sys_state(m: Any, v: Vehicle, t: int) -> None:
    m.extended_sys_state_send(mav.MAV_VTOL_STATE_UNDEFINED, v.landed)


def _position_target(m: Any, v: Vehicle, t: int) -> None:
    target = v.reported_target()
    if target is None:
        return  # nothing to report outside the guided mode: sent as nothing
    m.position_target_local_ned_send(
        t, mav.MAV_FRAME_LOCAL_NED, POSITION_ONLY, *target, 0, 0, 0, 0, 0, 0, v.yaw, 0
    )


def _vfr_hud(m: Any, v: Vehicle, t: int) -> None:
    vx, vy, vz = v.vel
    hdg = int(math.degrees(v.yaw) % 360)
    throttle = 50 if v.motors_on else 0
    m.vfr_hud_send(math.hypot(vx, vy), math.hypot(vx, vy), hdg, throttle, -v.pos[2], -vz)


def _home_position(m: Any, v: Vehicle, t: int) -> None:
    lat, lon, alt = v.cfg.home
    m.home_position_send(
        int(lat * 1e7), int(lon * 1e7), int(alt * 1000), 0, 0, 0, [1, 0, 0, 0], 0, 0, 0
    )


Encoder = Callable[[Any, Vehicle, int], None]  # (MAVLink encoder, vehicle, boot ms)

_ENCODERS: dict[int, Encoder] = {
    mav.MAVLINK_MSG_ID_HEARTBEAT: _heartbeat,
    mav.MAVLINK_MSG_ID_SYS_STATUS: _sys_status,
    mav.MAVLINK_MSG_ID_ATTITUDE: _attitude,
    mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED: _local_position,
    mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: _global_position,
    mav.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: _extended_sys_state,
    mav.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED: _position_target,
    mav.MAVLINK_MSG_ID_VFR_HUD: _vfr_hud,
    mav.MAVLINK_MSG_ID_HOME_POSITION: _home_position,
}
_TELEMETRY_COMMANDS = {
    mav.MAV_CMD_SET_MESSAGE_INTERVAL,
    mav.MAV_CMD_GET_MESSAGE_INTERVAL,
    mav.MAV_CMD_REQUEST_MESSAGE,
}


class TelemetryStreams:
    """The vehicle's telemetry schedule; `stream(now)` sends what is due."""

    def __init__(self, vehicle: Vehicle, encoder: Any, rate_hz: float, physics_hz: float) -> None:
        self.vehicle = vehicle
        self.m = encoder  # a pymavlink MAVLink object: its *_send methods write packets
        self.rate_hz = rate_hz
        self.physics_hz = physics_hz
        self.t0 = time.monotonic()
        default = 1.0 / rate_hz if rate_hz > 0 else 0.0
        self.intervals: dict[int, float] = dict.fromkeys(_ENCODERS, default)
        self.intervals[mav.MAVLINK_MSG_ID_HEARTBEAT] = 1.0
        self.intervals[mav.MAVLINK_MSG_ID_HOME_POSITION] = 0.0
        self.next_send: dict[int, float] = dict.fromkeys(self.intervals, self.t0)

    def boot_ms(self) -> int:
        return int((time.monotonic() - self.t0) * 1000) & 0xFFFFFFFF

    def stream(self, now: float) -> None:
        """Send every message whose interval has come round."""
        for msg_id, interval in self.intervals.items():
            if interval <= 0.0 or now < self.next_send[msg_id]:
                continue
            nxt = self.next_send[msg_id] + interval
            self.next_send[msg_id] = nxt if nxt > now else now + interval
            self.send_one(msg_id)

    def send_one(self, msg_id: int) -> bool:
        """Send one telemetry message now; False if this vehicle does not produce it."""
        encoder = _ENCODERS.get(msg_id)
        if encoder is None:
            return False
        encoder(self.m, self.vehicle, self.boot_ms())
        return True

    def handles(self, command: int) -> bool:
        """Whether `command` is a telemetry command (answered by `command()`)."""
        return command in _TELEMETRY_COMMANDS

    def command(self, command: int, p: Sequence[float]) -> int:
        """SET_MESSAGE_INTERVAL, GET_MESSAGE_INTERVAL or REQUEST_MESSAGE; a MAV_RESULT."""
        msg_id = int(p[0])
        if command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
            return self._set_interval(msg_id, p[1])
        if command == mav.MAV_CMD_GET_MESSAGE_INTERVAL:
            if msg_id not in self.intervals:
                return mav.MAV_RESULT_DENIED
            interval = self.intervals[msg_id]
            self.m.message_interval_send(msg_id, int(interval * 1e6) if interval else -1)
            return mav.MAV_RESULT_ACCEPTED
        if self.send_one(msg_id):  # REQUEST_MESSAGE
            return mav.MAV_RESULT_ACCEPTED
        return mav.MAV_RESULT_DENIED

    def _set_interval(self, msg_id: int, interval_us: float) -> int:
        if msg_id not in self.intervals:
            return mav.MAV_RESULT_DENIED
        if interval_us < 0:
            self.intervals[msg_id] = 0.0
        elif interval_us == 0:
            default = 1.0 / self.rate_hz if self.rate_hz > 0 else 0.0
            self.intervals[msg_id] = 1.0 if msg_id == mav.MAVLINK_MSG_ID_HEARTBEAT else default
        else:
            self.intervals[msg_id] = max(interval_us / 1e6, 1.0 / self.physics_hz)
        self.next_send[msg_id] = time.monotonic()
        return mav.MAV_RESULT_ACCEPTED
