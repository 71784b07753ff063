"""The MAVLink link against real simulator processes: several vehicles side by side, a
cut link (the simulator killed by PID), command retries over a lossy link, PX4 OFFBOARD."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import TYPE_CHECKING

from proxima.drone.controller import DroneController
from proxima.drone.events import CommandResultEvent, DroneAlarmEvent
from proxima.drone.mavlink import LinkConfig
from proxima.events import ActionEvent, ArmingEvent, CommandEvent, EventBus, Subscription
from proxima.store.command_log import CommandLog
from proxima.types import LinkState

if TYPE_CHECKING:
    from conftest import Connect, StartSim


def next_result(sub: Subscription, command: str) -> CommandResultEvent:
    """The next answer (not a later outcome) for `command` on a command_result queue."""
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline:
        event = sub.get(timeout=0.2)
        answer = isinstance(event, CommandResultEvent) and event.status != "done"
        if answer and event.command == command:
            return event
    raise AssertionError(f"no result for {command}")


def test_two_vehicles_and_a_cut_link(start_sim: StartSim, connect: Connect) -> None:
    sim_a, sim_b = start_sim(sysid=11), start_sim(sysid=12)
    bus = EventBus()
    alarms = bus.subscribe(types=["drone_alarm"])
    link_a, link_b = connect(sim_a, "a", bus), connect(sim_b, "b", bus)
    assert link_a.telemetry().system_id == 11 and link_b.telemetry().system_id == 12

    ctl = DroneController({"a": link_a, "b": link_b}, bus=bus)
    try:
        ctl.handle(CommandEvent(t=0.0, stream="front", command="have_command", drone="a"))
        assert ctl.gesture_control_armed("a")

        os.kill(sim_a.proc.pid, signal.SIGKILL)
        cut = time.monotonic()
        while link_a.state != LinkState.LOST and time.monotonic() - cut < 6.0:
            time.sleep(0.01)
        lost_after = time.monotonic() - cut
        assert link_a.state == LinkState.LOST
        # 3 s without a heartbeat; the last one came at most 1 s before the cut.
        assert lost_after <= 3.0 + 0.15, lost_after
        assert link_b.state == LinkState.OK  # the other vehicle is untouched

        # Link lost: nothing is sent, and an alarm was raised.
        sent = link_a.sent_count()
        result = link_a.arm()
        assert result.ack == "link_lost" and not result.ok and result.attempts == 0
        assert link_a.sent_count() == sent
        deadline = time.monotonic() + 1.0
        while ctl.gesture_control_armed("a") and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not ctl.gesture_control_armed("a")  # have_command again once the link is back
        out = ctl.handle(CommandEvent(t=1.0, stream="front", command="hover", drone="a"))
        assert out.status == "refused" and link_a.sent_count() == sent
        kinds = {(e.drone, e.kind) for e in alarms.drain() if isinstance(e, DroneAlarmEvent)}
        assert ("a", "link_lost") in kinds and ("b", "link_lost") not in kinds

        # The vehicle comes back (a new process on the same port): the link recovers,
        # but gesture control stays disarmed until the operator arms it again.
        start_sim(sysid=11, port=sim_a.port)
        back = time.monotonic()
        while link_a.state != LinkState.OK and time.monotonic() - back < 15.0:
            time.sleep(0.02)
        assert link_a.state == LinkState.OK
        assert link_a.arm().ok and not ctl.gesture_control_armed("a")
        recovered = [e for e in alarms.drain() if isinstance(e, DroneAlarmEvent)]
        assert any(e.kind == "link_lost" and not e.active for e in recovered)
    finally:
        ctl.close()


def test_commands_are_retried_until_acknowledged(start_sim: StartSim, connect: Connect) -> None:
    sim = start_sim("--loss", "0.5", "--seed", "7")  # the vehicle drops half of what it gets
    link = connect(sim, config=LinkConfig(ack_timeout_s=0.1, retries=10))
    results = [link.change_speed(1.0 + 0.25 * i) for i in range(12)]
    assert all(r.ok and r.ack == "accepted" and r.confirmed for r in results), results
    assert sum(r.attempts for r in results) > len(results)  # some needed a retry
    assert max(r.attempts for r in results) > 1

    sent = link.sent_count()
    unknown = link.set_mode("NO_SUCH_MODE")  # refused here, never sent
    assert not unknown.ok and unknown.ack == "unknown_mode" and link.sent_count() == sent


def test_px4_offboard_flight(start_sim: StartSim, connect: Connect, tmp_path: Path) -> None:
    sim = start_sim("--autopilot", "px4", sysid=3)
    link = connect(sim)
    tel = link.telemetry()
    assert tel.autopilot == "px4" and tel.mode == "LOITER"

    takeoff = link.takeoff(2.0)
    assert takeoff.ok, takeoff
    assert takeoff.sent["params"][6] == 302.0  # PX4 wants the takeoff altitude AMSL
    # PX4 holds (AUTO.LOITER) once AUTO.TAKEOFF reached the altitude.
    tel = link.wait_for(lambda t: t.mode == "LOITER" and abs(t.altitude - 2.0) < 0.05, 6.0)
    assert tel is not None and tel.landed == "in_air"

    # Driven through the bus, as the live engine drives it.
    bus = EventBus()
    results = bus.subscribe(types=["command_result"])
    log = CommandLog(tmp_path / "log.db")
    ctl = DroneController({"alpha": link}, log=log)
    ctl.attach(bus)
    try:
        bus.publish(ArmingEvent(t=0.0, stream="s", armed=True, reason="have_command"))
        bus.publish(ActionEvent(t=0.9, stream="s", action="move_to_right", confidence=0.87))
        start = tel.position
        bus.publish(CommandEvent(t=1.0, stream="s", command="move_to_right", drone="alpha"))
        sent = next_result(results, "move_to_right")
        assert sent.status == "sent"
        row = log.get(sent.log_id)
        assert row["confidence"] == 0.87 and row["gesture_t"] == 1.0 and row["stream"] == "s"
        target = (start[0], start[1] + 1.0, start[2])
        tel = link.wait_for(lambda t: t.distance_to(target) < 0.05, 6.0)
        assert tel is not None and abs(tel.position[1] - (start[1] + 1.0)) < 0.1
        time.sleep(0.8)  # the setpoint stream (> 2 Hz) keeps PX4 in OFFBOARD
        assert link.telemetry().mode == "OFFBOARD"
        assert link.sent_counts["SET_POSITION_TARGET_LOCAL_NED"] > 8

        # wave_off: the engine publishes the command, then its disarm; the hold goes out.
        bus.publish(CommandEvent(t=2.0, stream="s", command="wave_off", drone="alpha"))
        bus.publish(ArmingEvent(t=2.0, stream="s", armed=False, reason="wave_off"))
        abort = next_result(results, "wave_off")
        assert abort.status == "sent" and abort.action == "abort"
        assert link.telemetry().mode == "LOITER"  # PX4's Hold
        bus.publish(CommandEvent(t=3.0, stream="s", command="land", drone="alpha"))
        assert next_result(results, "land").status == "refused"  # disarmed by wave_off
        bus.publish(CommandEvent(t=4.0, stream="s", command="have_command", drone="alpha"))
        bus.publish(CommandEvent(t=5.0, stream="s", command="land", drone="alpha"))
        assert next_result(results, "land").status == "sent"
        assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 8.0)
    finally:
        ctl.close()
