"""What the simulated vehicle does with the commands a ground station sends.

`vehicle_command` executes the COMMAND_LONG / COMMAND_INT commands that act on the
vehicle itself (arming, modes, takeoff, landing, RTL, speed, reposition) and answers
with a MAV_RESULT; the MAVLink server (`server`) and the in-memory link
(`proxima.drone.memory`) both call it, so they behave alike. Commands about messages
(intervals, REQUEST_MESSAGE, AUTOPILOT_VERSION) are the telemetry's (`telemetry`).

Every param is untrusted. NaN means "default / unchanged" where MAVLink's common.xml
gives it that meaning (NAV_TAKEOFF's altitude: the takeoff-altitude parameter; yaw:
keep the heading; DO_REPOSITION's position: stay; ARM_DISARM's param 2: 0); anything
else that is not a valid value (a NaN elsewhere, infinity, a non-integral enum, a
MAV_BOOL that is not 0 or 1) is answered MAV_RESULT_DENIED without touching the vehicle.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from proxima.drone.mavlink.fields import integer, mav_bool, or_default, valid_lat_lon
from proxima.drone.mavlink.protocol import FORCE_DISARM_MAGIC, mav
from proxima.drone.sim.geo import local_from_global
from proxima.drone.sim.vehicle import Vehicle

DENIED = mav.MAV_RESULT_DENIED
AMSL_FRAMES = frozenset({mav.MAV_FRAME_GLOBAL, mav.MAV_FRAME_GLOBAL_INT})  # altitude AMSL
RELATIVE_FRAMES = frozenset(
    {mav.MAV_FRAME_GLOBAL_RELATIVE_ALT, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
)


@dataclass(frozen=True)
class Command:
    """One MAV_CMD as it arrived: params 1-7 (COMMAND_INT's x and y as degrees, NaN for
    INT32_MAX) and COMMAND_INT's frame (None for COMMAND_LONG)."""

    id: int
    params: tuple[float, ...]
    frame: int | None = None

    @classmethod
    def of(cls, command: int, params: Sequence[float], frame: int | None = None) -> Command:
        p = [float(x) for x in params[:7]]
        return cls(command, (*p, *([0.0] * (7 - len(p)))), frame)


CommandHandler = Callable[[Vehicle, Command], int]


def _arm_disarm(v: Vehicle, c: Command) -> int:
    arm = mav_bool(c.params[0])
    magic = integer(c.params[1], 0, FORCE_DISARM_MAGIC, nan=0)
    if arm is None or magic not in (0, FORCE_DISARM_MAGIC):
        return DENIED
    force = magic == FORCE_DISARM_MAGIC
    if arm:
        return v.arm(force)
    result = v.disarm(force, "commanded")
    if force:
        v.motors_on = False
    return result


def _set_mode(v: Vehicle, c: Command) -> int:
    flags = integer(c.params[0], 0, 255)
    custom = integer(c.params[1], 0, 2**32 - 1)
    sub = integer(c.params[2], 0, 255, nan=0)
    if flags is None or custom is None or sub is None:
        return DENIED
    if not flags & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return DENIED
    name = v.fw.mode_from_params(custom, sub)
    return v.set_mode(name) if name else DENIED


def _takeoff(v: Vehicle, c: Command) -> int:
    alt = c.params[6]
    if math.isnan(alt):
        return v.takeoff(None)  # "use the default": MIS_TAKEOFF_ALT / PILOT_TKOFF_ALT
    if not math.isfinite(alt):
        return DENIED
    return v.takeoff(v.fw.takeoff_altitude(alt, v.cfg.home[2]))


def _land(v: Vehicle, c: Command) -> int:
    return v.set_mode("LAND")  # where it is: both autopilots ignore lat/lon here


def _return_to_launch(v: Vehicle, c: Command) -> int:
    return v.set_mode("RTL")


def _change_speed(v: Vehicle, c: Command) -> int:
    kind = integer(c.params[0], 0, 3)
    if kind is None or not math.isfinite(c.params[1]):
        return DENIED
    return v.change_speed(kind, c.params[1])


