"""What the simulated vehicle does with the commands a ground station sends.

`vehicle_command` executes the COMMAND_LONG / COMMAND_INT commands that act on the
vehicle itself (arming, modes, takeoff, landing, RTL, speed) and answers with a
MAV_RESULT; the MAVLink server (`server`) and the in-memory link (`proxima.drone.memory`)
both call it, so they behave alike. Commands about the telemetry (message intervals,
REQUEST_MESSAGE) are the server's (`telemetry.TelemetryStreams`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from proxima.drone.mavlink.protocol import FORCE_DISARM_MAGIC, mav
from proxima.drone.sim.vehicle import Vehicle

CommandHandler = Callable[[Vehicle, Sequence[float]], int]


def _arm_disarm(v: Vehicle, p: Sequence[float]) -> int:
    force = int(p[1]) == FORCE_DISARM_MAGIC
    if p[0] >= 0.5:
        return v.arm(force)
    result = v.disarm(force, "commanded")
    if force:
        v.motors_on = False
    return result


def _set_mode(v: Vehicle, p: Sequence[float]) -> int:
    name = None
    if int(p[0]) & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        name = v.fw.mode_from_params(p[1], p[2])
    return v.set_mode(name) if name else mav.MAV_RESULT_DENIED


def _takeoff(v: Vehicle, p: Sequence[float]) -> int:
    return v.takeoff(v.fw.takeoff_altitude(p[6], v.cfg.home[2]))


def _land(v: Vehicle, p: Sequence[float]) -> int:
    return v.set_mode("LAND")


def _return_to_launch(v: Vehicle, p: Sequence[float]) -> int:
    return v.set_mode("RTL")


def _change_speed(v: Vehicle, p: Sequence[float]) -> int:
    return v.change_speed(int(p[0]), p[1])


VEHICLE_COMMANDS: dict[int, CommandHandler] = {
    mav.MAV_CMD_COMPONENT_ARM_DISARM: _arm_disarm,
    mav.MAV_CMD_DO_SET_MODE: _set_mode,
    mav.MAV_CMD_NAV_TAKEOFF: _takeoff,
    mav.MAV_CMD_NAV_LAND: _land,
    mav.MAV_CMD_NAV_RETURN_TO_LAUNCH: _return_to_launch,
    mav.MAV_CMD_DO_CHANGE_SPEED: _change_speed,
}


def vehicle_command(vehicle: Vehicle, command: int, params: Sequence[float]) -> int | None:
    """Execute one vehicle command (params 1-7); its MAV_RESULT, or None when `command`
    is not one that acts on the vehicle."""
    handler = VEHICLE_COMMANDS.get(command)
    return None if handler is None else handler(vehicle, params)


def set_mode_message(vehicle: Vehicle, base_mode: int, custom_mode: int) -> int:
    """The SET_MODE message (older ground stations use it instead of DO_SET_MODE)."""
    if not base_mode & mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return mav.MAV_RESULT_DENIED
    name = vehicle.fw.mode_from_custom(custom_mode)
    return vehicle.set_mode(name) if name else mav.MAV_RESULT_DENIED
