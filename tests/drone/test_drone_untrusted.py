"""Every field is untrusted: the simulated vehicle's commands, parameters, mission items
and position targets with NaN, infinities and out-of-range values, on the vehicle
itself (what the UDP server and the in-memory link both execute), on a manual clock."""

from __future__ import annotations

import math
import struct

import pytest

from proxima.drone.mavlink.fields import INT32_MAX, degrees_e7, integer, mav_bool, or_default
from proxima.drone.mavlink.protocol import POSITION_ONLY, mav
from proxima.drone.memory import ManualClock
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.handlers import Command, vehicle_command
from proxima.drone.sim.mission import MISSION, MissionItem, check_item
from proxima.drone.sim.vehicle import Vehicle

NAN, INF = math.nan, math.inf
ACCEPTED, DENIED, FAILED = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_DENIED, mav.MAV_RESULT_FAILED


def make(autopilot: str = "ardupilot", **cfg: float) -> tuple[Vehicle, ManualClock]:
    clock = ManualClock()
    return Vehicle(SimConfig(autopilot=autopilot, **cfg), clock=clock), clock


def run(v: Vehicle, clock: ManualClock, seconds: float) -> None:
    dt = 1.0 / v.cfg.physics_hz
    for _ in range(round(seconds / dt)):
        clock.advance(dt)
        v.step(dt)


def cmd(v: Vehicle, command: int, *params: float, frame: int | None = None) -> int | None:
    return vehicle_command(v, Command.of(command, params, frame))


def test_field_readers() -> None:
    assert or_default(NAN, 2.5) == 2.5 and or_default(INF, 2.5) is None and or_default(1.0, 0) == 1
    assert [mav_bool(x) for x in (0.0, 1.0, 0.5, NAN, INF)] == [False, True, None, None, None]
    assert integer(3.0, 0, 5) == 3 and integer(3.5, 0, 5) is None and integer(9.0, 0, 5) is None
    assert integer(NAN, 0, 5) is None and integer(NAN, 0, 5, nan=0) == 0
    assert math.isnan(degrees_e7(INT32_MAX)) and degrees_e7(500_755_000) == 50.0755


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_arm_with_nan_in_the_unused_params(autopilot: str) -> None:
    """The bug behind the PX4 crash: MAVSDK sends param2..7 as NaN (unset), and the
    simulator did int(NaN) on param2. NaN param2 is "not forced"."""
    v, _ = make(autopilot)
    assert cmd(v, mav.MAV_CMD_COMPONENT_ARM_DISARM, 1, NAN, NAN, NAN, NAN, NAN, NAN) == ACCEPTED
    assert v.armed
    assert cmd(v, mav.MAV_CMD_COMPONENT_ARM_DISARM, 0, NAN) == ACCEPTED and not v.armed


@pytest.mark.parametrize(
    "params",
    [(NAN,), (INF,), (0.5,), (2.0,), (-1.0,), (1.0, 123.0), (1.0, INF), (1.0, 21196.5)],
)
def test_arm_refuses_what_is_not_a_mav_bool_or_the_force_magic(params: tuple[float, ...]) -> None:
    v, _ = make()
    assert cmd(v, mav.MAV_CMD_COMPONENT_ARM_DISARM, *params) == DENIED and not v.armed


@pytest.mark.parametrize(
    ("autopilot", "param", "altitude"),
    [("ardupilot", "PILOT_TKOFF_ALT", 400.0), ("px4", "MIS_TAKEOFF_ALT", 4.0)],
)
def test_takeoff_nan_altitude_is_the_takeoff_altitude_parameter(
    autopilot: str, param: str, altitude: float
) -> None:
    v, clock = make(autopilot)
    assert v.params.set(param, altitude) is None
    if autopilot == "ardupilot":
        assert v.set_mode("GUIDED") == ACCEPTED
    assert cmd(v, mav.MAV_CMD_COMPONENT_ARM_DISARM, 1) == ACCEPTED
    assert cmd(v, mav.MAV_CMD_NAV_TAKEOFF, *[NAN] * 7) == ACCEPTED
    run(v, clock, 4.0)
    assert abs(v.altitude() - 4.0) < 0.05 and v.landed == mav.MAV_LANDED_STATE_IN_AIR


@pytest.mark.parametrize("alt", [INF, -INF, 0.0, -3.0, 1e9])
def test_takeoff_refuses_altitudes_it_cannot_fly(alt: float) -> None:
    v, _ = make()
    v.set_mode("GUIDED")
    v.arm()
    assert cmd(v, mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, alt) == DENIED
    assert v.landed == mav.MAV_LANDED_STATE_ON_GROUND


