"""The engine's per-frame call, end to end: a video file of a real photo through
file: ingest, MediaPipe and the tracker; and a replay stream that never loads MediaPipe."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from proxima.ingest import open_source
from proxima.pose import OperatorPoser, operator_visible

skimage_data = pytest.importorskip("skimage.data")

LASER = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "laser-uav-gesture"


@pytest.mark.slow
def test_video_file_through_pose_and_tracker(tmp_path: Path) -> None:
    photo = np.ascontiguousarray(skimage_data.astronaut()[:, :, ::-1])
    video = tmp_path / "astronaut.mp4"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), 15, (640, 480))
    for k in range(15):  # the photo drifting right on a 640x480 canvas
        canvas = np.full((480, 640, 3), 30, np.uint8)
        canvas[:, 4 * k : 4 * k + 512] = photo[16:496]
        writer.write(canvas)
    writer.release()
    xs = []
    with open_source(f"file:{video}", realtime=False) as src, OperatorPoser() as poser:
        for frame in src:
            pose = poser(frame)
            assert pose is not None and pose.image_size == (640, 480)
            assert pose.t == frame.t
            xs.append(float(pose.xyz[0, 0]))  # the nose
    assert len(xs) == 15
    assert xs[-1] - xs[0] == pytest.approx(56 / 640, abs=0.03)  # follows the drift


def test_replay_stream_skips_the_estimator() -> None:
    clip = LASER / "DJI_0149_hover_f.MP4.csv"
    with open_source(f"replay:{clip}", realtime=False) as src, OperatorPoser() as poser:
        poses = [poser(frame) for frame in src]
        assert poser._estimator is None  # no MediaPipe for landmark streams
    assert all(p is not None and operator_visible(p) for p in poses)
