"""What differs between ArduPilot and PX4 for a ground station, as one object each.

The link picks the policy from the vehicle's HEARTBEAT (`for_heartbeat`) and asks it
instead of branching on the autopilot's name: which mode follows external targets, from
which modes a gesture may take the vehicle there, how a mode is encoded in
MAV_CMD_DO_SET_MODE, how takeoff is sequenced and what altitude NAV_TAKEOFF carries,
whether position targets must be streamed, and how the vehicle is told to hold.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

from proxima.drone.link import Telemetry
from proxima.drone.mavlink.protocol import PX4_MODES, mav, mavutil


class Autopilot(ABC):
    """The ground-station side of one autopilot family."""

    name: str  # Telemetry.autopilot: "ardupilot" or "px4"
    label: str  # how messages name it
    guided_mode: str  # the mode that follows SET_POSITION_TARGET_LOCAL_NED
    # Modes in which the vehicle only holds its position: from these a gesture may take
    # it into `guided_mode`. Gestures never override LAND, RTL, a mission or a pilot's
    # manual mode.
    holding_modes: frozenset[str]
    # The vehicle leaves `guided_mode` unless targets keep coming (PX4 OFFBOARD: > 2 Hz),
    # so the link streams the active target and starts the stream before the switch.
    streams_setpoints: bool
    # Take off from `guided_mode` (enter it before arming) or from the current mode.
    takeoff_in_guided: bool
    # A mode that stops and holds by itself (PX4 Hold), or None: hold by a position
    # target at the stopping point in `guided_mode`, or `brake_mode` without a position.
    hold_mode: str | None
    brake_mode: str
    # What an empty COMMAND_LONG param is sent as (MAVSDK's convention: 0 to ArduPilot,
    # NaN to PX4, where NaN is MAVLink's "unset").
    unused_param: float

    @abstractmethod
    def mode_params(self, mode: str, vehicle_type: int) -> list[float] | None:
        """MAV_CMD_DO_SET_MODE params 1-3 for `mode` (upper case), None if unknown."""

    @abstractmethod
    def takeoff_altitude(self, tel: Telemetry, altitude_m: float) -> float | None:
        """NAV_TAKEOFF param 7 for `altitude_m` above the origin, None when a fact it
        needs (PX4: the home altitude) is not known yet."""

    def takeoff_params(self, altitude: float) -> list[float]:
        """NAV_TAKEOFF params 1-7 around param 7 `altitude` (from `takeoff_altitude`)."""
        return [0, 0, 0, 0, 0, 0, altitude]


class ArduPilot(Autopilot):
    """ArduCopter: GUIDED, DO_SET_MODE with a custom mode number, takeoff altitude
    relative to home, one position target per move."""

    name = "ardupilot"
    label = "ArduPilot"
    guided_mode = "GUIDED"
    holding_modes = frozenset({"GUIDED", "LOITER", "BRAKE", "POSHOLD"})
    streams_setpoints = False
    takeoff_in_guided = True
    hold_mode = None
    brake_mode = "BRAKE"
    unused_param = 0.0

    def mode_params(self, mode: str, vehicle_type: int) -> list[float] | None:
        mapping = mavutil.mode_mapping_byname(vehicle_type) or {}
        if mode not in mapping:
            return None
        return [mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mapping[mode]]

    def takeoff_altitude(self, tel: Telemetry, altitude_m: float) -> float | None:
        return altitude_m


class PX4(Autopilot):
    """PX4: OFFBOARD (fed by a setpoint stream above 2 Hz), DO_SET_MODE with base mode,
    main and sub mode, takeoff altitude AMSL, Hold (AUTO.LOITER) to stop."""

    name = "px4"
    label = "PX4"
    guided_mode = "OFFBOARD"
    holding_modes = frozenset({"OFFBOARD", "LOITER", "POSCTL"})
    streams_setpoints = True
    takeoff_in_guided = False
    hold_mode = "LOITER"
    brake_mode = "LOITER"
    unused_param = math.nan

    def mode_params(self, mode: str, vehicle_type: int) -> list[float] | None:
        if mode not in PX4_MODES:
            return None
        base, main, sub = PX4_MODES[mode]
        return [base, main, sub]

    def takeoff_altitude(self, tel: Telemetry, altitude_m: float) -> float | None:
        home_amsl = tel.home[2] if tel.home else None
        if home_amsl is None and tel.global_position and tel.relative_alt is not None:
            home_amsl = tel.global_position[2] - tel.relative_alt
        return None if home_amsl is None else home_amsl + altitude_m

    def takeoff_params(self, altitude: float) -> list[float]:
        nan = math.nan  # PX4: NaN yaw and position mean "keep the current ones"
        return [0, 0, 0, nan, nan, nan, altitude]


ARDUPILOT = ArduPilot()
PX4_AUTOPILOT = PX4()
AUTOPILOTS: dict[str, Autopilot] = {a.name: a for a in (ARDUPILOT, PX4_AUTOPILOT)}


def for_heartbeat(autopilot: int) -> Autopilot:
    """The policy for a HEARTBEAT's `autopilot` field (anything but PX4 is flown as
    ArduPilot, the project's default vehicle)."""
    return PX4_AUTOPILOT if autopilot == mav.MAV_AUTOPILOT_PX4 else ARDUPILOT


def by_name(name: str) -> Autopilot:
    """The policy for a Telemetry.autopilot name ("unknown" is flown as ArduPilot)."""
    return AUTOPILOTS.get(name, ARDUPILOT)
