"""The MAVLink facts the link and the simulator share, each defined once.

Both sides import the dialect from here, so they speak the same MAVLink 2
`ardupilotmega` dialect; mode numbers come from pymavlink's own tables (ArduCopter's
`mode_mapping_acm`, PX4's `px4_map`), type masks from the dialect's
POSITION_TARGET_TYPEMASK bits, result and landed-state names from their enums.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from types import MappingProxyType

os.environ.setdefault("MAVLINK20", "1")  # speak MAVLink 2, as ArduPilot and PX4 do
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav

mavutil.set_dialect("ardupilotmega")

__all__ = [
    "ARDUCOPTER_MODES",
    "FORCE_DISARM_MAGIC",
    "IGNORE_ACCELERATION",
    "IGNORE_POSITION",
    "IGNORE_VELOCITY",
    "IGNORE_YAW",
    "IGNORE_YAW_RATE",
    "LANDED_STATES",
    "NOT_VEHICLES",
    "POSITION_ONLY",
    "PX4_MAIN_MODE_AUTO",
    "PX4_MODES",
    "RESULTS",
    "STREAMED",
    "ZERO_PADDED_COMMANDS",
    "command_name",
    "mav",
    "mavutil",
    "px4_custom_mode",
    "px4_main_sub",
]

# param2 of MAV_CMD_COMPONENT_ARM_DISARM that disarms in flight (ArduPilot and PX4).
FORCE_DISARM_MAGIC = 21196

# ArduCopter custom mode numbers by name (pymavlink's table for a quadrotor).
ARDUCOPTER_MODES: Mapping[str, int] = MappingProxyType(
    mavutil.mode_mapping_byname(mav.MAV_TYPE_QUADROTOR) or {}
)
# PX4 modes by name: (base_mode, custom main mode, custom sub mode), pymavlink's table.
PX4_MODES: Mapping[str, tuple[int, int, int]] = MappingProxyType(dict(mavutil.px4_map))


PX4_MAIN_MODE_AUTO = mavutil.PX4_CUSTOM_MAIN_MODE_AUTO  # its modes differ by sub mode


def px4_custom_mode(main: int, sub: int) -> int:
    """PX4's HEARTBEAT `custom_mode`: the main mode in bits 16-23, the sub mode in 24-31."""
    return (main << 16) | (sub << 24)


def px4_main_sub(custom_mode: int) -> tuple[int, int]:
    """The (main, sub) mode of a PX4 `custom_mode` (the inverse of `px4_custom_mode`)."""
    return (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF


# SET_POSITION_TARGET_LOCAL_NED type mask bits (set = ignore that field).
IGNORE_POSITION = (
    mav.POSITION_TARGET_TYPEMASK_X_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_Y_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_Z_IGNORE
)
IGNORE_VELOCITY = (
    mav.POSITION_TARGET_TYPEMASK_VX_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_VY_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_VZ_IGNORE
)
IGNORE_ACCELERATION = (
    mav.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | mav.POSITION_TARGET_TYPEMASK_AZ_IGNORE
)
IGNORE_YAW = mav.POSITION_TARGET_TYPEMASK_YAW_IGNORE
IGNORE_YAW_RATE = mav.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
# Use x, y, z (and yaw unless IGNORE_YAW is added); ignore velocity, acceleration, yaw
# rate: 0b110111111000.
POSITION_ONLY = IGNORE_VELOCITY | IGNORE_ACCELERATION | IGNORE_YAW_RATE

# COMMAND_ACK results by MAV_RESULT, the names CommandResult.ack uses.
RESULTS: Mapping[int, str] = MappingProxyType(
    {
        mav.MAV_RESULT_ACCEPTED: "accepted",
        mav.MAV_RESULT_TEMPORARILY_REJECTED: "temporarily_rejected",
        mav.MAV_RESULT_DENIED: "denied",
        mav.MAV_RESULT_UNSUPPORTED: "unsupported",
        mav.MAV_RESULT_FAILED: "failed",
        mav.MAV_RESULT_IN_PROGRESS: "in_progress",
        6: "cancelled",  # MAV_RESULT_CANCELLED, newer than this pymavlink's dialect
    }
)

# EXTENDED_SYS_STATE landed states by MAV_LANDED_STATE, the names Telemetry.landed uses.
LANDED_STATES: Mapping[int, str] = MappingProxyType(
    {
        mav.MAV_LANDED_STATE_UNDEFINED: "unknown",
        mav.MAV_LANDED_STATE_ON_GROUND: "on_ground",
        mav.MAV_LANDED_STATE_IN_AIR: "in_air",
        mav.MAV_LANDED_STATE_TAKEOFF: "takeoff",
        mav.MAV_LANDED_STATE_LANDING: "landing",
    }
)

# Heartbeats of these component types are never the vehicle a link follows.
NOT_VEHICLES = frozenset(
    {
        mav.MAV_TYPE_GCS,
        mav.MAV_TYPE_GIMBAL,
        mav.MAV_TYPE_CAMERA,
        mav.MAV_TYPE_ADSB,
        mav.MAV_TYPE_ONBOARD_CONTROLLER,
        mav.MAV_TYPE_ANTENNA_TRACKER,
    }
)

# The telemetry the link reads, asked for with SET_MESSAGE_INTERVAL.
STREAMED = (
    mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    mav.MAVLINK_MSG_ID_ATTITUDE,
    mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
    mav.MAVLINK_MSG_ID_SYS_STATUS,
    mav.MAVLINK_MSG_ID_EXTENDED_SYS_STATE,
    mav.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED,
)


# Commands whose unused params common.xml documents as 0 (reserved default 0, "assumed
# not used (0)"): the link pads them with 0 whatever the autopilot's habit for empty
# params (`Autopilot.unused_param`).
ZERO_PADDED_COMMANDS = frozenset(
    {
        mav.MAV_CMD_DO_CHANGE_SPEED,
        mav.MAV_CMD_SET_MESSAGE_INTERVAL,
        mav.MAV_CMD_GET_MESSAGE_INTERVAL,
        mav.MAV_CMD_REQUEST_MESSAGE,
    }
)


def command_name(command: int) -> str:
    """The MAV_CMD name of a command id (its number when the dialect does not know it)."""
    entry = mav.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else str(command)
