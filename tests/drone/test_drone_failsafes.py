"""The simulated vehicle obeys its parameters: speeds, the geofence, the battery
failsafe, the ground-station-loss failsafe and PX4's offboard-loss rule, each set with
the autopilot's own parameter names, on a manual clock."""

from __future__ import annotations

import math

import pytest

from proxima.drone.mavlink.protocol import POSITION_ONLY, mav
from proxima.drone.memory import ManualClock
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.vehicle import Vehicle

FAST = {"max_accel": 8.0, "max_climb": 4.0, "land_speed": 3.0}


def flying(autopilot: str, altitude: float = 3.0, **params: float) -> tuple[Vehicle, ManualClock]:
    clock = ManualClock()
    v = Vehicle(SimConfig(autopilot=autopilot, **FAST), clock=clock)
    for name, value in params.items():
        assert v.params.set(name, value) is None, name
    if autopilot == "ardupilot":
        v.set_mode("GUIDED")
    v.arm()
    v.takeoff(altitude)
    run(v, clock, altitude)
    assert v.landed == mav.MAV_LANDED_STATE_IN_AIR
    return v, clock


def run(v: Vehicle, clock: ManualClock, seconds: float) -> None:
    dt = 1.0 / v.cfg.physics_hz
    for _ in range(round(seconds / dt)):
        clock.advance(dt)
        v.step(dt)


def goto(v: Vehicle, north: float, down: float) -> None:
    v.position_target(mav.MAV_FRAME_LOCAL_NED, POSITION_ONLY, (north, 0.0, down), (0, 0, 0), 0)


def stream(v: Vehicle, clock: ManualClock, seconds: float, north: float, down: float) -> None:
    """A position target at 10 Hz for `seconds` (PX4 OFFBOARD needs the stream)."""
    for _ in range(round(seconds * 10)):
        goto(v, north, down)
        run(v, clock, 0.1)


def test_speed_parameters_are_flown() -> None:
    v, clock = flying("ardupilot", WPNAV_SPEED=200.0)  # cm/s
    goto(v, 20.0, -3.0)
    run(v, clock, 4.0)
    assert abs(math.hypot(*v.vel[:2]) - 2.0) < 0.01
    v2, clock2 = flying("px4", MPC_XY_CRUISE=3.0)
    v2.enter("OFFBOARD")
    stream(v2, clock2, 3.0, 20.0, -3.0)
    assert v2.mode == "OFFBOARD" and abs(math.hypot(*v2.vel[:2]) - 3.0) < 0.01


@pytest.mark.parametrize(
    ("autopilot", "params", "action_mode"),
    [
        ("ardupilot", {"FENCE_ENABLE": 1, "FENCE_ALT_MAX": 10.0, "FENCE_ACTION": 2}, "LAND"),
        ("px4", {"GF_MAX_VER_DIST": 10.0, "GF_ACTION": 2}, "LOITER"),  # Hold
    ],
)
def test_fence_ceiling(autopilot: str, params: dict[str, float], action_mode: str) -> None:
    v, clock = flying(autopilot, **params)
    texts: list[str] = []
    v.on_text = lambda text, severity: texts.append(text)
    if autopilot == "px4":
        v.enter("OFFBOARD")
    peak = 0.0
    for _ in range(40):  # climb at the ceiling, streaming as PX4 needs
        goto(v, 0.0, -14.0)
        run(v, clock, 0.1)
        peak = max(peak, v.altitude())
    assert v.mode == action_mode and any(t.startswith("Fence breach") for t in texts)
    assert 10.0 < peak < 11.5  # stopped just above the 10 m ceiling


def test_fence_circle_rtl_stays_below_the_ceiling() -> None:
    params = {"FENCE_ENABLE": 1, "FENCE_RADIUS": 30.0, "FENCE_ALT_MAX": 12.0, "RTL_ALT": 3000.0}
    v, clock = flying("ardupilot", **params)
    goto(v, 40.0, -3.0)
    run(v, clock, 10.0)
    assert v.mode == "RTL"  # breached at 30 m: return (FENCE_ACTION 1)
    run(v, clock, 3.0)
    assert v.altitude() <= 11.0 + 0.2  # RTL_ALT 30 m, kept under the 12 m fence


@pytest.mark.parametrize(
    ("autopilot", "params", "mode"),
    [
        ("ardupilot", {"BATT_LOW_VOLT": 16.5, "BATT_FS_LOW_ACT": 2}, "RTL"),
        ("px4", {"BAT_CRIT_THR": 0.4, "BAT_LOW_THR": 0.45, "COM_LOW_BAT_ACT": 3}, "RTL"),
        ("ardupilot", {"BATT_LOW_VOLT": 16.5, "BATT_FS_LOW_ACT": 0}, "GUIDED"),
    ],
)
def test_battery_failsafe(autopilot: str, params: dict[str, float], mode: str) -> None:
    v, clock = flying(autopilot, **params)
    v.battery = 35.0  # ArduCopter: 14.98 V
    run(v, clock, 0.1)
    assert v.mode == mode and v.failsafes.battery_level is not None


def test_battery_too_low_refuses_arming() -> None:
    v = Vehicle(SimConfig(battery_pct=12.0))
    v.set_mode("GUIDED")
    assert v.arm() == mav.MAV_RESULT_FAILED and not v.armable()


@pytest.mark.parametrize(
    ("autopilot", "params", "mode"),
    [
        ("ardupilot", {"FS_GCS_ENABLE": 5, "FS_GCS_TIMEOUT": 3.0}, "LAND"),
        ("px4", {"NAV_DLL_ACT": 2, "COM_DL_LOSS_T": 5.0}, "RTL"),
    ],
)
def test_ground_station_loss(autopilot: str, params: dict[str, float], mode: str) -> None:
    v, clock = flying(autopilot, **params)
    before = v.mode
    v.gcs_heard()
    timeout = params.get("FS_GCS_TIMEOUT", params.get("COM_DL_LOSS_T", 0.0))
    run(v, clock, timeout - 0.5)
    assert v.mode == before
    run(v, clock, 1.0)
    assert v.mode == mode and v.failsafes.gcs_lost


def test_ground_station_loss_is_off_by_default() -> None:
    v, clock = flying("ardupilot")
    v.gcs_heard()
    run(v, clock, 30.0)
    assert v.mode == "GUIDED"


def test_px4_offboard_loss_action() -> None:
    v, clock = flying("px4", COM_OF_LOSS_T=1.0, COM_OBL_RC_ACT=4)  # land
    goto(v, 0.0, -3.0)
    assert v.set_mode("OFFBOARD") == mav.MAV_RESULT_ACCEPTED  # one setpoint is enough
    run(v, clock, 0.9)
    assert v.mode == "OFFBOARD"
    run(v, clock, 0.2)
    assert v.mode == "LAND"
