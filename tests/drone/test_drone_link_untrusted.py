"""The project's link treats what it hears and what it is asked as untrusted: values
that MAVLink does not allow never reach its telemetry, arguments that cannot be flown
are refused before sending, and it follows the autopilots' conventions for unused
params (NaN to PX4, as MAVSDK sends)."""

from __future__ import annotations

import math
import socket
import time
from typing import TYPE_CHECKING

import pytest

from proxima.drone.link import Telemetry
from proxima.drone.mavlink.protocol import mav

if TYPE_CHECKING:
    from conftest import Connect, MemoryLinks, ServeSim

NAN, INF = math.nan, math.inf


def numbers(tel: Telemetry) -> list[float]:
    fields = (tel.position, tel.velocity, tel.attitude, tel.global_position, tel.home)
    return [x for f in fields if f for x in f] + [tel.relative_alt or 0.0]


def test_hostile_telemetry_never_reaches_the_snapshot(
    serve_sim: ServeSim, connect: Connect
) -> None:
    """Found by the fuzz test: NaN positions and attitudes from the vehicle's system id
    went straight into Telemetry (and from there into the controller's arithmetic)."""
    sim = serve_sim()
    link = connect(sim)
    assert link.wait_for(lambda t: t.home is not None, 5.0)
    spoof = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    bad = [
        mav.MAVLink_local_position_ned_message(0, NAN, 0, -1, 0, 0, 0),
        mav.MAVLink_local_position_ned_message(0, 0, INF, -1, 0, 0, 0),
        mav.MAVLink_attitude_message(0, NAN, 0, INF, 0, 0, 0),
        mav.MAVLink_global_position_int_message(0, 2_000_000_000, 0, 0, 0, 0, 0, 0, 0),
        mav.MAVLink_home_position_message(-1_000_000_000, 0, 0, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0),
        mav.MAVLink_position_target_local_ned_message(0, 1, 0, NAN, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0),
        mav.MAVLink_sys_status_message(0, 0, 0, 0, 0, 0, 120, 0, 0, 0, 0, 0, 0),
        mav.MAVLink_heartbeat_message(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_PX4, 0, 0, 0, 3),
    ]
    samples: list[Telemetry] = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for _ in range(20):
            for msg in bad:
                tx.sendto(msg.pack(spoof), ("127.0.0.1", sim.server.cfg.port))
            for _ in range(10):
                samples.append(link.telemetry())
                time.sleep(0.001)
    assert all(math.isfinite(x) for tel in samples for x in numbers(tel))
    assert all(
        tel.autopilot == "ardupilot" for tel in samples
    )  # a GCS heartbeat is not the vehicle
    assert all(tel.battery_pct is None or tel.battery_pct <= 100 for tel in samples)
    assert all(abs(tel.home[0]) <= 90 for tel in samples if tel.home)
    assert link.faults["decode_error"] == 0 and link.faults["reopened"] == 0


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_arguments_that_cannot_be_flown_are_refused_unsent(
    memory_link: MemoryLinks, autopilot: str
) -> None:
    link = memory_link(autopilot=autopilot)
    for result in (
        link.takeoff(NAN),
        link.takeoff(-2.0),
        link.takeoff(INF),
        link.goto_local(NAN, 0.0, -2.0),
        link.goto_local(0.0, 0.0, -2.0, yaw=INF),
        link.change_speed(NAN),
        link.change_speed(0.0),
    ):
        assert result.ack == "invalid" and not result.ok and "nothing sent" in result.detail
    assert link.sent_count() == 0


def test_unused_params_follow_the_autopilot(memory_link: MemoryLinks) -> None:
    px4, ardupilot = memory_link(autopilot="px4"), memory_link("beta")
    arm = px4.arm()
    assert arm.ok and arm.sent["params"][0] == 1.0
    assert all(math.isnan(p) for p in arm.sent["params"][1:])  # NaN: "unset" to PX4
    assert ardupilot.set_mode("GUIDED").sent["params"][2:] == [0.0] * 5  # 0 to ArduPilot
    # DO_CHANGE_SPEED's reserved params are 0 in common.xml, whatever the autopilot.
    assert px4.change_speed(2.0).sent["params"] == [1.0, 2.0, -1.0, 0.0, 0.0, 0.0, 0.0]


def test_px4_takes_off_again_after_landing(memory_link: MemoryLinks) -> None:
    """PX4 arms from its holding modes: after a landing (mode LAND) the link switches to
    Hold first, as MAVSDK does."""
    link = memory_link(autopilot="px4")
    for _ in range(2):
        assert link.takeoff(2.0).ok
        assert link.wait_for(lambda t: t.landed == "in_air" and t.mode == "LOITER", 10.0)
        assert link.land().ok
        assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 20.0)
        assert link.telemetry().mode == "LAND"
