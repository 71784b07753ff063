"""The whole decision path (arbiter -> debounce -> arming) on explicit update sequences."""

from proxima.control import CommandController, ControlSettings, Sight, StreamUpdate
from proxima.events import ArmingEvent, CommandEvent, HandoverEvent

# Every command on its first filtered decision (no longer agreement for land here).
SETTINGS = ControlSettings(
    debounce_s=1.0, confirm=1, confirm_by_command={}, release_s=1.0, hold_s=1.0, regain_s=0.0
)


def segment(stream: str, start: float, stop: float, action: str, sight: Sight = Sight.FULL) -> list:
    dt = 0.2
    n = round((stop - start) / dt)
    return [StreamUpdate(stream, round(start + i * dt, 6), sight, action) for i in range(n)]


def run(ctl: CommandController, updates: list[StreamUpdate]) -> list:
    events = []
    for u in sorted(updates, key=lambda u: (u.t, ctl.arbiter.ranking.index(u.stream))):
        events.extend(ctl.process(u))
    return events


def commands(events: list) -> list[tuple[float, str, str, str]]:
    return [(e.t, e.command, e.stream, e.drone) for e in events if isinstance(e, CommandEvent)]


def test_no_motion_command_before_arming() -> None:
    ctl = CommandController(["main"], drone="x500", settings=SETTINGS)
    ev = run(
        ctl,
        segment("main", 0, 3, "move_to_left")
        + segment("main", 3, 5, "have_command")
        + segment("main", 5, 8, "move_to_left")
        + segment("main", 8, 10, "wave_off")
        + segment("main", 10, 12, "land"),
    )
    assert commands(ev) == [
        (3.0, "have_command", "main", "x500"),
        (5.0, "move_to_left", "main", "x500"),
        (8.0, "wave_off", "main", "x500"),
    ]
    arming = [(e.t, e.armed, e.reason) for e in ev if isinstance(e, ArmingEvent)]
    assert arming == [(3.0, True, "have_command"), (8.0, False, "wave_off")]


def test_idle_disarm_on_stream_time() -> None:
    settings = SETTINGS.model_copy(update={"idle_disarm_s": 5.0})
    ctl = CommandController(["main"], drone="x500", settings=settings)
    ev = run(
        ctl,
        segment("main", 0, 2, "have_command")
        + segment("main", 2, 9, "")
        + segment("main", 9, 11, "land"),
    )
    assert commands(ev) == [(0.0, "have_command", "main", "x500")]
    assert [(e.t, e.reason) for e in ev if isinstance(e, ArmingEvent) and not e.armed] == [
        (5.0, "idle")
    ]


def test_secondary_drives_the_main_drone_after_handover() -> None:
    ctl = CommandController(["main", "side"], drone="x500", settings=SETTINGS)
    main = (
        segment("main", 0, 2, "have_command")
        + segment("main", 2, 4, "move_to_left")
        + segment("main", 4, 12, "", Sight.PARTIAL)  # feet out of view
    )
    side = (
        segment("side", 0, 2, "hover")  # ignored: main drives
        + segment("side", 2, 6, "move_to_left")
        + segment("side", 6, 8, "have_command")
        + segment("side", 8, 10, "move_to_right")
        + segment("side", 10, 12, "land")
    )
    ev = run(ctl, main + side)
    handovers = [(e.t, e.from_stream, e.to_stream) for e in ev if isinstance(e, HandoverEvent)]
    # main had the whole operator last at 3.8; hold 1 s
    assert handovers == [(0.0, "", "main"), (5.0, "main", "side")]
    assert commands(ev) == [
        (0.0, "have_command", "main", "x500"),
        (2.0, "move_to_left", "main", "x500"),
        (6.0, "have_command", "side", "x500"),
        (8.0, "move_to_right", "side", "x500"),
        (10.0, "land", "side", "x500"),
    ]
    assert any(isinstance(e, ArmingEvent) and e.reason == "handover" for e in ev)


def test_operator_lost_everywhere_means_hover_and_disarm() -> None:
    ctl = CommandController(["main", "side"], drone="x500", settings=SETTINGS)
    ev = run(
        ctl,
        segment("main", 0, 3, "have_command")
        + segment("main", 3, 6, "", Sight.NONE)
        + segment("side", 0, 6, "", Sight.NONE),
    )
    assert commands(ev) == [(0.0, "have_command", "main", "x500"), (4.0, "hover", "", "x500")]
    assert not ctl.arming.armed
    assert ctl.active == ""
