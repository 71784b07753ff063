"""The in-memory link keeps the real one's contract: one scripted flight through the
DroneLink interface gives the same answers, modes and places over MAVLink/UDP to the
simulator `proxima sim-drone` runs (here on a thread, to skip the process start) as in
memory, for ArduPilot and for PX4. This is what lets the controller's unit tests run on
the in-memory link."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

from proxima.drone.link import CommandResult, DroneLink, Telemetry
from proxima.drone.mavlink.protocol import mav
from proxima.drone.memory import ManualClock, MemoryLink
from proxima.drone.sim import SimConfig

if TYPE_CHECKING:
    from conftest import Connect, ServeSim

from drone_helpers import FAST_SIM

AUTOPILOTS = ("ardupilot", "px4")
QUICK = {**FAST_SIM, "position_gain": 6.0}  # a snappier final approach: a shorter test


def answer(result: CommandResult) -> tuple[Any, ...]:
    """What a command's result must agree on (not its timing)."""
    sent = dict(result.sent)
    if "params" in sent:  # NaN != NaN: compare the params as text
        sent["params"] = [repr(p) for p in sent["params"]]
    return (result.action, result.ack, result.ok, result.confirmed, sent)


def state(tel: Telemetry | None) -> tuple[Any, ...]:
    assert tel is not None and tel.position is not None
    where = tuple(round(p, 1) + 0.0 for p in tel.position)  # + 0.0: no -0.0
    return (tel.autopilot, tel.mode, tel.armed, tel.landed, where)


def still(tel: Telemetry) -> bool:
    return tel.velocity is not None and math.hypot(*tel.velocity) < 0.05


def fly(link: DroneLink) -> dict[str, tuple[Any, ...]]:
    """Takeoff, a refused mode, the guided mode, a 1 m move, speed, hold, land, disarm;
    what each step answered and where the vehicle was."""
    out = {"start": state(link.telemetry())}
    out["unknown mode"] = answer(link.set_mode("NO_SUCH_MODE"))
    out["takeoff"] = answer(link.takeoff(2.0))
    tel = link.wait_for(
        lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.05 and t.mode != "TAKEOFF",
        10.0,
    )
    out["airborne"] = state(tel)
    out["enter guided"] = answer(link.enter_guided())
    start = link.telemetry().position
    target = (start[0], start[1] - 1.0, -2.0)
    out["goto"] = answer(link.goto_local(*target))[:4]  # `sent`: from the start position
    tel = link.wait_for(lambda t: t.distance_to(target) < 0.05 and still(t), 10.0)
    out["moved"] = state(tel)
    out["speed"] = answer(link.change_speed(2.0))
    out["hold"] = answer(link.hold())[:4]  # `sent`: the stopping point
    out["land"] = answer(link.land())
    tel = link.wait_for(
        lambda t: t.landed == "on_ground" and not t.armed and t.mode == "LAND", 10.0
    )
    out["landed"] = state(tel)
    out["disarm"] = answer(link.disarm())
    return out


def test_memory_link_answers_like_the_mavlink_link(serve_sim: ServeSim, connect: Connect) -> None:
    sims = {ap: serve_sim(sysid=5, autopilot=ap, **QUICK) for ap in AUTOPILOTS}
    with ThreadPoolExecutor(len(AUTOPILOTS)) as pool:  # both at once: half the time
        links = dict(zip(AUTOPILOTS, pool.map(connect, sims.values(), AUTOPILOTS), strict=True))
        for link in links.values():  # mode and arming changes show up in 0.1 s, not 1 s
            assert link.set_message_interval(mav.MAVLINK_MSG_ID_HEARTBEAT, 10.0).ok
        real = dict(zip(AUTOPILOTS, pool.map(fly, links.values()), strict=True))
    for ap in AUTOPILOTS:
        cfg = SimConfig(autopilot=ap, sysid=5, **QUICK)
        memory = MemoryLink(ap, cfg, clock=ManualClock())
        memory.connect()
        in_memory = fly(memory)
        assert in_memory == real[ap], ap
    # The two autopilots did differ, where they should.
    assert real["px4"]["takeoff"][4]["params"][6] == "302.0"  # PX4: the altitude AMSL
    assert real["ardupilot"]["takeoff"][4]["params"][6] == "2.0"
    assert real["px4"]["moved"][1] == "OFFBOARD" and real["ardupilot"]["moved"][1] == "GUIDED"
    assert real["px4"]["hold"][1] == "accepted"  # Hold mode; ArduPilot: a target, echoed
    assert real["ardupilot"]["hold"][1] == "echoed"
