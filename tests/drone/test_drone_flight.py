"""A whole gesture-commanded flight against `proxima sim-drone` over real UDP: heartbeat,
mode change, arming, takeoff, safety refusals, a 1 m move to the left, landing, and the
command log rows it leaves."""

from __future__ import annotations

import math
import sqlite3
import time
from pathlib import Path
from typing import TYPE_CHECKING

from proxima.drone.controller import DroneController
from proxima.drone.events import CommandResultEvent, DroneStateEvent
from proxima.drone.link import Telemetry
from proxima.drone.safety import SafetyConfig
from proxima.events import CommandEvent, EventBus
from proxima.store.command_log import CommandLog

if TYPE_CHECKING:
    from conftest import Connect, StartSim


def cmd(t: float, command: str, drone: str = "alpha") -> CommandEvent:
    return CommandEvent(t=t, stream="front", command=command, drone=drone)


def speed(tel: Telemetry) -> float:
    return math.hypot(*tel.velocity)


def test_gesture_flight_ardupilot(start_sim: StartSim, connect: Connect, tmp_path: Path) -> None:
    sim = start_sim(sysid=7)
    bus = EventBus()
    events = bus.subscribe(maxsize=10_000)
    link = connect(sim, "alpha", bus)

    # Heartbeat: a quadrotor running ArduPilot, sysid 7, disarmed on the ground.
    tel = link.telemetry()
    assert tel.system_id == 7 and tel.autopilot == "ardupilot"
    assert tel.mode == "STABILIZE" and not tel.armed and tel.landed == "on_ground"
    assert tel.battery_pct == 100.0

    # Mode change: acknowledged, and still reported by the heartbeats that follow.
    result = link.set_mode("GUIDED")
    assert result.ok and result.ack == "accepted" and result.confirmed
    time.sleep(1.1)  # at least one heartbeat later
    assert link.telemetry().mode == "GUIDED"

    # Arming the motors, then takeoff to 2 m.
    assert link.arm().ack == "accepted"
    assert link.takeoff(2.0).ack == "accepted"
    tel = link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.05, 6.0)
    assert tel is not None and tel.armed

    log = CommandLog(tmp_path / "proxima.db")
    ctl = DroneController(
        {"alpha": link}, log=log, bus=bus, safety=SafetyConfig(min_interval_s=0.5)
    )
    try:
        # A gesture before have_command sends nothing.
        sent_before = link.sent_count()
        target_before = link.telemetry().position_target  # the takeoff target
        out = ctl.handle(cmd(1.0, "move_to_left"))
        assert out.status == "refused" and "not armed" in out.reason
        time.sleep(0.3)
        assert link.sent_count() == sent_before
        assert link.telemetry().position_target == target_before  # the vehicle got nothing

        # have_command arms gesture control, not the motors: still nothing sent.
        out = ctl.handle(cmd(2.0, "have_command"))
        assert out.status == "done" and ctl.gesture_control_armed("alpha")
        assert link.sent_count() == sent_before

        # move_to_left: 1 m to the drone's left; heading north, that is 1 m west.
        start = link.wait_for(lambda t: speed(t) < 0.05, 3.0).position
        out = ctl.handle(cmd(3.0, "move_to_left"))
        assert out.status == "sent" and out.result.ack == "echoed", out
        # Rate limit: a second motion command right after is refused, nothing sent.
        sent_before = link.sent_count()
        quick = ctl.handle(cmd(3.1, "move_to_right"))
        assert quick.status == "refused" and "rate limit" in quick.reason
        assert link.sent_count() == sent_before
        tel = link.wait_for(lambda t: t.distance_to(out.target) < 0.05 and speed(t) < 0.05, 6.0)
        assert tel is not None, link.telemetry()
        assert abs(tel.position[1] - (start[1] - 1.0)) < 0.1  # 1 m west
        assert abs(tel.position[0] - start[0]) < 0.1
        assert abs(tel.altitude - 2.0) < 0.1

        # Geofence: a 0.5 m fence refuses the next step; nothing is sent.
        fenced = DroneController(
            {"alpha": link}, log=log, safety=SafetyConfig(geofence_radius_m=0.5)
        )
        try:
            fenced.safety.arm_control("alpha")
            sent_before = link.sent_count()
            out_fence = fenced.handle(cmd(4.0, "move_to_left"))
            assert out_fence.status == "refused" and "geofence" in out_fence.reason
            assert link.sent_count() == sent_before
        finally:
            fenced.close()

        # land: down, on the ground, disarmed by the vehicle itself.
        out_land = ctl.handle(cmd(5.0, "land"))
        assert out_land.status == "sent" and out_land.result.ack == "accepted"
        tel = link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 8.0)
        assert tel is not None and abs(tel.altitude) < 0.05
        assert abs(tel.position[1] - (start[1] - 1.0)) < 0.15  # landed where it was
        assert tel.battery_voltage < 16.8  # flying drained the battery (16.8 V when full)

        # The command log holds every command with its gesture, ack and outcome.
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:
            if log.get(out_land.log_id)["outcome"] == "landed":
                break
            time.sleep(0.05)
    finally:
        ctl.close()

    con = sqlite3.connect(tmp_path / "proxima.db")
    rows = con.execute(
        "SELECT command, status, ack, outcome, stream, gesture_t, sent FROM command_log "
        "WHERE source = 'gesture' ORDER BY id"
    ).fetchall()
    con.close()
    by = [(r[0], r[1], r[3]) for r in rows]
    assert by == [
        ("move_to_left", "refused", "refused"),
        ("have_command", "done", "control_armed"),
        ("move_to_left", "sent", "reached"),
        ("move_to_right", "refused", "refused"),
        ("move_to_left", "refused", "refused"),  # the geofence
        ("land", "sent", "landed"),
    ]
    move = rows[2]
    assert move[2] == "echoed" and move[4] == "front" and move[5] == 3.0
    assert "SET_POSITION_TARGET_LOCAL_NED" in move[6]
    assert "MAV_CMD_NAV_LAND" in rows[5][6]

    seen = events.drain()
    states = [e for e in seen if isinstance(e, DroneStateEvent)]
    results = [e for e in seen if isinstance(e, CommandResultEvent)]
    assert states and states[-1].drone == "alpha" and states[-1].link == "ok"
    assert any(e.position is not None and e.armed for e in states)
    assert {e.outcome for e in results} >= {"refused", "control_armed", "reached", "landed"}
