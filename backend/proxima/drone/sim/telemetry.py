"""What the simulated vehicle reports: each telemetry message's encoder and its rate.

Rates start at `SimConfig.rate_hz` (HEARTBEAT and MISSION_CURRENT at 1 Hz, HOME_POSITION
at 0.5 Hz as PX4 streams it, AUTOPILOT_VERSION only on request) and follow
SET_MESSAGE_INTERVAL; GET_MESSAGE_INTERVAL, REQUEST_MESSAGE, GET_HOME_POSITION and
REQUEST_AUTOPILOT_CAPABILITIES are answered here too. A new message is one more entry
in `ENCODERS`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from proxima.drone.mavlink.fields import integer, mav_bool
from proxima.drone.mavlink.protocol import POSITION_ONLY, mav
from proxima.drone.sim.handlers import Command
from proxima.drone.sim.vehicle import Vehicle
from proxima.drone.sim.version import send_autopilot_version

# SYS_STATUS sensors the simulated vehicle has (all present, enabled and healthy).
SENSORS = (
    mav.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | mav.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mav.MAV_SYS_STATUS_SENSOR_3D_MAG
    | mav.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | mav.MAV_SYS_STATUS_SENSOR_GPS
    | mav.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | mav.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
    | mav.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | mav.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
    | mav.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | mav.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    | mav.MAV_SYS_STATUS_AHRS
    | mav.MAV_SYS_STATUS_SENSOR_BATTERY
)
MAX_MESSAGE_ID = 16_777_215  # MAVLink 2's 24-bit message ids


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
    # The geofence is present; enabled when its parameters turn it on; unhealthy while
    # breached. The pre-arm bit is healthy when arming would pass (MAVSDK's is_armable).
    fence = mav.MAV_SYS_STATUS_GEOFENCE
    prearm = mav.MAV_SYS_STATUS_PREARM_CHECK
    enabled = SENSORS | prearm | (fence if v.fw.params.fence(v.params) else 0)
    health = SENSORS | (fence if not v.failsafes.fence_breached else 0)
    health |= prearm if v.armable() or v.armed else 0
    m.sys_status_send(
        SENSORS | fence | prearm,
        enabled,
        health,
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
        round(lat * 1e7), round(lon * 1e7), round(alt * 1000), 0, 0, 0, [1, 0, 0, 0], 0, 0, 0
    )


def _mission_current(m: Any, v: Vehicle, t: int) -> None:
    total = len(v.missions.lists[0])
    m.mission_current_send(min(v.missions.current, 0xFFFF), total)


Encoder = Callable[[Any, Vehicle, int], None]  # (MAVLink encoder, vehicle, boot ms)

ENCODERS: dict[int, Encoder] = {
    mav.MAVLINK_MSG_ID_HEARTBEAT: _heartbeat,
    mav.MAVLINK_MSG_ID_SYS_STATUS: _sys_status,
    mav.MAVLINK_MSG_ID_ATTITUDE: _attitude,
    mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED: _local_position,
    mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: _global_position,
    mav.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: _extended_sys_state,
    mav.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED: _position_target,
    mav.MAVLINK_MSG_ID_VFR_HUD: _vfr_hud,
    mav.MAVLINK_MSG_ID_HOME_POSITION: _home_position,
    mav.MAVLINK_MSG_ID_MISSION_CURRENT: _mission_current,
    mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION: send_autopilot_version,
}
# Intervals (s) other than the default rate; 0: only on request.
FIXED_INTERVALS = {
    mav.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    mav.MAVLINK_MSG_ID_MISSION_CURRENT: 1.0,
    mav.MAVLINK_MSG_ID_HOME_POSITION: 2.0,
    mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION: 0.0,
}


class TelemetryStreams:
    """The vehicle's telemetry schedule; `stream(now)` sends what is due."""

    def __init__(self, vehicle: Vehicle, encoder: Any, rate_hz: float, physics_hz: float) -> None:
        self.vehicle = vehicle
        self.m = encoder  # a pymavlink MAVLink object: its *_send methods write packets
        self.rate_hz = rate_hz
        self.physics_hz = physics_hz
        self.t0 = time.monotonic()
        self.intervals = {msg_id: self._default(msg_id) for msg_id in ENCODERS}
        self.next_send: dict[int, float] = dict.fromkeys(self.intervals, self.t0)
        self.requested: list[int] = []  # sent after the COMMAND_ACK (`send_requested`)
        self.messages: dict[str, Callable[[Any], None]] = {}  # commands only, below
        self.commands: dict[int, Callable[[Command], int]] = {
            mav.MAV_CMD_SET_MESSAGE_INTERVAL: self._set_interval,
            mav.MAV_CMD_GET_MESSAGE_INTERVAL: self._get_interval,
            mav.MAV_CMD_REQUEST_MESSAGE: self._request_message,
            mav.MAV_CMD_GET_HOME_POSITION: self._get_home,
            mav.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: self._capabilities,
        }

    def _default(self, msg_id: int) -> float:
        if msg_id in FIXED_INTERVALS:
            return FIXED_INTERVALS[msg_id]
        return 1.0 / self.rate_hz if self.rate_hz > 0 else 0.0

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
        encoder = ENCODERS.get(msg_id)
        if encoder is None:
            return False
        encoder(self.m, self.vehicle, self.boot_ms())
        return True

    def tick(self, now: float) -> None:
        self.stream(now)

    def send_requested(self) -> None:
        """Send the messages a command asked for. The server calls this after the
        command's COMMAND_ACK: the answer to REQUEST_MESSAGE follows its ACK."""
        requested, self.requested = self.requested, []
        for msg_id in requested:
            self.send_one(msg_id)

    # --- commands (each param untrusted: a bad one is DENIED) ---------------------------
    def _set_interval(self, c: Command) -> int:
        msg_id = integer(c.params[0], 0, MAX_MESSAGE_ID)
        interval_us = c.params[1]
        if msg_id not in self.intervals or not math.isfinite(interval_us) or interval_us < -1:
            return mav.MAV_RESULT_DENIED
        if interval_us < 0:
            self.intervals[msg_id] = 0.0
        elif interval_us == 0:
            self.intervals[msg_id] = self._default(msg_id)
        else:
            self.intervals[msg_id] = max(interval_us / 1e6, 1.0 / self.physics_hz)
        self.next_send[msg_id] = time.monotonic()
        return mav.MAV_RESULT_ACCEPTED

    def _get_interval(self, c: Command) -> int:
        msg_id = integer(c.params[0], 0, MAX_MESSAGE_ID)
        if msg_id is None or msg_id not in self.intervals:
            return mav.MAV_RESULT_DENIED
        interval = self.intervals[msg_id]
        self.m.message_interval_send(msg_id, int(interval * 1e6) if interval else -1)
        return mav.MAV_RESULT_ACCEPTED

    def _request_message(self, c: Command) -> int:
        msg_id = integer(c.params[0], 0, MAX_MESSAGE_ID)
        if msg_id is None or msg_id not in ENCODERS:
            return mav.MAV_RESULT_DENIED
        self.requested.append(msg_id)
        return mav.MAV_RESULT_ACCEPTED

    def _get_home(self, c: Command) -> int:
        self.requested.append(mav.MAVLINK_MSG_ID_HOME_POSITION)
        return mav.MAV_RESULT_ACCEPTED

    def _capabilities(self, c: Command) -> int:
        wanted = mav_bool(c.params[0], nan=True)
        if wanted is None:
            return mav.MAV_RESULT_DENIED
        if wanted:
            self.requested.append(mav.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        return mav.MAV_RESULT_ACCEPTED
