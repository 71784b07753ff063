from __future__ import annotations

import numpy as np
import pytest

from proxima.gesture.clip import DataError
from proxima.gesture.windows import make_windows, split_clips, window_starts


def test_windows_never_span_a_long_gap() -> None:
    frames = np.r_[np.arange(1, 101), np.arange(121, 221)]  # 20 frames missing after 100
    starts, skipped = window_starts(frames, 60, 1, max_gap=5)
    assert skipped == 59  # every window that would bridge rows 99 -> 100
    assert all(not (s <= 99 < s + 59) for s in starts)
    starts, skipped = window_starts(frames, 60, 1, max_gap=20)
    assert skipped == 0


def test_gapped_clip_reports_skipped_windows(laser_clips) -> None:
    clip = next(c for c in laser_clips if c.name == "DJI_0171_move_upward_r")
    w = make_windows([clip], stride=1, max_gap=5)
    assert w.skipped > 0 and len(w) + w.skipped == len(clip) - 59
    assert w.xyz.shape[1:] == (60, 33, 3)


def test_temporal_split_keeps_a_window_gap(laser_clips) -> None:
    parts = split_clips(laser_clips, "temporal")
    for tr, te in zip(parts.train, parts.test, strict=True):
        assert tr.name == te.name
        assert te.frames[0] - tr.frames[-1] >= 60  # no window can touch both sides
        total = len(tr) + len(te) + 60
        assert abs(len(te) / total - 0.3) < 0.01


@pytest.mark.parametrize("view", ["f", "l", "r"])
def test_cross_view_tests_only_the_unseen_view(laser_clips, view) -> None:
    parts = split_clips(laser_clips, f"cross-view:{view}")
    assert {c.view for c in parts.test} == {view}
    assert view not in {c.view for c in parts.train}
    assert len(parts.test) == 13


def test_unknown_split_is_an_error(laser_clips) -> None:
    with pytest.raises(DataError, match="unknown split"):
        split_clips(laser_clips, "random")
    with pytest.raises(DataError, match="needs UAV-Gesture"):
        split_clips(laser_clips, "uav-gesture:1")
