"""`land` ends the flight, and `land_direction`'s recordings hold a pause with both hands
low in front, which is `land`'s pose: the default rule (24 nats and 5 agreeing
decisions, control/config.py) must command `land_direction` there and `land` only for
`land`, on the shipped model's replay of real clips from two views."""

from __future__ import annotations

from engine_helpers import commands, replay

from proxima.evaluation.stitch import stitch_views

PLAN = [("have_command", 5.0), ("land_direction", 8.0), ("have_command", 4.0), ("land", 6.0)]


def test_the_pause_in_land_direction_is_no_landing(laser_clips, classifier, tmp_path) -> None:
    streams = stitch_views(laser_clips, PLAN, views=("f", "r"), part="test", seed=0)
    for view, stream in streams.items():
        stream.write(tmp_path / f"{view}.csv")
        events = replay(tmp_path / f"{view}.csv", classifier)
        # the hover: the replay ends and the operator is lost
        assert commands(events) == [*(g for g, _ in PLAN), "hover"], view
        onset = next(seg.onset_t for seg in stream.segments if seg.gesture == "land")
        landed = next(e["t"] for e in events if e.get("command") == "land")
        assert onset < landed < onset + 6.0, (view, onset, landed)
