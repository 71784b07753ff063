"""The multi-stream engine on replayed streams stitched from held-out dataset clips:
handover when the main camera loses the operator's feet, commands to the main drone
whichever stream saw them, replay speed without effect, failing streams and slow
subscribers that do not disturb recognition."""

from __future__ import annotations

from pathlib import Path

import pytest
from engine_helpers import collect

from proxima.control import AVERAGE_RULE, ControlSettings
from proxima.engine import Engine, JsonlWriter, StreamSpec
from proxima.evaluation.stitch import Blank, stitch_views
from proxima.events import EventBus

# The paper's flight: hover (not armed: ignored), arm, move left; the main drone's camera
# then loses the operator's feet and the secondary one's recognition takes over.
PAPER = [
    ("hover", 4.0),
    ("have_command", 4.0),
    ("move_to_left", 5.0),
    ("have_command", 5.0),
    ("move_to_right", 5.0),
    ("land", 4.0),
]


@pytest.fixture(scope="module")
def paper_streams(laser_clips, tmp_path_factory) -> tuple[Path, Path, dict]:
    folder = tmp_path_factory.mktemp("paper")
    plan_probe = stitch_views(laser_clips, PAPER, views=("f", "r"), seed=11)
    loss = plan_probe["f"].segments[2].end_t  # the main camera loses the feet from here
    streams = stitch_views(
        laser_clips, PAPER, views=("f", "r"), seed=11, blanks={"f": [Blank(loss, 1e6, "feet")]}
    )
    streams["f"].write(folder / "front.csv")
    streams["r"].write(folder / "right.csv")
    return folder / "front.csv", folder / "right.csv", streams["f"].truth()


def test_secondary_takes_over_and_commands_the_main_drone(
    paper_streams, reference_classifier
) -> None:
    classifier = reference_classifier  # an exact script: the fixed model (conftest)
    front, right, truth = paper_streams
    specs = [
        StreamSpec(name="x500", uri=f"replay:{front}"),
        StreamSpec(name="dji", uri=f"replay:{right}"),
    ]
    # with the rule it was tuned with (it is uncalibrated: temperature 1)
    events, engine = collect({"classifier": classifier, "control": AVERAGE_RULE}, specs)
    assert engine.drone == "x500"
    handovers = [
        (e["from_stream"], e["to_stream"], e["reason"])
        for e in events
        if e["type"] == "handover" and e["t"] < truth["duration_s"] - 0.1
    ]
    assert handovers == [
        ("", "x500", "operator_acquired"),
        ("x500", "dji", "operator_partly_visible"),
    ]
    loss = truth["blanks"][0]["start_t"]
    handover_t = next(e["t"] for e in events if e["type"] == "handover" and e["to_stream"] == "dji")
    assert loss + 0.9 <= handover_t <= loss + 1.2  # after the 1 s hold
    commands = [
        (e["command"], e["stream"], e["drone"])
        for e in events
        if e["type"] == "command" and e["stream"]
    ]
    assert commands == [
        ("have_command", "x500", "x500"),
        ("move_to_left", "x500", "x500"),
        ("have_command", "dji", "x500"),
        ("move_to_right", "dji", "x500"),
        ("land", "dji", "x500"),
    ]
    # No command before arming: the hover performed first was ignored.
    first = next(e for e in events if e["type"] == "command")
    assert first["t"] >= truth["segments"][1]["onset_t"]
    reasons = [e["reason"] for e in events if e["type"] == "arming"]
    assert reasons[:4] == ["have_command", "handover", "have_command", "stream_ended"][:4]


def test_replay_speed_does_not_change_decisions(laser_clips, classifier, tmp_path) -> None:
    stream = stitch_views(laser_clips, [("have_command", 3.2)], views=("f",), seed=2)["f"]
    stream.write(tmp_path / "s.csv")
    spec = [StreamSpec(name="main", uri=f"replay:{tmp_path / 's.csv'}")]
    fast, _ = collect({"classifier": classifier, "realtime": False}, spec)
    paced, _ = collect({"classifier": classifier, "realtime": True}, spec)

    def decisions(events: list[dict]) -> list[dict]:
        return [e for e in events if e["type"] != "stream"]

    assert decisions(fast) == decisions(paced)
    assert next(e["command"] for e in fast if e["type"] == "command") == "have_command"


def test_a_failing_stream_and_a_slow_subscriber_disturb_nothing(
    laser_clips, classifier, tmp_path
) -> None:
    stream = stitch_views(laser_clips, [("have_command", 4.0)], views=("f",), seed=4)["f"]
    stream.write(tmp_path / "ok.csv")
    bus = EventBus()
    slow = bus.subscribe(maxsize=10)  # never read: it must lose events, not stall anyone
    writer = JsonlWriter(tmp_path / "events.jsonl", bus)
    seen: list[dict] = []
    bus.add_listener(lambda e: seen.append(e.to_dict()))
    specs = [
        StreamSpec(name="main", uri=f"replay:{tmp_path / 'ok.csv'}"),
        StreamSpec(name="broken", uri=f"replay:{tmp_path / 'missing.csv'}"),
    ]
    with pytest.raises(ValueError, match="'gopher://nowhere' must start with one of"):
        StreamSpec(name="weird", uri="gopher://nowhere")  # refused before any stream starts
    engine = Engine(
        specs, bus, realtime=False, classifier=classifier, control=ControlSettings(regain_s=0.5)
    )
    engine.run()
    writer.close()
    assert engine.stats["main"].frames == len(stream.frames)
    assert "missing.csv" in (engine.stats["broken"].error or "")
    ended = {
        e["stream"]: e["detail"] for e in seen if e["type"] == "stream" and e["state"] == "ended"
    }
    assert "missing.csv" in ended["broken"]
    assert any(e["type"] == "command" and e["command"] == "have_command" for e in seen)
    assert slow.dropped > 0
    lines = (tmp_path / "events.jsonl").read_text().splitlines()
    assert len(lines) == len(seen)  # the writer lost nothing


def test_camera_frames_go_through_pose_estimation(classifier, tmp_path) -> None:
    """A real video (a photo of a person, moving slightly) through MediaPipe, operator
    tracking, the window and the classifier."""
    import cv2
    import numpy as np
    from skimage import data as skimage_data

    photo = np.ascontiguousarray(skimage_data.astronaut()[:, :, ::-1])  # BGR 512x512
    path = tmp_path / "person.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 15, (640, 512))
    for k in range(66):
        frame = np.zeros((512, 640, 3), np.uint8)
        frame[:, k : k + 512] = photo
        writer.write(frame)
    writer.release()
    bus = EventBus()
    events: list[dict] = []
    bus.add_listener(lambda e: events.append(e.to_dict()))
    engine = Engine(
        [StreamSpec(name="cam", uri=f"file:{path}")], bus, realtime=False, classifier=classifier
    )
    engine.run()
    assert engine.stats["cam"].error is None
    poses = [e for e in events if e["type"] == "pose"]
    assert len(poses) >= 60, "the operator must be found in nearly every frame"
    assert all(len(p["xyz"]) == 33 for p in poses)
    gestures = [e for e in events if e["type"] == "gesture"]
    assert len(gestures) >= 1 and all(len(g["probs"]) == 13 for g in gestures)
    assert poses[-1]["t"] == pytest.approx(65 / 15, abs=0.01)