def test_takeoff_default_zero_is_refused() -> None:
    """ArduCopter's PILOT_TKOFF_ALT 0 gives a NaN altitude no meaning: refused."""
    v, _ = make()
    v.params.set("PILOT_TKOFF_ALT", 0.0)
    v.set_mode("GUIDED")
    v.arm()
    assert cmd(v, mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, NAN) == DENIED


@pytest.mark.parametrize(
    "params", [(NAN, 4), (INF, 4), (1.5, 4), (1, NAN), (1, INF), (1, -4), (1, 4.5), (0, 4)]
)
def test_set_mode_refuses_bad_numbers(params: tuple[float, ...]) -> None:
    v, _ = make()
    assert cmd(v, mav.MAV_CMD_DO_SET_MODE, *params) == DENIED and v.mode == "STABILIZE"


def test_set_mode_nan_submode_is_zero() -> None:
    v, _ = make()
    assert cmd(v, mav.MAV_CMD_DO_SET_MODE, 1, 4, NAN, NAN, NAN, NAN, NAN) == ACCEPTED
    assert v.mode == "GUIDED"


def test_change_speed_untrusted_and_defaults() -> None:
    v, _ = make()
    for params in ((NAN, 2), (1, NAN), (1, INF), (9, 2), (1.5, 2), (1, 0), (1, -3)):
        assert cmd(v, mav.MAV_CMD_DO_CHANGE_SPEED, *params) == DENIED, params
    assert cmd(v, mav.MAV_CMD_DO_CHANGE_SPEED, 1, 2.0, -1) == ACCEPTED and v.speed == 2.0
    assert cmd(v, mav.MAV_CMD_DO_CHANGE_SPEED, 1, 50.0) == ACCEPTED and v.speed == 5.0  # capped
    assert cmd(v, mav.MAV_CMD_DO_CHANGE_SPEED, 1, -2.0) == ACCEPTED and v.speed == 5.0  # default
    v.params.set("WPNAV_SPEED", 300.0)  # cm/s: the cruise speed follows the parameter
    assert v.speed == 3.0


def flying(autopilot: str = "ardupilot") -> tuple[Vehicle, ManualClock]:
    v, clock = make(autopilot, max_accel=8.0, max_climb=4.0)
    if autopilot == "ardupilot":
        v.set_mode("GUIDED")
    v.arm()
    v.takeoff(2.0)
    run(v, clock, 3.0)
    assert v.landed == mav.MAV_LANDED_STATE_IN_AIR
    return v, clock


def test_position_targets_with_nan_are_ignored_and_nan_yaw_keeps_the_heading() -> None:
    v, clock = flying()
    before = list(v.target or ())
    frame = mav.MAV_FRAME_LOCAL_NED
    for pos in ((NAN, 0, -2), (INF, 0, -2), (0, 0, -INF), (1e7, 0, -2), (0, 0, -1e6)):
        v.position_target(frame, POSITION_ONLY, pos, (0, 0, 0), 0.0)
        assert v.target == before, pos
    # Velocity only (position ignored): NaN velocity refused, a huge one capped.
    vel_only = 0b110111000111
    v.position_target(frame, vel_only, (NAN, NAN, NAN), (NAN, 1, 0), 0.0)
    assert v.vel_target is None
    v.position_target(frame, vel_only, (NAN, NAN, NAN), (1e30, 0, -1e30), 0.0)
    assert v.vel_target == [v.speed, 0.0, -v.climb]
    # A usable position with a NaN yaw: flown, heading kept.
    v.position_target(frame, POSITION_ONLY, (1.0, 0.0, -2.0), (0, 0, 0), NAN)
    run(v, clock, 3.0)
    assert math.dist(v.pos, (1.0, 0.0, -2.0)) < 0.05 and v.yaw == 0.0


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_reposition_nan_means_stay(autopilot: str) -> None:
    v, clock = flying(autopilot)
    lat, lon, _ = v.global_position()
    home_alt = v.cfg.home[2]
    reposition = mav.MAV_CMD_DO_REPOSITION
    # NaN latitude/longitude: stay where it is; a new altitude AMSL.
    assert cmd(v, reposition, -1, 1, 0, NAN, NAN, NAN, home_alt + 3.0) == ACCEPTED
    run(v, clock, 3.0)
    assert abs(v.altitude() - 3.0) < 0.05 and math.hypot(v.pos[0], v.pos[1]) < 0.05
    assert v.mode == ("GUIDED" if autopilot == "ardupilot" else "LOITER")
    # Bad numbers and places: refused, nothing moves.
    for params in (
        (-1, 1, 0, NAN, lat + 200.0, lon, NAN),  # not on Earth
        (-1, 1, 0, NAN, lat, NAN, NAN),  # only one of the two
        (-1, 1, 0, NAN, NAN, NAN, INF),
        (INF, 1, 0, NAN, NAN, NAN, NAN),
        (-1, 1, 0, INF, NAN, NAN, NAN),
        (-1, 1.5, 0, NAN, NAN, NAN, NAN),
        (-1, 1, 0, NAN, lat + 5.0, lon, NAN),  # 550 km: outside the simulated world
    ):
        assert cmd(v, reposition, *params) == DENIED, params
    assert cmd(v, reposition, -1, 1, 0, NAN, NAN, NAN, 3.0, frame=mav.MAV_FRAME_LOCAL_NED) == DENIED


