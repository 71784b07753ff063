"""Safety rules in flight against `proxima sim-drone`: losing the operator makes the drone
hover, and an emergency stop needs its explicit confirmation."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from proxima.drone.controller import DroneController, EmergencyStopService
from proxima.drone.events import DroneAlarmEvent
from proxima.drone.mapping import DEFAULT_MAPPING, load_mapping
from proxima.drone.safety import EmergencyStopError, SafetyConfig
from proxima.events import CommandEvent, EventBus, PoseEvent
from proxima.store.command_log import CommandLog

if TYPE_CHECKING:
    from conftest import Connect, StartSim


def pose(t: float, sight: str) -> PoseEvent:
    return PoseEvent(
        t=t, stream="front", xyz=[[0.5, 0.5, 0.0]] * 33, visibility=[1.0] * 33, sight=sight
    )


def test_operator_lost_hovers_and_emergency_stop_needs_confirmation(
    start_sim: StartSim, connect: Connect, tmp_path: Path
) -> None:
    sim = start_sim("--max-speed", "1.0")  # slow enough to stop a 3 m move half-way
    bus = EventBus()
    alarms = bus.subscribe(types=["drone_alarm"])
    link = connect(sim, "alpha", bus)
    assert link.takeoff(2.0).ok
    assert link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 2.0) < 0.05, 6.0)

    # The editable table: a 3 m step for move_ahead.
    table = DEFAULT_MAPPING.read_text().replace(
        "direction = [1.0, 0.0, 0.0]", "direction = [1.0, 0.0, 0.0]\nstep_m = 3.0"
    )
    (tmp_path / "mapping.toml").write_text(table)
    mapping = load_mapping(tmp_path / "mapping.toml")
    assert mapping.actions["move_ahead"].step_m == 3.0

    log = CommandLog(tmp_path / "log.db")
    ctl = DroneController(
        {"alpha": link}, mapping=mapping, log=log, bus=bus, safety=SafetyConfig(operator_lost_s=0.6)
    )
    try:
        ctl.on_event(pose(0.0, "full"))
        ctl.handle(CommandEvent(t=0.1, stream="front", command="have_command", drone="alpha"))
        out = ctl.handle(CommandEvent(t=0.2, stream="front", command="move_ahead", drone="alpha"))
        assert out.status == "sent" and abs(out.target[0] - 3.0) < 0.05
        # The feet leave the image: the arbiter still lets this stream drive, so no hover.
        ctl.on_event(pose(0.25, "partial"))
        time.sleep(0.4)
        assert not ctl.safety.operator_lost()
        ctl.on_event(pose(0.3, "none"))  # the operator leaves every stream's view

        # After operator_lost_s the watchdog sends hold: the drone stops short of 3 m.
        time.sleep(0.7)
        tel = link.wait_for(lambda t: math.hypot(*t.velocity) < 0.02, 5.0)
        assert tel is not None and 0.3 < tel.position[0] < 2.0, tel.position
        time.sleep(0.3)
        assert abs(link.telemetry().position[0] - tel.position[0]) < 0.1  # it stays there
        watchdog = [r for r in log.recent() if r["source"] == "watchdog"]
        assert watchdog and watchdog[0]["action"] == "hold" and watchdog[0]["status"] == "sent"
        assert log.get(out.log_id)["outcome"] == "superseded"
        assert any(
            a.kind == "operator_lost" for a in alarms.drain() if isinstance(a, DroneAlarmEvent)
        )

        # Emergency stop, step one: a token; nothing is sent, the drone keeps flying.
        service = EmergencyStopService(ctl)
        sent = link.sent_count()
        req = service.request("alpha", "supervisor")
        assert req["confirmation_id"] and req["expires_in_s"] > 0
        time.sleep(0.3)
        assert link.sent_count() == sent and link.telemetry().landed == "in_air"
        with pytest.raises(PermissionError):
            service.confirm("alpha", "not-the-token", "supervisor")
        with pytest.raises(KeyError):
            service.confirm("nobody", req["confirmation_id"], "supervisor")
        assert link.sent_count() == sent

        # Step two with the token: the drone lands and disarms; the token is spent.
        done = service.confirm("alpha", req["confirmation_id"], "supervisor")
        assert done["ok"], done
        with pytest.raises(EmergencyStopError):
            ctl.confirm_emergency_stop(req["confirmation_id"])
        assert not ctl.gesture_control_armed("alpha")
        assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 8.0)
    finally:
        ctl.close()
    rows = [(r["command"], r["status"]) for r in log.recent() if r["command"] == "emergency_stop"]
    assert rows == [("emergency_stop", "sent"), ("emergency_stop", "pending")]
