"""A field session is replayable: `proxima recognize --record DIR` writes the operator's
poses as a replay CSV (with the events and session.json beside it), and replaying the
recording gives the same gestures and commands. The stream is a held-out stitched one
under the field capture condition (a drawn frame rate below 30 fps)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.cli import app
from proxima.engine.record import PoseRecorder
from proxima.evaluation.latency import build_streams
from proxima.evaluation.robustness import capture_rng, captured_stream
from proxima.gesture.capture import condition
from proxima.ingest import read_landmark_csv
from proxima.types import Pose

SHIPPED = Path(__file__).resolve().parents[2] / "models" / "gesture-default.pt"


def recognize(*args: str | Path) -> None:
    result = CliRunner().invoke(app, ["recognize", "--checkpoint", str(SHIPPED), *map(str, args)])
    assert result.exit_code == 0, result.output


def gestures(path: Path) -> tuple[list, list]:
    events = [json.loads(line) for line in path.read_text().splitlines()]
    named = [(round(e["t"], 4), e["gesture"]) for e in events if e["type"] == "gesture"]
    commands = [(round(e["t"], 4), e["command"]) for e in events if e["type"] == "command"]
    return named, commands


@pytest.mark.parametrize("captured", [False, True], ids=["as-recorded", "field"])
def test_a_recorded_session_replays_to_the_same_gestures(laser_clips, tmp_path, captured) -> None:
    (stream,) = build_streams(laser_clips, [1003], 5, "test", 3.0, 5.0)
    if captured:
        stream = captured_stream(stream, condition("field", 1), capture_rng(0, "rec", 1, 0, 0))
        assert stream.fps < 30
    source = tmp_path / "field.csv"
    stream.write(source)
    recognize("--source", f"replay:{source}@{stream.fps:g}", "--events", tmp_path / "a.jsonl",
              "--record", tmp_path / "rec")  # fmt: skip
    session = json.loads((tmp_path / "rec" / "session.json").read_text())
    main = session["streams"]["main"]
    assert main["frames_with_operator"] == len(stream.frames)
    assert (tmp_path / "rec" / "events.jsonl").read_text() == (tmp_path / "a.jsonl").read_text()
    recorded = read_landmark_csv(tmp_path / "rec" / "main.csv")
    original = read_landmark_csv(source)
    assert np.array_equal(recorded.frames, original.frames)
    assert np.array_equal(recorded.xyz, original.xyz)
    assert np.array_equal(recorded.visibility, original.visibility)

    recognize("--source", main["replay"], "--events", tmp_path / "b.jsonl")
    first, again = gestures(tmp_path / "a.jsonl"), gestures(tmp_path / "b.jsonl")
    assert first[0], "the stream names gestures"
    # The shipped model commands the clean stream; under field it may command nothing
    # (bench/results/robustness-temporal.json), and the replay must agree either way.
    assert first[1] or captured
    assert again == first


def test_a_camera_pose_of_another_aspect_is_stored_as_the_replay_reads_it(tmp_path) -> None:
    rec = PoseRecorder(tmp_path / "cam.csv", fps=30)
    rng = np.random.default_rng(0)
    xyz = rng.uniform(0.2, 0.8, (33, 3)).astype(np.float32)
    vis = np.ones(33, np.float32)
    rec.add(Pose(t=0.0, xyz=xyz, visibility=vis, image_size=(640, 480)))
    rec.add(Pose(t=0.0334, xyz=xyz, visibility=vis, image_size=(640, 480)))
    rec.add(Pose(t=0.04, xyz=xyz, visibility=vis, image_size=(640, 480)))  # same frame slot
    rec.close()
    track = read_landmark_csv(tmp_path / "cam.csv")
    assert track.frames.tolist() == [1, 2, 3]
    # x and z times the replay's 16:9 equal x and z times the camera's 4:3.
    np.testing.assert_allclose(track.xyz[0, :, 0] * 16 / 9, xyz[:, 0] * 4 / 3, rtol=1e-6)
    np.testing.assert_allclose(track.xyz[0, :, 2] * 16 / 9, xyz[:, 2] * 4 / 3, rtol=1e-6)
    np.testing.assert_array_equal(track.xyz[0, :, 1], xyz[:, 1])
    with pytest.raises(ValueError, match="fps"):
        PoseRecorder(tmp_path / "x.csv", fps=0)
