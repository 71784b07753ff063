"""The sliding pose window: stride and restarts at gaps, on real dataset poses."""

from proxima.engine import PoseWindow
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
