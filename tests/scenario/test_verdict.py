"""The verdict rules on timelines written out by hand: each rule fails when it should."""

from __future__ import annotations

import math
from typing import Any

from proxima.scenario.verdict import (
    Verdict,
    check_geometric_loss,
    collapse_rearms,
    commands_before_arming,
    expected_position,
    judge_paper_flight,
)

EXPECTED = [
    ("have_command", "main"),
    ("move_to_left", "main"),
    ("have_command", "secondary"),
    ("move_to_right", "secondary"),
    ("land", "secondary"),
]
LANDED = {
    "position_ned": [0.02, -0.01, 0.0],
    "altitude_m": 0.0,
    "landed": "on_ground",
    "armed": False,
}


def cmd(t: float, command: str, stream: str, drone: str = "main") -> dict[str, Any]:
    return {"t": t, "kind": "command", "command": command, "stream": stream, "drone": drone}


def ack(t: float, command: str, stream: str, status: str = "sent", reason: str = "") -> dict:
    return {"t": t, "kind": "ack", "command": command, "stream": stream, "status": status,
            "reason": reason, "drone": "main"}  # fmt: skip


def arming(t: float, armed: bool) -> dict[str, Any]:
    return {"t": t, "kind": "arming", "armed": armed, "reason": "", "stream": ""}


def handover(t: float, a: str, b: str, reason: str = "operator_partly_visible") -> dict:
    return {"t": t, "kind": "handover", "from_stream": a, "to_stream": b, "reason": reason}


def good_flight() -> list[dict[str, Any]]:
    return [
        handover(8.0, "", "main", "operator_acquired"),
        cmd(11.0, "have_command", "main"),
        arming(11.0, True),
        ack(11.0, "have_command", "main", "done"),
        cmd(15.8, "move_to_left", "main"),
        ack(15.8, "move_to_left", "main"),
        handover(17.3, "main", "secondary"),
        arming(17.3, False),
        cmd(23.1, "have_command", "secondary"),
        arming(23.1, True),
        ack(23.1, "have_command", "secondary", "done"),
        cmd(29.5, "move_to_right", "secondary"),
        ack(29.5, "move_to_right", "secondary"),
        cmd(33.6, "land", "secondary"),
        ack(33.6, "land", "secondary"),
        {"t": 37.9, "kind": "outcome", "command": "land", "outcome": "landed", "stream": ""},
        handover(38.0, "secondary", "", "stream_ended"),
        cmd(38.0, "hover", ""),
        ack(38.0, "hover", "", "ignored", "on the ground: nothing to hold"),
    ]


def test_the_paper_flight_passes() -> None:
    v = judge_paper_flight(good_flight(), LANDED, (0.0, 0.0), EXPECTED)
    assert v.passed, v.reasons
    assert any(r.startswith("exactly one handover: main->secondary") for r in v.reasons)


def test_a_second_handover_fails() -> None:
    timeline = good_flight()
    timeline.insert(12, handover(30.5, "secondary", "main", "higher_priority_sees_operator"))
    v = judge_paper_flight(timeline, LANDED, (0.0, 0.0), EXPECTED)
    assert not v.passed
    assert any("expected exactly one handover main->secondary, got 2" in r for r in v.reasons)


def test_a_command_before_arming_fails() -> None:
    timeline = [cmd(5.0, "move_to_left", "main"), *good_flight()]
    v = judge_paper_flight(timeline, LANDED, (0.0, 0.0), EXPECTED)
    assert not v.passed
    assert any(r.startswith("FAILED: commands before arming") for r in v.reasons)
    assert commands_before_arming(timeline) == [timeline[0]]


def test_a_wrong_command_fails() -> None:
    timeline = good_flight()
    timeline[13] = cmd(33.6, "move_ahead", "secondary")
    v = judge_paper_flight(timeline, LANDED, (0.0, 0.0), EXPECTED)
    assert not v.passed
    assert any("expected exactly have_command@main" in r for r in v.reasons)


