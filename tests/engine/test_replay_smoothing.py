"""Replayed landmark streams pass the same One Euro filter as camera streams and training
windows (`EngineSettings.smooth_replays`, `proxima.pose.LIVE_ONE_EURO`), on a real clip."""

from __future__ import annotations

import numpy as np

from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.stream import StreamPipeline
from proxima.events import PoseEvent
from proxima.ingest.landmark_csv import LandmarkTrack
from proxima.ingest.replay import ReplaySource
from proxima.pose import OperatorTracker
from proxima.pose.one_euro import LIVE_ONE_EURO, one_euro_windows


def poses(clip, classifier, settings: EngineSettings) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The landmarks of every PoseEvent of a replay of `clip` through the pipeline."""
    track = LandmarkTrack("clip", clip.frames.astype(np.int64), clip.xyz, clip.visibility)
    got: list[PoseEvent] = []
    spec = StreamSpec(name="r", uri="replay:clip")
    pipeline = StreamPipeline(
        spec, classifier, lambda e: got.append(e) if isinstance(e, PoseEvent) else None,
        settings=settings,
    )  # fmt: skip
    with ReplaySource("replay:clip", track, 30.0, realtime=False) as source:
        for frame in source:
            pipeline.process(frame)
    return np.asarray([e.xyz for e in got])


def test_replays_are_smoothed_as_cameras_are(laser_clips, classifier) -> None:
    clip = next(c for c in laser_clips if c.name == "DJI_0149_hover_f").slice(0, 150)
    smoothed = poses(clip, classifier, EngineSettings())
    t = (clip.frames - clip.frames[0]) / 30.0
    want = one_euro_windows(clip.xyz[None], t[None], LIVE_ONE_EURO)[0]
    assert np.abs(smoothed - want).max() < 1e-4  # PoseEvents round to 4 decimals
    raw = poses(clip, classifier, EngineSettings(smooth_replays=False))
    assert np.abs(raw - clip.xyz).max() < 1e-4
    assert np.abs(smoothed - raw).max() > 1e-3  # the filter did something
    # the camera path's tracker uses the same setting
    tracker = OperatorTracker()
    f = tracker._filter
    assert f is not None
    assert (f.min_cutoff, f.beta, f.d_cutoff) == (
        LIVE_ONE_EURO.min_cutoff,
        LIVE_ONE_EURO.beta,
        LIVE_ONE_EURO.d_cutoff,
    )
