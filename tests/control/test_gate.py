"""The debounce gate on explicit sequences of filtered actions."""

import pytest

from proxima.control import CommandGate


def always(_: str) -> bool:
    return True


def run(gate: CommandGate, seq: list[tuple[float, str]], allowed=always) -> list[tuple[float, str]]:
    fired = []
    for t, action in seq:
        cmd = gate.step(t, action, allowed)
        if cmd is not None:
            fired.append((t, cmd))
    return fired


def ticks(start: float, stop: float, action: str, dt: float = 0.25) -> list[tuple[float, str]]:
    n = round((stop - start) / dt)
    return [(round(start + i * dt, 6), action) for i in range(n)]


def test_held_gesture_fires_once() -> None:
    gate = CommandGate(debounce_s=1.0, release_s=1.0)
    fired = run(gate, ticks(0, 10, "move_to_left"))
    assert fired == [(0.0, "move_to_left")]


def test_new_gesture_fires_after_the_debounce_not_before() -> None:
    gate = CommandGate(debounce_s=2.0, release_s=1.0)
    seq = ticks(0, 1, "hover") + ticks(1, 5, "land")
    # hover at 0; land is there from 1.0 but must wait for 2.0 s after the hover.
    assert run(gate, seq) == [(0.0, "hover"), (2.0, "land")]


def test_debounce_is_stream_time_the_paper_setting() -> None:
    gate = CommandGate(debounce_s=10.0)
    seq = ticks(0, 3, "hover") + ticks(3, 12, "land") + ticks(12, 25, "move_ahead")
    # land waits until 10 s after hover, move_ahead until 10 s after land.
    assert run(gate, seq) == [(0.0, "hover"), (10.0, "land"), (20.0, "move_ahead")]


def test_short_blip_is_dropped_by_confirm() -> None:
    gate = CommandGate(debounce_s=0.0, confirm=2)
    seq = [*ticks(0, 1, "hover"), (1.0, "land"), *ticks(1.25, 2, "hover")]
    assert run(gate, seq) == [(0.25, "hover")]


def test_same_command_again_only_after_release() -> None:
    gate = CommandGate(debounce_s=0.5, release_s=1.0)
    seq = (
        ticks(0, 2, "move_upward")
        + ticks(2, 2.5, "")  # a short dip: still the same performance
        + ticks(2.5, 4, "move_upward")
        + ticks(4, 5.5, "")  # gone for 1.5 s: released
        + ticks(5.5, 7, "move_upward")
    )
    assert run(gate, seq) == [(0.0, "move_upward"), (5.5, "move_upward")]


def test_repeat_while_held() -> None:
    gate = CommandGate(debounce_s=0.5, repeat_s=3.0)
    assert [t for t, _ in run(gate, ticks(0, 7, "move_ahead"))] == [0.0, 3.0, 6.0]


def test_refused_action_changes_nothing() -> None:
    gate = CommandGate(debounce_s=2.0)
    only_arm = lambda a: a == "have_command"  # noqa: E731
    seq = ticks(0, 1, "move_to_left") + ticks(1, 3, "have_command")
    # move_to_left is refused, so it starts no debounce: have_command fires at once.
    assert run(gate, seq, only_arm) == [(1.0, "have_command")]


def test_land_can_ask_for_a_longer_agreement_than_other_commands() -> None:
    gate = CommandGate(debounce_s=0.0, confirm=1, confirm_by_command={"land": 4})
    # land_direction's arms-down phase looks like land for three decisions: no command.
    seq = [*ticks(0, 1, "hover"), *ticks(1, 1.75, "land"), *ticks(1.75, 3, "hover")]
    assert run(gate, seq) == [(0.0, "hover")]
    # Held for the fourth decision, land fires then; hover still fires at once.
    gate = CommandGate(debounce_s=0.0, confirm=1, confirm_by_command={"land": 4})
    assert run(gate, ticks(0, 2, "land")) == [(0.75, "land")]
    with pytest.raises(ValueError, match="land must be >= 1"):
        CommandGate(confirm_by_command={"land": 0})