def test_a_command_the_operator_did_not_perform_fails() -> None:
    truth = {
        "main": [{"gesture": "have_command", "transition_t": 9.5, "end_t": 14.5}],
        "secondary": [{"gesture": "hover", "transition_t": 0.0, "end_t": 40.0}],
    }
    v = judge_paper_flight(good_flight(), LANDED, (0.0, 0.0), EXPECTED, truth=truth)
    assert not v.passed
    bad = next(r for r in v.reasons if "did not perform" in r)
    assert "move_to_left@main t=15.8" in bad and "land@secondary t=33.6" in bad


def test_landing_elsewhere_or_a_safety_hover_in_flight_fails() -> None:
    far = {**LANDED, "position_ned": [0.0, -1.0, 0.0]}
    v = judge_paper_flight(good_flight(), far, (0.0, 0.0), EXPECTED)
    assert not v.passed and v.reasons[0].startswith("FAILED: main at N +0.00 E -1.00")
    timeline = good_flight()
    timeline.insert(9, cmd(20.0, "hover", ""))
    v = judge_paper_flight(timeline, LANDED, (0.0, 0.0), EXPECTED)
    assert any("hovered the drone in flight" in r for r in v.reasons) and not v.passed


def test_a_repeated_have_command_is_noted_not_counted() -> None:
    timeline = good_flight()
    timeline.insert(11, cmd(27.3, "have_command", "secondary"))
    timeline.insert(12, ack(27.3, "have_command", "secondary", "done"))
    kept, repeats = collapse_rearms([e for e in timeline if e["kind"] == "command" and e["stream"]])
    assert [r["t"] for r in repeats] == [27.3] and len(kept) == 5
    v = judge_paper_flight(timeline, LANDED, (0.0, 0.0), EXPECTED)
    assert v.passed, v.reasons
    assert any("have_command repeated at t=27.3 s" in r for r in v.reasons)


def test_expected_position_follows_the_mapping_and_heading() -> None:
    assert expected_position((0, 0, -2), 0.0, ["move_to_left", "move_upward"]) == (0, -1, -3)
    n, e, d = expected_position((0, 0, -2), math.pi / 2, ["move_ahead", "hover"])  # east
    assert abs(n) < 1e-9 and abs(e - 1) < 1e-9 and d == -2


def view(t: float, stream: str, framed: bool, height: float) -> dict[str, Any]:
    return {"t": t, "kind": "view", "stream": stream, "framed": framed,
            "camera_height_m": height}  # fmt: skip


def geometric_flight() -> list[dict[str, Any]]:
    return [
        view(0.0, "main", True, 2.5),
        view(0.0, "secondary", True, 2.5),
        cmd(18.8, "move_upward", "main"),
        view(19.5, "main", False, 2.99),
        handover(20.5, "main", "secondary"),
    ]


def _geometric(timeline: list[dict[str, Any]]) -> Verdict:
    v = Verdict()
    check_geometric_loss(v, timeline, "main", "secondary", "move_upward", 2.5, rise_m=0.3)
    return v


def test_the_feet_lost_by_the_climb_pass() -> None:
    v = _geometric(geometric_flight())
    assert v.passed, v.reasons
    assert "lost the feet at t=19.5 s with the camera 2.99 m up" in v.reasons[0]


def test_a_loss_before_the_move_or_without_a_climb_fails() -> None:
    early = geometric_flight()
    early.insert(2, view(10.0, "main", False, 2.5))
    assert not _geometric(early).passed
    low = geometric_flight()
    low[3] = view(19.5, "main", False, 2.6)  # lost, but the camera had not climbed
    assert not _geometric(low).passed
    late = geometric_flight()
    late[3] = view(21.0, "main", False, 3.0)  # after the handover: not what caused it
    assert not _geometric(late).passed
    blind = geometric_flight()
    blind[1] = view(0.0, "secondary", False, 2.5)  # the secondary did not see the feet
    v = _geometric(blind)
    assert not v.passed and "did not frame the operator" in v.reasons[-1]
    assert not _geometric([e for e in geometric_flight() if e["kind"] != "handover"]).passed
