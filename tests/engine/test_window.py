"""The sliding pose window: stride and restarts at gaps, on real dataset poses."""

import pytest

from proxima.engine import PoseWindow
from proxima.engine.config import EngineSettings
from proxima.gesture.capture import MAX_GAP_S
from proxima.types import Pose


def poses(clip, rows, fps=30.0):
    return [
        Pose(t=(int(clip.frames[r]) - 1) / fps, xyz=clip.xyz[r], visibility=clip.visibility[r])
        for r in rows
    ]


def test_classifies_every_stride_once_full(laser_clips) -> None:
    clip = laser_clips[0]
    w = PoseWindow(size=60, stride=5)
    due = []
    for i, p in enumerate(poses(clip, range(80))):
        w.push(p)
        if w.due():
            xyz, vis = w.take()
            assert xyz.shape == (1, 60, 33, 3) and vis.shape == (1, 60, 33)
            due.append(i)
    assert due == [59, 64, 69, 74, 79]


def test_a_gap_restarts_the_window(laser_clips) -> None:
    # DJI_0171 (move_upward, right view) loses the person for 14 frames at some point.
    clip = next(c for c in laser_clips if c.name == "DJI_0171_move_upward_r")
    gaps = (clip.frames[1:] - clip.frames[:-1]) - 1
    r = int((gaps > 7).nonzero()[0][0]) + 1  # first row after a gap of more than 0.25 s
    w = PoseWindow(size=60, stride=5, max_gap_s=0.25)
    restarted = [w.push(p) for p in poses(clip, range(r - 70, r + 1))]
    assert restarted[-1] and not any(restarted[:-1])
    assert len(w) == 1 and not w.due()


def test_the_engine_bridges_a_moment_without_the_operator(laser_clips) -> None:
    # The same 14-frame (0.47 s) loss: by default the window holds the poses on both
    # sides and classification goes on at the stride, as a field camera needs.
    clip = next(c for c in laser_clips if c.name == "DJI_0171_move_upward_r")
    gaps = (clip.frames[1:] - clip.frames[:-1]) - 1
    r = int((gaps > 7).nonzero()[0][0]) + 1
    assert EngineSettings().max_gap_s == MAX_GAP_S == PoseWindow().max_gap_s
    assert (clip.frames[r] - clip.frames[r - 1]) / 30 < MAX_GAP_S
    w = PoseWindow(size=30, stride=5)
    due = []
    for i, p in enumerate(poses(clip, range(r - 40, r + 6))):
        assert not w.push(p)
        if w.due():
            w.take()
            due.append(i)
    assert due == [29, 34, 39, 44] and w.restarts == 0
    # while it holds a pause longer than training windows do, its readings count less
    assert w.bridged() and w.longest_pause_s() > 0.45
    for q in poses(clip, range(r + 6, r + 36)):
        w.push(q)
    assert not w.bridged()
    # a pause longer than MAX_GAP_S still restarts it
    later = Pose(t=q.t + MAX_GAP_S + 0.05, xyz=q.xyz, visibility=q.visibility)
    assert w.push(later) and len(w) == 1


def test_the_time_clock_gives_the_pose_clocks_windows_at_30_fps(laser_clips) -> None:
    clip = laser_clips[0]
    by_pose, by_time = PoseWindow(30, 5), PoseWindow(30, 5, clock="time")
    taken = 0
    for p in poses(clip, range(90)):
        by_pose.push(p)
        by_time.push(p)
        assert by_pose.due() == by_time.due()
        if by_pose.due():
            a, b = by_pose.take(), by_time.take()
            assert abs(a[0] - b[0]).max() < 1e-6 and abs(a[1] - b[1]).max() < 1e-6
            taken += 1
    assert taken == 13