def _reposition(v: Vehicle, c: Command) -> int:
    """MAV_CMD_DO_REPOSITION: NaN position or altitude keeps the current one; a
    COMMAND_LONG's altitude is AMSL (as PX4 reads it)."""
    speed = or_default(c.params[0], -1.0)
    flags = integer(c.params[1], 0, 255, nan=0)
    yaw = or_default(c.params[3], math.nan)
    lat, lon, alt = c.params[4], c.params[5], c.params[6]
    frame = mav.MAV_FRAME_GLOBAL if c.frame is None else c.frame
    if speed is None or flags is None or yaw is None or math.isinf(alt):
        return DENIED
    if frame not in AMSL_FRAMES | RELATIVE_FRAMES:
        return DENIED
    if math.isnan(lat) and math.isnan(lon):
        north, east = v.pos[0], v.pos[1]
    elif valid_lat_lon(lat, lon):
        north, east = local_from_global(v.cfg.home, lat, lon)
    else:
        return DENIED
    if math.isnan(alt):
        down = v.pos[2]
    else:
        down = -alt if frame in RELATIVE_FRAMES else v.cfg.home[2] - alt
    return v.reposition(
        north,
        east,
        down,
        speed=speed if speed > 0 else None,
        yaw=None if math.isnan(yaw) else yaw,
        change_mode=bool(flags & mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE),
    )


def _land_start(v: Vehicle, c: Command) -> int:
    return v.land_start()


VEHICLE_COMMANDS: dict[int, CommandHandler] = {
    mav.MAV_CMD_COMPONENT_ARM_DISARM: _arm_disarm,
    mav.MAV_CMD_DO_SET_MODE: _set_mode,
    mav.MAV_CMD_NAV_TAKEOFF: _takeoff,
    mav.MAV_CMD_NAV_LAND: _land,
    mav.MAV_CMD_NAV_RETURN_TO_LAUNCH: _return_to_launch,
    mav.MAV_CMD_DO_CHANGE_SPEED: _change_speed,
    mav.MAV_CMD_DO_REPOSITION: _reposition,
    mav.MAV_CMD_DO_LAND_START: _land_start,
}


def vehicle_command(vehicle: Vehicle, command: Command) -> int | None:
    """Execute one vehicle command; its MAV_RESULT, or None when `command` is not one
    that acts on the vehicle."""
    handler = VEHICLE_COMMANDS.get(command.id)
    return None if handler is None else handler(vehicle, command)


def set_mode_message(vehicle: Vehicle, base_mode: int, custom_mode: int) -> int:
    """The SET_MODE message (older ground stations use it instead of DO_SET_MODE)."""
    if not base_mode & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return DENIED
    name = vehicle.fw.mode_from_custom(custom_mode)
    return vehicle.set_mode(name) if name else DENIED


def global_position_target(
    vehicle: Vehicle,
    frame: int,
    mask: int,
    lat_lon_e7: tuple[int, int],
    alt: float,
    velocity: tuple[float, float, float],
    yaw: float,
) -> None:
    """SET_POSITION_TARGET_GLOBAL_INT as a local target (ignored, like a refused local
    one, when its frame, place or numbers are not usable)."""
    if frame in AMSL_FRAMES:
        down = vehicle.cfg.home[2] - alt
    elif frame in RELATIVE_FRAMES:
        down = -alt
    else:
        vehicle.statustext(f"Frame {frame} unsupported", mav.MAV_SEVERITY_WARNING)
        return
    lat, lon = lat_lon_e7[0] / 1e7, lat_lon_e7[1] / 1e7
    north, east = math.nan, math.nan  # an unusable place refuses a used position
    if valid_lat_lon(lat, lon):
        north, east = local_from_global(vehicle.cfg.home, lat, lon)
    vehicle.position_target(mav.MAV_FRAME_LOCAL_NED, mask, (north, east, down), velocity, yaw)
