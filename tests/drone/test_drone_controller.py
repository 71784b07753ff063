"""The drone controller on the in-memory link (the simulated vehicle of `proxima sim-drone`
in this process, on a manual clock): body-frame moves, mode rules, outcome tracking,
speed gestures, refusals, a lost link, the operator watchdog and the emergency stop,
each with the command-log rows and events it leaves. What the vehicle does is the
simulator's own physics; only the wire is gone (test_drone_contract.py holds the two
links to the same answers)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from proxima.drone.controller import DroneController, EmergencyStopService
from proxima.drone.events import CommandResultEvent, DroneAlarmEvent
from proxima.drone.mapping import DEFAULT_MAPPING, load_mapping
from proxima.drone.memory import ManualClock, MemoryLink
from proxima.drone.safety import EmergencyStopError, SafetyConfig, SafetyGate
from proxima.events import ActionEvent, ArmingEvent, CommandEvent, EventBus, PoseEvent
from proxima.store.command_log import CommandLog
from proxima.types import LinkState

if TYPE_CHECKING:
    from conftest import MemoryLinks

Controllers = Callable[..., DroneController]


def cmd(t: float, command: str, drone: str = "alpha") -> CommandEvent:
    return CommandEvent(t=t, stream="front", command=command, drone=drone)


def pose(t: float, sight: str) -> PoseEvent:
    return PoseEvent(
        t=t, stream="front", xyz=[[0.5, 0.5, 0.0]] * 33, visibility=[1.0] * 33, sight=sight
    )


def speed(link: MemoryLink) -> float:
    tel = link.telemetry()
    assert tel is not None and tel.velocity is not None
    return math.hypot(*tel.velocity)


def airborne(link: MemoryLink, clock: ManualClock, altitude: float = 2.0) -> None:
    """Pre-flight: take off and hover, as a pilot does before gesture control."""
    assert link.takeoff(altitude).ok
    hover = link.wait_for(
        lambda t: (
            t.landed == "in_air" and abs(t.altitude - altitude) < 0.02 and t.mode != "TAKEOFF"
        ),
        10.0,
    )
    assert hover is not None, link.telemetry()
    clock.advance(1.0)  # settled


def outcome(log: CommandLog, log_id: int | None, timeout: float = 3.0) -> str | None:
    """The row's outcome once the controller's watchdog has set it (wall seconds)."""
    assert log_id is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        got = log.get(log_id)["outcome"]
        if got is not None:
            return got
        time.sleep(0.01)
    return None


@pytest.fixture
def log(tmp_path: Path) -> CommandLog:
    return CommandLog(tmp_path / "proxima.db")


@pytest.fixture
def controller(clock: ManualClock, log: CommandLog) -> Iterator[Controllers]:
    """Controllers on the test's clock (outcome deadlines and the safety rules)."""
    made: list[DroneController] = []

    def make(links: dict[str, MemoryLink], bus: EventBus | None = None, **limits: float):
        safety = SafetyGate(SafetyConfig(**{"min_interval_s": 0.0, **limits}), clock=clock)
        ctl = DroneController(links, safety=safety, log=log, bus=bus, clock=clock)
        made.append(ctl)
        return ctl

    yield make
    for ctl in made:
        ctl.close()


