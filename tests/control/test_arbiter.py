"""The priority arbiter on explicit sequences of how each stream sees the operator."""

import pytest

from proxima.control import PriorityArbiter, Sight

FULL, PARTIAL, NONE = Sight.FULL, Sight.PARTIAL, Sight.NONE


def feed(arb: PriorityArbiter, frames: list[tuple[float, dict[str, Sight]]]) -> list:
    out = []
    for t, sights in frames:
        for stream in arb.ranking:
            if stream in sights:
                h = arb.observe(stream, t, sights[stream])
                if h is not None:
                    out.append((round(h.t, 6), h.from_stream, h.to_stream, h.reason))
    return out


def steps(start: float, stop: float, sights: dict[str, Sight], dt: float = 0.1) -> list:
    return [(round(start + i * dt, 6), sights) for i in range(round((stop - start) / dt))]


def test_main_loses_the_feet_secondary_takes_over_then_main_again() -> None:
    arb = PriorityArbiter(["main", "side"], hold_s=1.0, regain_s=0.5)
    both = {"main": FULL, "side": FULL}
    frames = (
        steps(0, 3, both)
        + steps(3, 6, {"main": PARTIAL, "side": FULL})  # main's view cuts the feet
        + steps(6, 8, both)
    )
    assert feed(arb, frames) == [
        (0.5, "", "main", "operator_acquired"),  # after regain_s of seeing the operator
        (4.0, "main", "side", "operator_partly_visible"),  # FULL last at 2.9, hold 1.0
        (6.5, "side", "main", "higher_priority_sees_operator"),
    ]


def test_short_loss_within_hold_is_no_handover() -> None:
    arb = PriorityArbiter(["main", "side"], hold_s=1.0, regain_s=0.0)
    both = {"main": FULL, "side": FULL}
    frames = steps(0, 2, both) + steps(2, 2.8, {"main": NONE, "side": FULL}) + steps(2.8, 4, both)
    assert [h[1:3] for h in feed(arb, frames)] == [("", "main")]


def test_a_single_camera_that_cuts_the_feet_keeps_driving() -> None:
    arb = PriorityArbiter(["main"], hold_s=0.5, regain_s=0.0)
    frames = steps(0, 1, {"main": FULL}) + steps(1, 5, {"main": PARTIAL})
    assert [h[1:3] for h in feed(arb, frames)] == [("", "main")]


def test_partial_main_beats_partial_secondary() -> None:
    arb = PriorityArbiter(["main", "side"], hold_s=0.5, regain_s=0.0)
    frames = steps(0, 2, {"main": NONE, "side": PARTIAL}) + steps(
        2, 3, {"main": PARTIAL, "side": PARTIAL}
    )
    assert feed(arb, frames) == [
        (0.0, "", "side", "operator_acquired"),
        (2.0, "side", "main", "higher_priority_sees_operator"),
    ]


def test_nobody_sees_the_operator() -> None:
    arb = PriorityArbiter(["main", "side"], hold_s=0.5, regain_s=0.0)
    frames = steps(0, 1, {"main": FULL, "side": NONE}) + steps(1, 2, {"main": NONE, "side": NONE})
    assert feed(arb, frames) == [
        (0.0, "", "main", "operator_acquired"),
        (1.5, "main", "", "operator_lost"),  # last seen 0.9, hold 0.5
    ]


def test_ended_stream_hands_over_at_once() -> None:
    arb = PriorityArbiter(["main", "side"], hold_s=1.0, regain_s=0.0)
    feed(arb, steps(0, 1, {"main": FULL, "side": FULL}))
    h = arb.end("main", 1.0)
    assert h is not None and (h.to_stream, h.reason) == ("side", "stream_ended")


def test_unknown_stream_is_an_error() -> None:
    arb = PriorityArbiter(["main"])
    with pytest.raises(ValueError, match="unknown stream 'x'"):
        arb.observe("x", 0.0, FULL)
