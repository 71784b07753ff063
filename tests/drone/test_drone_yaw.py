"""The link sends a yaw, the vehicle turns to it; the heading policy of the controller
(free, keep, face the operator) decides which yaw a gesture's move carries."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import pytest

from proxima.drone.controller import DroneController
from proxima.drone.heading import HeadingPolicy, bearing
from proxima.drone.link import DroneLink, Telemetry
from proxima.drone.mavlink.protocol import IGNORE_YAW
from proxima.drone.mavlink.setpoint import Setpoint
from proxima.drone.memory import ManualClock
from proxima.drone.safety import SafetyConfig, SafetyGate
from proxima.events import CommandEvent

if TYPE_CHECKING:  # conftest is not importable by name beside other folders' conftest
    from conftest import Connect, MemoryLinks, ServeSim


def _angle(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def test_a_setpoint_with_a_yaw_clears_the_ignore_yaw_bit() -> None:
    assert Setpoint((0.0, 0.0, -2.0)).type_mask & IGNORE_YAW
    assert not Setpoint((0.0, 0.0, -2.0), yaw=1.0).type_mask & IGNORE_YAW


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_memory_link_turns_the_vehicle(
    memory_link: MemoryLinks, clock: ManualClock, autopilot: str
) -> None:
    link = memory_link(autopilot=autopilot)
    assert link.takeoff(2.0).ok
    assert link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.1, 20.0)
    tel = link.telemetry()
    assert tel is not None and tel.position is not None and _angle(tel.yaw, 0.0) < 1e-6
    assert link.enter_guided().ok  # PX4 holds in LOITER after its takeoff
    result = link.goto_local(*tel.position, yaw=math.radians(120))
    assert result.ok and result.sent["yaw"] == pytest.approx(math.radians(120))
    sent = [s for s in link.sent if s["msg"] == "SET_POSITION_TARGET_LOCAL_NED"][-1]
    assert sent["yaw"] == pytest.approx(math.radians(120))
    clock.advance(0.5)  # 90 degrees a second: half-way there
    half = link.telemetry()
    assert half is not None and 30 < math.degrees(half.yaw) < 60
    turned = link.wait_for(lambda t: _angle(t.yaw, math.radians(120)) < 1e-3, 5.0)
    assert turned is not None and turned.distance_to(tel.position) < 0.05
    # A target without a yaw keeps the heading.
    assert link.goto_local(tel.position[0] + 1.0, tel.position[1], tel.position[2]).ok
    ahead = (tel.position[0] + 1.0, tel.position[1], tel.position[2])
    moved = link.wait_for(lambda t: t.distance_to(ahead) < 0.05, 5.0)
    assert moved is not None and _angle(moved.yaw, math.radians(120)) < 1e-3


def test_mavlink_link_turns_the_vehicle_over_udp(serve_sim: ServeSim, connect: Connect) -> None:
    link = connect(serve_sim(sysid=3))
    assert link.takeoff(2.0).ok
    tel = link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.1, 20.0)
    assert tel is not None and tel.position is not None
    result = link.goto_local(*tel.position, yaw=math.radians(-75))
    assert result.ok and result.ack == "echoed"
    turned = link.wait_for(lambda t: _angle(t.yaw, math.radians(-75)) < math.radians(1), 5.0)
    assert turned is not None, link.telemetry()


def _flying(memory_link: MemoryLinks, clock: ManualClock, name: str) -> DroneLink:
    link = memory_link(name)
    assert link.takeoff(3.0).ok
    assert link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 3.0) < 0.1, 20.0)
    return link


def _move(link: DroneLink, policy: HeadingPolicy, clock: ManualClock, gesture: str) -> Telemetry:
    ctl = DroneController(
        {link.name: link},
        safety=SafetyGate(SafetyConfig(min_interval_s=0.0), clock=clock),
        clock=clock,
        heading=policy,
    )
    ctl.executor.set_control(link.name, True)
    out = ctl.handle(CommandEvent(t=0.0, stream="s", command=gesture, drone=link.name))
    assert out.status == "sent", out
    tel = link.wait_for(lambda t: all(abs(v) < 0.01 for v in t.velocity or (1.0,)), 10.0)
    assert tel is not None
    return tel


def test_face_operator_turns_a_sideways_move_toward_the_operator(
    memory_link: MemoryLinks, clock: ManualClock
) -> None:
    link = _flying(memory_link, clock, "main")
    # The operator stands 5 m north of the drone's origin (the drone faces them).
    policy = HeadingPolicy({"main": "face_operator"}, {"main": (5.0, 0.0)})
    tel = _move(link, policy, clock, "move_to_right")
    assert tel.position is not None
    assert tel.position[1] == pytest.approx(1.0, abs=0.05)  # 1 m to its right: east
    want = bearing(tel.position, (5.0, 0.0))
    assert math.degrees(want) == pytest.approx(-11.3, abs=0.2)
    assert _angle(tel.yaw, want) < math.radians(0.5)
    sent = [s for s in link.sent if s["msg"] == "SET_POSITION_TARGET_LOCAL_NED"][-1]
    assert sent["yaw"] == pytest.approx(want, abs=1e-3)


def test_keep_and_free_headings(memory_link: MemoryLinks, clock: ManualClock) -> None:
    link = _flying(memory_link, clock, "a")
    tel = _move(link, HeadingPolicy({"a": "keep"}), clock, "move_to_left")
    sent = [s for s in link.sent if s["msg"] == "SET_POSITION_TARGET_LOCAL_NED"][-1]
    assert sent["yaw"] == pytest.approx(0.0) and _angle(tel.yaw, 0.0) < 1e-6
    _move(link, HeadingPolicy(), clock, "move_to_right")  # free: no yaw sent
    sent = [s for s in link.sent if s["msg"] == "SET_POSITION_TARGET_LOCAL_NED"][-1]
    assert sent["yaw"] is None


def test_heading_policy_from_the_console_settings() -> None:
    from proxima.settings import Settings

    s = Settings(
        drones=[
            {"name": "main", "connection": "udpin:127.0.0.1:1", "home": (0.0, -5.0, 0.0),
             "heading": "face_operator"},
            {"name": "side", "connection": "udpin:127.0.0.1:2", "sysid": 2,
             "home": (5.0, 0.0, 0.0)},
        ],
        view={"operator_position": (0.0, 0.0)},
    )  # fmt: skip
    policy = HeadingPolicy.from_drones(s.drones, s.view.operator_position)
    assert policy.operator_ne["main"] == (5.0, 0.0)  # 5 m north of its origin
    assert policy.operator_ne["side"] == (0.0, -5.0)  # 5 m west
    assert policy.modes == {"main": "face_operator", "side": "free"}
    with pytest.raises(ValueError, match="heading 'sideways'"):
        HeadingPolicy({"main": "sideways"})
