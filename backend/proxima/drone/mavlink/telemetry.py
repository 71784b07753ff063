"""Telemetry decoding: the vehicle's MAVLink messages into one `Telemetry` snapshot.

`TelemetryStore.decode` is called by the link's owner thread for every message of the
followed vehicle; `snapshot()` may be called from any thread. The HEARTBEAT also says
which autopilot policy the link uses from then on.
"""

from __future__ import annotations

import threading
from typing import Any

from proxima.drone.link import Telemetry
from proxima.drone.mavlink.autopilot import ARDUPILOT, Autopilot, for_heartbeat
from proxima.drone.mavlink.fields import finite, text, valid_lat_lon
from proxima.drone.mavlink.protocol import LANDED_STATES, NOT_VEHICLES, mav, mavutil


class TelemetryStore:
    """The newest decoded fields of one vehicle, guarded by a lock."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._fields: dict[str, Any] = {}
        self.last_heartbeat = 0.0  # monotonic time of the vehicle's newest HEARTBEAT
        self.target_echo_at = 0.0  # ... of its newest POSITION_TARGET_LOCAL_NED
        self.autopilot: Autopilot = ARDUPILOT
        self.vehicle_type = mav.MAV_TYPE_QUADROTOR

    def snapshot(self) -> Telemetry | None:
        """The newest telemetry, or None before the first heartbeat."""
        with self._lock:
            if not self.last_heartbeat:
                return None
            return Telemetry(**self._fields)

    def get(self, name: str, default: Any = None) -> Any:
        """One field (a Telemetry attribute name) as last decoded."""
        with self._lock:
            return self._fields.get(name, default)

    def echo(self) -> tuple[float, tuple[float, float, float] | None]:
        """When the newest position-target echo came, and what it said."""
        with self._lock:
            return self.target_echo_at, self._fields.get("position_target")

    def update(self, **fields: Any) -> None:
        """Record facts the vehicle established another way (an accepted COMMAND_ACK),
        so callers need not wait for the next heartbeat to see them."""
        with self._lock:
            self._fields.update(fields)

    def decode(self, msg: Any, now: float, heartbeat_component: int) -> None:
        """Fold one message of the followed vehicle into the fields (`now` is monotonic).
        Heartbeats of other components of that system (a gimbal, a camera) are ignored,
        and so is every value that is not what MAVLink allows (a non-finite position, a
        latitude beyond the poles): the field keeps what the vehicle said last."""
        kind = msg.get_type()
        if kind == "HEARTBEAT" and msg.get_srcComponent() != heartbeat_component:
            return
        f = self._fields
        with self._lock:
            if kind == "HEARTBEAT":
                if msg.type in NOT_VEHICLES or msg.autopilot == mav.MAV_AUTOPILOT_INVALID:
                    return
                self.last_heartbeat = now
                self.autopilot = for_heartbeat(msg.autopilot)
                self.vehicle_type = msg.type
                f["system_id"] = msg.get_srcSystem()
                f["autopilot"] = self.autopilot.name
                f["mode"] = mavutil.mode_string_v10(msg)
                f["armed"] = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
                f.setdefault("landed", "unknown")
            elif kind == "LOCAL_POSITION_NED":
                if not finite(msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz):
                    return
                f["position"] = (msg.x, msg.y, msg.z)
                f["velocity"] = (msg.vx, msg.vy, msg.vz)
            elif kind == "ATTITUDE":
                if not finite(msg.roll, msg.pitch, msg.yaw):
                    return
                f["attitude"] = (msg.roll, msg.pitch, msg.yaw)
            elif kind == "SYS_STATUS":
                if 0 <= msg.battery_remaining <= 100:
                    f["battery_pct"] = float(msg.battery_remaining)
                if msg.voltage_battery != 0xFFFF:
                    f["battery_voltage"] = msg.voltage_battery / 1000.0
            elif kind == "EXTENDED_SYS_STATE":
                f["landed"] = LANDED_STATES.get(msg.landed_state, "unknown")
            elif kind == "GLOBAL_POSITION_INT":
                lat, lon = msg.lat / 1e7, msg.lon / 1e7
                if not valid_lat_lon(lat, lon):
                    return
                f["global_position"] = (lat, lon, msg.alt / 1000.0)
                f["relative_alt"] = msg.relative_alt / 1000.0
            elif kind == "POSITION_TARGET_LOCAL_NED":
                if not finite(msg.x, msg.y, msg.z):
                    return
                f["position_target"] = (msg.x, msg.y, msg.z)
                self.target_echo_at = now
            elif kind == "HOME_POSITION":
                lat, lon = msg.latitude / 1e7, msg.longitude / 1e7
                if not valid_lat_lon(lat, lon):
                    return
                f["home"] = (lat, lon, msg.altitude / 1000.0)
            elif kind == "STATUSTEXT":
                f["status_text"] = text(msg.text, 50)
            else:
                return
            f["received"] = now