def test_moves_are_in_the_drones_body_frame(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link()
    airborne(link, clock)
    here = link.telemetry().position
    assert link.goto_local(*here, yaw=math.pi / 2).ok  # the drone turns to face east
    clock.advance(2.0)
    assert abs(link.telemetry().yaw - math.pi / 2) < 1e-9
    ctl = controller({"alpha": link})
    assert ctl.handle(cmd(1.0, "have_command")).status == "done"

    # Facing east: ahead is east, its left is north, up is -z.
    for t, gesture, step in (
        (2.0, "move_ahead", (0.0, 1.0, 0.0)),
        (3.0, "move_to_left", (1.0, 0.0, 0.0)),
        (4.0, "move_upward", (0.0, 0.0, -1.0)),
    ):
        before = link.telemetry().position_target  # the vehicle is settled on it
        out = ctl.handle(cmd(t, gesture))
        assert out.status == "sent" and out.result.ack == "echoed", out
        want = tuple(b + s for b, s in zip(before, step, strict=True))
        assert math.dist(out.target, want) < 1e-6, (gesture, out.target, want)
        clock.advance(3.0)
        assert outcome(log, out.log_id) == "reached"
        assert link.telemetry().distance_to(want) < 0.02
        row = log.get(out.log_id)
        assert row["sent"]["msg"] == "SET_POSITION_TARGET_LOCAL_NED"
        assert row["sent"]["x"] == out.target[0] and row["stream"] == "front"
    assert abs(link.telemetry().yaw - math.pi / 2) < 1e-9  # moves leave the heading alone


def test_gestures_take_over_only_from_holding_modes(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link(land_speed=0.5)
    airborne(link, clock)
    ctl = controller({"alpha": link})
    ctl.safety.arm_control("alpha")

    # LOITER holds position: a move takes the vehicle into GUIDED and goes.
    assert link.set_mode("LOITER").ok
    out = ctl.handle(cmd(1.0, "move_to_right"))
    assert out.status == "sent" and link.telemetry().mode == "GUIDED"
    clock.advance(3.0)
    assert outcome(log, out.log_id) == "reached"

    # RTL, LAND and a pilot's STABILIZE are never overridden by a move; nothing is sent.
    for mode in ("RTL", "STABILIZE", "LAND"):
        assert link.set_mode(mode).ok
        sent = link.sent_count()
        out = ctl.handle(cmd(2.0, "move_to_left"))
        assert out.status == "refused" and f"vehicle in {mode}" in out.reason, out
        assert link.sent_count() == sent and link.telemetry().mode == mode

    # But hover stops a landing: GUIDED, holding where it braked.
    clock.advance(0.3)
    low = link.telemetry().altitude
    assert low < 2.0
    out = ctl.handle(cmd(3.0, "hover"))
    assert out.status == "sent" and out.action == "hold", out
    assert link.telemetry().mode == "GUIDED"
    clock.advance(3.0)
    assert outcome(log, out.log_id) == "reached"
    held = link.telemetry().altitude
    clock.advance(5.0)
    assert abs(link.telemetry().altitude - held) < 0.01 and held > 1.0


def test_steps_follow_on_from_the_settling_target(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link()
    airborne(link, clock)
    ctl = controller({"alpha": link})
    ctl.safety.arm_control("alpha")
    start = link.telemetry().position

    first = ctl.handle(cmd(1.0, "move_to_left"))
    # Sent again at once: the vehicle is still 1 m from the first target, so the step
    # starts where the vehicle is (the same target), and the first is superseded.
    again = ctl.handle(cmd(1.1, "move_to_left"))
    assert math.dist(first.target, again.target) < 0.01
    assert outcome(log, first.log_id) == "superseded"
    clock.advance(3.0)
    assert outcome(log, again.log_id) == "reached"
    settled = link.telemetry()
    assert settled.position != again.target  # within tolerance, not exactly there
    # Settled near its target: the next step starts from the target, not from the noise.
    third = ctl.handle(cmd(2.0, "move_to_left"))
    assert third.target == (again.target[0], again.target[1] - 1.0, again.target[2])
    assert abs(third.target[1] - (start[1] - 2.0)) < 0.02


def test_outcomes_not_reached_landed_and_on_the_ground(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link()
    airborne(link, clock)
    ctl = controller({"alpha": link})
    ctl.safety.arm_control("alpha")

    # A pilot takes over mid-move (LOITER stops the vehicle): the target is never reached
    # and the outcome says so once its deadline (5 s + 3 x the time at speed) passed.
    out = ctl.handle(cmd(1.0, "move_ahead"))
    clock.advance(0.2)
    assert link.set_mode("LOITER").ok
    clock.advance(5.0)
    time.sleep(0.2)
    assert log.get(out.log_id)["outcome"] is None  # not yet: 5.6 s
    clock.advance(1.0)
    assert outcome(log, out.log_id) == "not_reached"
    assert link.telemetry().distance_to(out.target) > 0.25

    out = ctl.handle(cmd(2.0, "land"))
    assert out.status == "sent" and out.result.sent["command"] == "MAV_CMD_NAV_LAND"
    clock.advance(5.0)
    assert outcome(log, out.log_id) == "landed"
    tel = link.telemetry()
    assert tel.landed == "on_ground" and not tel.armed

    sent = link.sent_count()
    assert ctl.handle(cmd(3.0, "land")).reason == "already on the ground"
    assert ctl.handle(cmd(4.0, "hover")).reason == "on the ground: nothing to hold"
    abort = ctl.handle(cmd(5.0, "wave_off"))
    assert abort.status == "ignored" and not ctl.gesture_control_armed("alpha")
    assert log.get(abort.log_id)["outcome"] == "control_disarmed"
    assert link.sent_count() == sent


def test_speed_gestures_halve_and_restore(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link()
    airborne(link, clock)
    ctl = controller({"alpha": link}, min_interval_s=1.0)
    ctl.safety.arm_control("alpha")
    speeds = []
    for t in range(5):
        out = ctl.handle(cmd(float(t), "slow_down"))
        assert out.status == "sent" and out.result.ack == "accepted", out
        speeds.append(log.get(out.log_id)["sent"]["params"][1])
        assert link.vehicle.speed == speeds[-1]  # the vehicle flies at it
        # Motion commands are rate-limited; hold never is.
        quick = ctl.handle(cmd(t + 0.5, "slow_down"))
        assert quick.status == "refused" and "rate limit" in quick.reason
        assert ctl.handle(cmd(t + 0.6, "hover")).status == "sent"
        clock.advance(1.1)
    assert speeds == [2.5, 1.25, 0.625, 0.5, 0.5]  # halved, not below min_speed_m_s
    out = ctl.handle(cmd(9.0, "all_clear"))
    assert out.action == "resume_speed" and link.vehicle.speed == 5.0
    assert log.get(out.log_id)["outcome"] == "done"


def test_refusals_send_nothing_and_are_logged(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link()
    airborne(link, clock)
    silent = MemoryLink("bravo", clock=clock)  # never connected: no heartbeat yet
    ctl = controller({"alpha": link, "bravo": silent})
    sent = link.sent_count()
    refusals = [
        (cmd(1.0, "move_to_left"), "gesture control not armed"),
        (cmd(2.0, "backflip"), "no entry for gesture 'backflip'"),
        (cmd(3.0, "hover", drone="charlie"), "unknown drone 'charlie'"),
        (cmd(4.0, "hover", drone="bravo"), "link connecting: nothing sent"),
    ]
    ctl.safety.arm_control("bravo")
    for event, reason in refusals:
        out = ctl.handle(event)
        assert out.status == "refused" and reason in out.reason, out
        row = log.get(out.log_id)
        assert (row["status"], row["outcome"], row["command"]) == (
            "refused",
            "refused",
            event.command,
        )
        assert reason in row["reason"]
    assert link.sent_count() == sent and silent.sent_count() == 0

    # A fence of 0.5 m: the step is checked before anything goes out.
    fenced = controller({"alpha": link}, geofence_radius_m=0.5)
    fenced.safety.arm_control("alpha")
    out = fenced.handle(cmd(5.0, "move_to_left"))
    assert out.status == "refused" and "geofence" in out.reason
    assert link.sent_count() == sent


def test_a_lost_link_disarms_its_drone_only(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    a, b = memory_link("a"), memory_link("b")
    airborne(a, clock)
    bus = EventBus()
    alarms = bus.subscribe(types=["drone_alarm"])
    ctl = controller({"a": a, "b": b}, bus=bus)
    ctl.on_event(ArmingEvent(t=0.0, stream="front", armed=True, reason="have_command"))
    assert ctl.gesture_control_armed("a") and ctl.gesture_control_armed("b")  # all drones
    move = ctl.handle(cmd(1.0, "move_to_left", drone="a"))
    assert move.status == "sent"

    a.cut()
    # The watchdog disarms first, then ends the command and raises the alarm: wait for
    # the alarm, its last step, before looking at the rest.
    deadline = time.monotonic() + 2.0
    lost: list[DroneAlarmEvent] = []
    while not lost and time.monotonic() < deadline:
        time.sleep(0.01)
        lost += [e for e in alarms.drain() if isinstance(e, DroneAlarmEvent)]
    assert not ctl.gesture_control_armed("a") and ctl.gesture_control_armed("b")
    assert outcome(log, move.log_id) == "link_lost"
    time.sleep(0.2)  # four more watchdog ticks: no second alarm
    lost += [e for e in alarms.drain() if isinstance(e, DroneAlarmEvent)]
    assert [(e.drone, e.kind) for e in lost] == [("a", "link_lost")]
    assert "have_command again" in lost[0].message

    sent = a.sent_count()
    assert a.arm().ack == "link_lost" and a.sent_count() == sent  # the link sends nothing
    ctl.safety.arm_control("a")
    out = ctl.handle(cmd(2.0, "hover", drone="a"))
    assert out.status == "refused" and out.reason == "link lost: nothing sent"
    assert a.sent_count() == sent
    ctl.safety.disarm_control("a")

    a.restore()  # heard again: the operator must arm gesture control again
    time.sleep(0.2)
    assert a.state == LinkState.OK and not ctl.gesture_control_armed("a")
    assert ctl.handle(cmd(3.0, "hover", drone="a")).status == "refused"


def test_operator_lost_hovers_and_emergency_stop_needs_confirmation(
    memory_link: MemoryLinks,
    clock: ManualClock,
    controller: Controllers,
    log: CommandLog,
    tmp_path: Path,
) -> None:
    link = memory_link(max_speed=1.0)  # slow enough to stop a 3 m move half-way
    bus = EventBus()
    alarms = bus.subscribe(types=["drone_alarm"])
    airborne(link, clock)

    # The editable table: a 3 m step for move_ahead.
    table = DEFAULT_MAPPING.read_text().replace(
        "direction = [1.0, 0.0, 0.0]", "direction = [1.0, 0.0, 0.0]\nstep_m = 3.0"
    )
    (tmp_path / "mapping.toml").write_text(table)
    mapping = load_mapping(tmp_path / "mapping.toml")
    assert mapping.actions["move_ahead"].step_m == 3.0
    safety = SafetyGate(SafetyConfig(operator_lost_s=0.6), clock=clock)
    ctl = DroneController(
        {"alpha": link}, mapping=mapping, log=log, bus=bus, safety=safety, clock=clock
    )
    try:
        ctl.on_event(pose(0.0, "full"))
        ctl.handle(cmd(0.1, "have_command"))
        out = ctl.handle(cmd(0.2, "move_ahead"))
        assert out.status == "sent" and abs(out.target[0] - 3.0) < 0.05
        # The feet leave the image: the arbiter still lets this stream drive, so no hover.
        ctl.on_event(pose(0.25, "partial"))
        clock.advance(0.4)
        assert not ctl.safety.operator_lost()
        ctl.on_event(pose(0.3, "none"))  # the operator leaves every stream's view
        clock.advance(0.1)
        time.sleep(0.2)
        assert not ctl.safety.operator_lost()  # 0.5 s since the partial sighting
        assert not any(r["source"] == "watchdog" for r in log.recent())

        # After operator_lost_s the watchdog sends hold: the drone stops short of 3 m.
        clock.advance(0.2)
        deadline = time.monotonic() + 3.0
        while not any(r["source"] == "watchdog" and r["ack"] for r in log.recent()):
            assert time.monotonic() < deadline, "no watchdog hold answered"
            time.sleep(0.01)
        tel = link.wait_for(lambda t: math.hypot(*t.velocity) < 0.02, 5.0)
        assert tel is not None and 0.3 < tel.position[0] < 2.0, tel.position
        clock.advance(3.0)
        assert abs(link.telemetry().position[0] - tel.position[0]) < 0.1  # it stays there
        watchdog = [r for r in log.recent() if r["source"] == "watchdog"]
        assert len(watchdog) == 1  # once per loss
        assert watchdog[0]["action"] == "hold" and watchdog[0]["status"] == "sent"
        assert watchdog[0]["command"] == "operator_lost"
        assert outcome(log, out.log_id) == "superseded"
        assert any(
            a.kind == "operator_lost" for a in alarms.drain() if isinstance(a, DroneAlarmEvent)
        )

        # Emergency stop, step one: a token; nothing is sent, the drone keeps flying.
        service = EmergencyStopService(ctl)
        sent = link.sent_count()
        req = service.request("alpha", "supervisor")
        assert req["confirmation_id"] and req["expires_in_s"] > 0
        clock.advance(0.3)
        assert link.sent_count() == sent and link.telemetry().landed == "in_air"
        with pytest.raises(PermissionError):
            service.confirm("alpha", "not-the-token", "supervisor")
        with pytest.raises(KeyError):
            service.confirm("nobody", req["confirmation_id"], "supervisor")
        with pytest.raises(KeyError):
            service.request("nobody", "supervisor")
        assert link.sent_count() == sent

        # Step two with the token: the drone lands and disarms; the token is spent.
        done = service.confirm("alpha", req["confirmation_id"], "supervisor")
        assert done["ok"], done
        with pytest.raises(EmergencyStopError):
            ctl.confirm_emergency_stop(req["confirmation_id"])
        assert not ctl.gesture_control_armed("alpha")
        assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 8.0)
        assert outcome(log, done["log_id"]) == "landed"
    finally:
        ctl.close()
    rows = [(r["command"], r["status"]) for r in log.recent() if r["command"] == "emergency_stop"]
    assert rows == [("emergency_stop", "sent"), ("emergency_stop", "pending")]


def test_emergency_kill_stops_the_motors_of_that_drone_only(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    a, b = memory_link("a"), memory_link("b")
    airborne(a, clock)
    airborne(b, clock)
    ctl = controller({"a": a, "b": b})
    token = ctl.request_emergency_stop("a", "kill").token
    other = ctl.request_emergency_stop("b", "kill").token
    with pytest.raises(EmergencyStopError, match="issued for 'b'"):
        ctl.confirm_emergency_stop(other, drone="a")
    out = ctl.confirm_emergency_stop(token, drone="a")
    assert out.status == "sent" and out.action == "kill"
    assert out.result.sent["params"][:2] == [0.0, 21196.0]  # force-disarm in flight
    clock.advance(1.0)  # it falls
    tel = a.telemetry()
    assert not tel.armed and tel.landed == "on_ground" and tel.altitude == 0.0
    assert b.telemetry().armed and abs(b.telemetry().altitude - 2.0) < 0.05
    assert log.get(out.log_id)["outcome"] == "done"


def test_px4_through_the_bus(
    memory_link: MemoryLinks, clock: ManualClock, controller: Controllers, log: CommandLog
) -> None:
    link = memory_link(autopilot="px4")
    airborne(link, clock)
    assert link.telemetry().mode == "LOITER"  # PX4 holds after AUTO.TAKEOFF
    bus = EventBus()
    results = bus.subscribe(types=["command_result"])
    ctl = controller({"alpha": link})
    ctl.attach(bus)

    def answer(command: str) -> CommandResultEvent:
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:
            event = results.get(timeout=0.1)
            answered = isinstance(event, CommandResultEvent) and event.status != "done"
            if answered and event.command == command:
                return event
        raise AssertionError(f"no result for {command}")

    bus.publish(ArmingEvent(t=0.0, stream="s", armed=True, reason="have_command"))
    bus.publish(ActionEvent(t=0.9, stream="s", action="move_to_right", confidence=0.87))
    start = link.telemetry().position
    bus.publish(CommandEvent(t=1.0, stream="s", command="move_to_right", drone="alpha"))
    sent = answer("move_to_right")
    assert sent.status == "sent" and sent.ack == "echoed"
    row = log.get(sent.log_id)
    assert row["confidence"] == 0.87 and row["gesture_t"] == 1.0 and row["stream"] == "s"
    clock.advance(5.0)  # the setpoint stream (> 2 Hz) keeps PX4 in OFFBOARD meanwhile
    assert outcome(log, sent.log_id) == "reached"
    tel = link.telemetry()
    assert tel.mode == "OFFBOARD" and abs(tel.position[1] - (start[1] + 1.0)) < 0.05
    assert link.sent_counts["SET_POSITION_TARGET_LOCAL_NED"] >= 50  # 10 Hz

    # wave_off: the engine publishes the command, then its disarm; the hold goes out.
    bus.publish(CommandEvent(t=2.0, stream="s", command="wave_off", drone="alpha"))
    bus.publish(ArmingEvent(t=2.0, stream="s", armed=False, reason="wave_off"))
    abort = answer("wave_off")
    assert abort.status == "sent" and abort.action == "abort"
    assert link.telemetry().mode == "LOITER"  # PX4's Hold; the stream stopped
    streamed = link.sent_counts["SET_POSITION_TARGET_LOCAL_NED"]
    clock.advance(1.0)
    assert link.sent_counts["SET_POSITION_TARGET_LOCAL_NED"] == streamed
    bus.publish(CommandEvent(t=3.0, stream="s", command="land", drone="alpha"))
    assert answer("land").status == "refused"  # disarmed by wave_off
    bus.publish(CommandEvent(t=4.0, stream="s", command="have_command", drone="alpha"))
    bus.publish(CommandEvent(t=5.0, stream="s", command="land", drone="alpha"))
    assert answer("land").status == "sent"
    assert link.wait_for(lambda t: t.landed == "on_ground" and not t.armed, 8.0)