def test_the_time_clock_keeps_the_span_of_a_slower_camera(laser_clips) -> None:
    # Every other pose of a 30 fps recording, as a 15 fps camera delivers it: the window
    # fills after 1 s (16 poses) instead of 2 s, and the poses it holds at the recorded
    # instants are the recording's own, the ones between them interpolated.
    clip = laser_clips[0]
    rows = range(0, 120, 2)
    w = PoseWindow(30, 5, clock="time")
    due = []
    for i, p in enumerate(poses(clip, rows)):
        w.push(p)
        if not w.due():
            continue
        xyz, vis = w.take()
        if not due:
            newest = rows[i]
            assert xyz.shape == (1, 30, 33, 3) and vis.shape == (1, 30, 33)
            assert abs(xyz[0, -1] - clip.xyz[newest]).max() < 1e-6
            assert abs(xyz[0, 1] - clip.xyz[newest - 28]).max() < 1e-6
            mid = (clip.xyz[newest - 2] + clip.xyz[newest]) / 2
            assert abs(xyz[0, -2] - mid).max() < 1e-6
        due.append(i)
    # full after 1 s (16 poses), then due every 5 / 30 s of stream time: every third
    # pose at 15 fps (0.2 s)
    assert due[:4] == [15, 18, 21, 24]


def test_the_engine_times_windows_as_the_model_trained(shipped_member, tmp_path) -> None:
    # A copy of a shipped member whose training windows were resampled to 30 per
    # second (`proxima train --window-clock time`); the file round trip is the real one.
    import torch

    from proxima.engine.config import EngineSettings, StreamSpec
    from proxima.engine.stream import StreamPipeline
    from proxima.engine.window import engine_clock
    from proxima.gesture.classifier import GestureClassifier

    blob = torch.load(shipped_member, map_location="cpu", weights_only=True)
    blob["metadata"].setdefault("train_config", {})["window_clock"] = "time"
    timed = tmp_path / "timed.pt"
    torch.save(blob, timed)
    shipped, resampled = GestureClassifier.load(shipped_member), GestureClassifier.load(timed)
    assert (shipped.window_clock, resampled.window_clock) == ("poses", "time")
    spec = StreamSpec(name="a", uri="replay:x")

    def clock(clf: GestureClassifier, settings: EngineSettings) -> str:
        return StreamPipeline(spec, clf, lambda e: None, settings=settings).window.clock

    assert clock(shipped, EngineSettings()) == "poses"
    assert clock(resampled, EngineSettings()) == "time"
    assert clock(resampled, EngineSettings(window_clock="poses")) == "poses"
    assert clock(shipped, EngineSettings(window_clock="time")) == "time"
    clocks = [engine_clock(s, "time") for s in ("model", "poses", "time")]
    assert clocks == ["time", "poses", "time"]
    with pytest.raises(ValueError, match="sundial"):
        engine_clock("sundial", "poses")
    # a swap to a model of the other clock brings its window
    pipeline = StreamPipeline(spec, shipped, lambda e: None)
    pipeline.swap_classifier(resampled)
    pipeline._apply_swap(0.0)
    assert pipeline.window.clock == "time"


def test_the_benchmarks_timed_windows_are_the_engines(laser_clips) -> None:
    # `live_windows(clock="time")` (what `proxima robustness` scores) cuts a captured
    # recording exactly as the engine's time-clock window does, gaps and drops included.
    import numpy as np

    from proxima.gesture.capture import CaptureModel, live_windows

    clip = next(c for c in laser_clips if c.name == "DJI_0171_move_upward_r")
    model = CaptureModel(fps=(14.0, 14.0), drop_rate=0.1, gap_rate_hz=0.3, gap_s=(0.3, 0.6))
    cap = model.apply_clip(clip, np.random.default_rng(3))
    xyz, vis, end = live_windows(cap, size=30, stride=5, clock="time")
    w = PoseWindow(30, 5, clock="time")
    got_t, got_x, got_v = [], [], []
    for t, x, v in zip(cap.t, cap.xyz, cap.visibility, strict=True):
        w.push(Pose(t=float(t), xyz=x, visibility=v))
        if w.due():
            a, b = w.take()
            got_t.append(t)
            got_x.append(a[0])
            got_v.append(b[0])
    assert w.restarts >= 2 and len(end) > 20
    np.testing.assert_allclose(end, got_t)
    np.testing.assert_allclose(xyz, np.stack(got_x), atol=1e-6)
    np.testing.assert_allclose(vis, np.stack(got_v), atol=1e-6)
