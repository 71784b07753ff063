"""file:PATH over a real video written in the test with cv2.VideoWriter, and files that
are not videos."""

from __future__ import annotations

import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from proxima.ingest import SourceError, StateChange, open_source
from proxima.types import StreamState

FPS = 10
N = 20


@pytest.fixture(scope="module")
def video(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """20 frames, 320x240 at 10 fps; frame k has a white square at x = 10 * k."""
    path = tmp_path_factory.mktemp("video") / "squares.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), FPS, (320, 240))
    assert writer.isOpened()
    for k in range(N):
        img = np.zeros((240, 320, 3), np.uint8)
        img[100:140, 10 * k : 10 * k + 40] = 255
        writer.write(img)
    writer.release()
    return path


def test_file_source_yields_every_frame_with_stream_time(video: Path) -> None:
    changes: list[StateChange] = []
    with open_source(f"file:{video}", realtime=False, on_state=changes.append) as src:
        frames = list(src)
    assert [f.index for f in frames] == list(range(N))
    assert [f.t for f in frames] == pytest.approx([k / FPS for k in range(N)])
    for k, frame in enumerate(frames):
        assert frame.pose is None and frame.image is not None
        assert frame.image.shape == (240, 320, 3) and frame.image.dtype == np.uint8
        column_profile = frame.image[120, :, 0].astype(int)
        bright = np.flatnonzero(column_profile > 128)
        assert abs(bright.min() - 10 * k) <= 3 and abs(bright.max() - (10 * k + 39)) <= 3
    assert [c.state for c in changes] == [StreamState.LIVE, StreamState.ENDED]


def test_file_source_realtime_runs_at_the_file_rate(video: Path) -> None:
    start = time.monotonic()
    n = len(list(open_source(f"file:{video}")))
    assert n == N
    assert time.monotonic() - start >= (N - 1) / FPS - 0.05


def test_close_mid_stream_releases_and_ends(video: Path) -> None:
    src = open_source(f"file:{video}", realtime=False)
    it = iter(src)
    next(it)
    src.close()
    assert list(it) == []
    assert src.state is StreamState.ENDED


def test_not_a_video_is_a_clear_error(tmp_path: Path) -> None:
    text = tmp_path / "notes.mp4"
    text.write_text("this is not a video\n" * 50)
    with pytest.raises(SourceError, match=f"{text} is not a video"):
        open_source(f"file:{text}")
    csv_file = tmp_path / "landmarks.csv"
    csv_file.write_text(",counter_frame,i,x,y,z,visibility\n")
    with pytest.raises(SourceError, match="not a video"):
        open_source(f"file:{csv_file}")
    with pytest.raises(SourceError, match="no such file"):
        open_source(f"file:{tmp_path / 'missing.mp4'}")


def test_missing_webcam_is_a_clear_error() -> None:
    with pytest.raises(SourceError, match="cannot open camera 57"):
        open_source("webcam:57")
