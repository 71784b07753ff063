"""The two replays of a stitched stream (proxima.evaluation.replay) on real clips: the
fast offline replay decides exactly as the real engine, at the default settings and at
other ones, when the operator is lost and when frames are missing."""

from pathlib import Path

import numpy as np
import pytest

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings
from proxima.evaluation.latency import build_streams
from proxima.evaluation.replay import (
    MemoClassifier,
    Run,
    decide,
    engine_run,
    recognize,
    replay_source,
)
from proxima.evaluation.stitch import Blank, apply_blank
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint
from proxima.ingest import read_landmark_csv

SHIPPED = Path(__file__).resolve().parents[2] / "models" / "gesture-default.pt"


@pytest.fixture(scope="module")
def shipped() -> GestureClassifier | EnsembleClassifier:
    return load_checkpoint(SHIPPED)


@pytest.fixture(scope="module")
def lost_stream(laser_clips):
    """A held-out stream where the operator is unseen for 1.5 s (every landmark
    invisible) and then gone for 2 s (no frames at all)."""
    (stream,) = build_streams(laser_clips, [5], 10, "test", 3.0, 4.0)
    t = (stream.frames - 1) / stream.fps
    stream.visibility[(t >= 12.0) & (t < 13.5)] = 0.0
    apply_blank(stream, Blank(24.0, 26.0, "drop"))
    return stream


def decisions(run: Run) -> tuple[list[tuple], list[tuple]]:
    commands = [(round(c["t"], 3), c["command"], c["stream"]) for c in run.commands]
    return commands, [(round(t, 3), a) for t, a in run.arming]


def test_the_offline_replay_decides_as_the_engine_when_the_operator_is_lost(
    lost_stream, shipped
) -> None:
    control = ControlSettings()
    offline = decide(recognize(lost_stream, shipped, EngineSettings(), control), control)
    engine = engine_run(lost_stream, control, EngineSettings(), shipped)
    assert decisions(offline) == decisions(engine)
    assert sum(c["stream"] == "" for c in engine.commands) >= 2  # the losses hovered
    assert offline.score(lost_stream).summary() == engine.score(lost_stream).summary()


def test_a_moment_without_the_operator_is_bridged_and_its_windows_count_half(
    laser_clips, shipped
) -> None:
    # 0.47 s without frames (a field camera losing the operator): the window goes on
    # across the pause, and the windows that hold it are flagged for the evidence rule.
    (stream,) = build_streams(laser_clips, [7], 8, "test", 3.0, 4.0)
    apply_blank(stream, Blank(10.0, 10.45, "drop"))
    control = ControlSettings()
    rec = recognize(stream, shipped, EngineSettings(), control)
    assert rec.bridged is not None and int(rec.new_window.sum()) == 1  # no restart
    t = np.array([rec.updates[i].t for i in rec.classified])
    assert rec.bridged.any() and np.all((t[rec.bridged] > 10.4) & (t[rec.bridged] < 11.5))
    engine = engine_run(stream, control, EngineSettings(), shipped)
    assert decisions(decide(rec, control)) == decisions(engine)


@pytest.mark.parametrize(
    ("stride", "params"),
    [
        pytest.param(
            3, {"threshold": 0.75, "confirm": 1, "debounce_s": 1.0}, marks=pytest.mark.slow
        ),
        (5, {"threshold": 0.0, "confirm": 1, "debounce_s": 10.0}),  # the paper's filter
        pytest.param(
            3,
            {"confirm": 3, "confirm_by_command": {"land": 12}, "release_s": 1.0},
            marks=pytest.mark.slow,
        ),
    ],
)
def test_the_offline_replay_decides_as_the_engine_at_other_settings(
    laser_clips, shipped, stride, params
) -> None:
    (stream,) = build_streams(laser_clips, [1001], 12, "test", 3.0, 6.0)  # left view
    control = ControlSettings().model_copy(update=params)
    settings = EngineSettings(stride=stride)
    offline = decide(recognize(stream, shipped, settings, control), control)
    engine = engine_run(stream, control, settings, shipped)
    assert decisions(offline) == decisions(engine)
    assert offline.commands, "the shipped model commands some of a held-out stream"


def test_one_recognition_serves_every_decision_setting_but_not_another_hand(
    lost_stream, shipped
) -> None:
    rec = recognize(lost_stream, shipped, EngineSettings(), ControlSettings())
    # The gap that dropped 2 s of frames restarted the window: a new stretch began.
    assert int(rec.new_window.sum()) == 2 and bool(rec.new_window[0])
    assert len(rec.updates) == len(lost_stream.frames)
    assert rec.probs.shape == (len(rec.classified), len(shipped.labels))
    with pytest.raises(ValueError, match="hand"):
        decide(rec, ControlSettings(thumb_hand="off"))


def test_the_replay_source_gives_the_frames_the_engine_reads_back(lost_stream, tmp_path) -> None:
    lost_stream.write(tmp_path / "s.csv")
    track = read_landmark_csv(tmp_path / "s.csv")
    with replay_source(lost_stream) as source:
        frames = list(source)
    assert [f.index + 1 for f in frames] == track.frames.tolist()
    assert np.array_equal(np.stack([f.pose.xyz for f in frames]), track.xyz)
    assert np.array_equal(np.stack([f.pose.visibility for f in frames]), track.visibility)


def test_the_memo_classifier_answers_as_the_classifier_and_remembers(laser_clips, shipped) -> None:
    clip = laser_clips[0]
    w = shipped.window
    xyz = clip.xyz[None, :w]
    memo = MemoClassifier(shipped)
    first = memo.predict(xyz, aspect=16 / 9)
    np.testing.assert_array_equal(first, shipped.predict(xyz, aspect=16 / 9))
    assert memo.predict(xyz.copy(), aspect=16 / 9) is first and len(memo) == 1
    memo.predict(clip.xyz[None, 1 : w + 1], aspect=16 / 9)
    assert len(memo) == 2
