"""AUTOPILOT_VERSION: who the simulated vehicle says it is and what it can do.

Sent on MAV_CMD_REQUEST_MESSAGE (148) and MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES. The
flight software version is the autopilot release whose documented behaviour the
simulator models (ArduCopter 4.5.0, PX4 1.15.0), marked as a development build, and
the custom version (the autopilot's git hash field) reads "proxsim" so that a tool that
prints it shows what answered. The capabilities are the protocols the simulator
implements; MAVLink FTP is not one of them (its requests are refused, `ftp`).
"""

from __future__ import annotations

from typing import Any

from proxima.drone.mavlink.protocol import mav
from proxima.drone.sim.vehicle import Vehicle

CUSTOM_VERSION = list(b"proxsim\0")  # 8 bytes, where an autopilot puts its git hash
_COMMON = (
    mav.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
    | mav.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
    | mav.MAV_PROTOCOL_CAPABILITY_MISSION_INT
    | mav.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | mav.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
    | mav.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
    | mav.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    | mav.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
    | mav.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
)


def capabilities(v: Vehicle) -> int:
    """MAV_PROTOCOL_CAPABILITY bits, with the parameter encoding of the autopilot."""
    if v.params.bytewise:
        return _COMMON | mav.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    return _COMMON | mav.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST


def flight_sw_version(v: Vehicle) -> int:
    """major.minor.patch and FIRMWARE_VERSION_TYPE_DEV packed as MAVLink does."""
    major, minor, patch = v.fw.flight_sw_version
    return (major << 24) | (minor << 16) | (patch << 8) | mav.FIRMWARE_VERSION_TYPE_DEV


def send_autopilot_version(m: Any, v: Vehicle, t: int) -> None:
    """One AUTOPILOT_VERSION (the telemetry encoder's signature)."""
    m.autopilot_version_send(
        capabilities(v),
        flight_sw_version(v),
        0,
        0,
        0,
        CUSTOM_VERSION,
        [0] * 8,
        [0] * 8,
        0,
        0,
        0x50524F58_00000000 | v.cfg.sysid,  # uid: "PROX" and the system id
    )
