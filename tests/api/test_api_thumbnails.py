"""JPEG thumbnails of camera frames: real photo in, small JPEG out, at a modest rate."""

from __future__ import annotations

import base64
import time

import cv2
import numpy as np
from matplotlib import cbook

from proxima.api.thumbnails import ThumbnailTap
from proxima.events import EventBus
from proxima.types import Frame


def _photo() -> np.ndarray:
    path = cbook.get_sample_data("grace_hopper.jpg", asfileobj=False)
    image = cv2.imread(str(path))
    assert image is not None
    return image


def test_thumbnail_is_a_small_jpeg_of_the_frame() -> None:
    bus = EventBus()
    image = _photo()
    tap = ThumbnailTap(bus, "cam", hz=1000.0, width=160)
    with bus.subscribe(types=["thumbnail"]) as sub:
        assert tap.offer(Frame(t=0.5, index=0, image=image))
        event = sub.get(timeout=1)
    assert event is not None and event.stream == "cam" and event.t == 0.5
    jpeg = base64.b64decode(event.jpeg_b64)
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    h, w = image.shape[:2]
    assert decoded.shape == (round(h * 160 / w), 160, 3) == (event.height, event.width, 3)
    # It is the same picture, shrunk: compare with a plain resize.
    small = cv2.resize(image, (160, decoded.shape[0]), interpolation=cv2.INTER_AREA)
    assert np.abs(decoded.astype(int) - small.astype(int)).mean() < 8
    assert len(jpeg) < 20_000


def test_rate_limit_and_replayed_frames() -> None:
    bus = EventBus()
    tap = ThumbnailTap(bus, "cam", hz=5.0)
    image = _photo()
    sent = 0
    end = time.monotonic() + 1.0
    while time.monotonic() < end:
        sent += tap.offer(Frame(t=0.0, index=0, image=image))
        time.sleep(0.005)
    assert 4 <= sent <= 6
    # A replayed frame has no pixels: no thumbnail.
    assert not ThumbnailTap(bus, "replay").offer(Frame(t=0.0, index=0, image=None))


def test_camera_stream_thumbnails_from_the_live_engine(tmp_path, checkpoint_path) -> None:  # type: ignore[no-untyped-def]
    """A `file:` video stream through the real engine (MediaPipe pose) yields thumbnails
    of its frames; the replayed stream beside it yields none."""
    from api_helpers import laser_clip

    from proxima.api.runtime import build_runtime
    from proxima.settings import Settings

    photo = _photo()
    video = tmp_path / "operator.mp4"
    writer = cv2.VideoWriter(
        str(video), cv2.VideoWriter_fourcc(*"mp4v"), 15.0, (photo.shape[1], photo.shape[0])
    )
    for _ in range(45):
        writer.write(photo)
    writer.release()
    settings = Settings.load(
        config=None,
        streams=[
            {"name": "cam", "uri": f"file:{video}", "drone": "main"},
            {
                "name": "replay",
                "uri": f"replay:{laser_clip('hover_f')}@30",
                "drone": "main",
                "priority": 1,
            },
        ],
        engine={"checkpoint": str(checkpoint_path), "stride": 4},
        recognition={"release_s": 3.0},
        server={"db_path": str(tmp_path / "c.db"), "thumbnail_hz": 4.0},
    )
    bus = EventBus()
    with bus.subscribe(types=["thumbnail"]) as sub:
        runtime = build_runtime(settings, bus=bus, engine=True, drones=False, view=False)
        try:
            assert runtime.engine is not None, runtime.notes
            # The [engine] and [recognition] sections are what the engine runs with.
            assert runtime.engine.settings is settings.engine
            assert runtime.engine.control is settings.recognition
            assert runtime.engine.pipelines["cam"].window.stride == 4
            first = sub.get(timeout=30)
            time.sleep(1.0)
            events = [first, *sub.drain()]
        finally:
            runtime.close()
    assert first is not None, "no thumbnail from the camera stream"
    assert {e.stream for e in events} == {"cam"}
    assert 1 <= len(events) <= 4 * 4  # a modest rate, never every frame
    jpeg = base64.b64decode(events[0].jpeg_b64)
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape[1] == 320