def test_reposition_needs_a_flying_vehicle() -> None:
    v, _ = make()
    assert cmd(v, mav.MAV_CMD_DO_REPOSITION, -1, 1, 0, NAN, NAN, NAN, 303.0) == DENIED


def test_land_start_without_a_landing_sequence_fails_as_ardupilot_answers() -> None:
    v, _ = flying()
    assert cmd(v, mav.MAV_CMD_DO_LAND_START) == FAILED and v.mode == "GUIDED"


def item(
    command: int,
    frame: int = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    p: tuple[float, float, float, float] = (0.0, 0.0, 0.0, NAN),
    x: int = 500_755_000,
    y: int = 144_378_000,
    z: float = 10.0,
) -> MissionItem:
    return MissionItem(0, frame, command, 0, 1, p, x, y, z)


def test_mission_items_are_checked() -> None:
    wp = mav.MAV_CMD_NAV_WAYPOINT
    assert check_item(item(wp), MISSION) == mav.MAV_MISSION_ACCEPTED  # NaN yaw: "current"
    assert check_item(item(wp, p=(INF, 0, 0, 0)), MISSION) == mav.MAV_MISSION_INVALID_PARAM1
    assert check_item(item(wp, p=(0, 0, 0, -INF)), MISSION) == mav.MAV_MISSION_INVALID_PARAM4
    assert check_item(item(wp, x=950_000_000), MISSION) == mav.MAV_MISSION_INVALID_PARAM5_X
    assert check_item(item(wp, y=-1_900_000_000), MISSION) == mav.MAV_MISSION_INVALID_PARAM6_Y
    assert check_item(item(wp, z=NAN), MISSION) == mav.MAV_MISSION_INVALID_PARAM7
    assert check_item(item(wp, frame=99), MISSION) == mav.MAV_MISSION_UNSUPPORTED_FRAME
    assert check_item(item(60000), MISSION) == mav.MAV_MISSION_UNSUPPORTED
    # A fence vertex belongs to the fence, not to the mission.
    vertex = mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
    assert check_item(item(vertex), MISSION) == mav.MAV_MISSION_UNSUPPORTED
    assert check_item(item(vertex), mav.MAV_MISSION_TYPE_FENCE) == mav.MAV_MISSION_ACCEPTED
    assert check_item(item(wp), mav.MAV_MISSION_TYPE_RALLY) == mav.MAV_MISSION_UNSUPPORTED
    # Items without a position (MAV_FRAME_MISSION) may leave z NaN.
    speed = item(mav.MAV_CMD_DO_CHANGE_SPEED, frame=mav.MAV_FRAME_MISSION, z=NAN)
    assert check_item(speed, MISSION) == mav.MAV_MISSION_ACCEPTED


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_parameters_refuse_what_is_not_a_value(autopilot: str) -> None:
    v, _ = make(autopilot)
    p = v.params
    name = "WPNAV_SPEED" if autopilot == "ardupilot" else "MPC_XY_CRUISE"
    before = p[name]
    for value in (NAN, INF, -INF, 1e9, -5.0):
        assert p.set(name, value) is not None and p[name] == before
    assert p.set("NO_SUCH_PARAM", 1.0) == "no parameter 'NO_SUCH_PARAM'"
    integer_param = "FENCE_ENABLE" if autopilot == "ardupilot" else "GF_ACTION"
    assert "not an integer" in (p.set(integer_param, 0.5) or "")


def test_px4_integers_travel_bytewise_ardupilot_cast() -> None:
    px4, _ = make("px4")
    raw = px4.params.encode("GF_ACTION")  # 2, as its bytes in a float
    assert struct.pack("<f", raw) == struct.pack("<i", 2)
    assert px4.params.decode("GF_ACTION", raw, mav.MAV_PARAM_TYPE_INT32) == 2.0
    assert px4.params.decode("GF_ACTION", 2.0, mav.MAV_PARAM_TYPE_REAL32) == 2.0
    assert px4.params.decode("GF_ACTION", 2.0, 77) is None  # not a MAV_PARAM_TYPE
    ap, _ = make("ardupilot")
    assert ap.params.encode("FENCE_ACTION") == 1.0
    assert ap.params.decode("FENCE_ACTION", 2.0, mav.MAV_PARAM_TYPE_INT8) == 2.0
