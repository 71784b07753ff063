"""Training clips lose the operator's opening rest (gesture/idle.py), on real LASER clips."""

from __future__ import annotations

from proxima.gesture.idle import STATIC_GESTURES, still_prefix, trim_idle


def test_a_moving_gesture_keeps_half_a_window_of_its_opening_rest(laser_clips) -> None:
    clip = next(c for c in laser_clips if c.name == "DJI_0173_slow_down_f")
    rest = still_prefix(clip.xyz)
    assert rest >= 45  # the operator stands still for 1.5 s before slowing down
    trimmed = trim_idle(clip, 30)
    assert len(clip) - len(trimmed) == rest - 15
    assert still_prefix(trimmed.xyz) == 15  # no 30-frame window of rest is left
    assert (trimmed.xyz == clip.xyz[rest - 15 :]).all() and trimmed.gesture == clip.gesture
    assert len(clip) - len(trim_idle(clip, 60)) == rest - 30


def test_static_signals_and_clips_that_move_at_once_are_kept_whole(laser_clips) -> None:
    for clip in laser_clips:
        if clip.gesture in STATIC_GESTURES or still_prefix(clip.xyz) <= 15:
            assert trim_idle(clip, 30) is clip, clip.name
    hover = next(c for c in laser_clips if c.name == "DJI_0149_hover_f")
    assert still_prefix(hover.xyz) >= 100 and trim_idle(hover, 30) is hover
