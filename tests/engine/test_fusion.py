"""Fusion across streams (`proxima.engine.fusion`) on real LASER clips, with the pre-capture
model: two views of one gesture, a stream that does not see the operator, the setting
off, and the priority arbiter still routing every command to the controlled drone."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from proxima.control import ControlSettings, Sight, StreamUpdate, WindowEvidence
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.fusion import ARMS, Fused, FusedDecisions, fuse, window_evidence
from proxima.evaluation.fusion import engine_run_views
from proxima.evaluation.replay import MemoClassifier
from proxima.evaluation.stitch import Blank, StitchedStream, apply_blank, stitch_views
from proxima.gesture.clip import Clip
from proxima.pose import FEET
from proxima.types import Event

# A model trained without capture augmentation, unsure on noisy input (tests/data/README.md).
NO_CAPTURE = Path(__file__).resolve().parents[1] / "data" / "gesture-no-capture.pt"

Clips = dict[tuple[str, str], Clip]
SHIPPED = EngineSettings().fusion_overrule_below  # agreement only


@pytest.fixture(scope="module")
def clf() -> MemoClassifier:
    from proxima.gesture.classifier import GestureClassifier

    return MemoClassifier(GestureClassifier.load(NO_CAPTURE))


@pytest.fixture(scope="module")
def clips() -> Clips:
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    try:
        loaded = load_laser_dir(resolve_dataset(None))
    except Exception as exc:  # no data on this machine
        pytest.skip(f"LASER data not available: {exc}")
    return {(c.gesture, c.view): c for c in loaded}


def evidence(
    clf: MemoClassifier, clip: Clip, start: int, withheld: Sequence[str] = ()
) -> WindowEvidence:
    """The window of `clip` rows start..start+60 as fusion reads it."""
    xyz = clip.xyz[start : start + 60][None].astype(np.float32)
    probs = clf.predict(xyz)[0]
    vis = clip.visibility[start : start + 60]
    return window_evidence(probs, vis, withheld, clf.labels, 0.5, False)


@pytest.mark.parametrize("overrule", [SHIPPED, 0.9, 1.0])
@pytest.mark.parametrize(("gesture", "start"), [("move_upward", 570), ("wave_off", 630)])
def test_two_views_beat_the_better_one_when_one_is_ambiguous(
    clf: MemoClassifier, clips: Clips, gesture: str, start: int, overrule: float
) -> None:
    g = clf.labels.index(gesture)
    front = evidence(clf, clips[(gesture, "f")], start)
    left = evidence(clf, clips[(gesture, "l")], start)
    assert front.probs.argmax() == g and front.probs[g] > 0.9
    assert left.probs.max() < 0.6  # the left view alone is ambiguous
    best = max(front.probs[g], left.probs[g])
    for fused in (
        fuse(("l", left), [("f", front)], overrule),
        fuse(("f", front), [("l", left)], overrule),
    ):
        assert int(np.argmax(fused.probs)) == g
        assert fused.probs[g] >= best
    # the ambiguous view's own decision is the sharpened one
    assert fuse(("l", left), [("f", front)], overrule).probs[g] > front.probs[g]


def test_thumb_gestures_are_read_from_the_view_that_sees_the_hand(
    clf: MemoClassifier, clips: Clips
) -> None:
    g = clf.labels.index("all_clear")
    front = evidence(clf, clips[("all_clear", "f")], 630)
    left = evidence(clf, clips[("all_clear", "l")], 630, withheld=("all_clear", "not_clear"))
    assert clf.labels[int(np.argmax(left.probs))] == "not_clear"  # a guess without the hand
    fused = fuse(("l", left), [("f", front)], SHIPPED)
    assert int(np.argmax(fused.probs)) == g and fused.probs[g] >= front.probs[g]
    assert fused.withheld == ()  # the front camera sees the hand
    alone = fuse(("l", left), [], 0.9)
    assert alone.withheld == left.withheld and np.array_equal(alone.probs, left.probs)


def test_a_stream_that_does_not_see_the_operator_contributes_nothing(
    clf: MemoClassifier, clips: Clips
) -> None:
    front = evidence(clf, clips[("move_upward", "f")], 570)
    left_clip = clips[("move_upward", "l")]
    hidden = left_clip.visibility[570:630].copy()
    hidden[:, ARMS] = 0.2  # the arms out of sight
    probs = clf.predict(left_clip.xyz[570:630][None].astype(np.float32))[0]
    low = window_evidence(probs, hidden, (), clf.labels, 0.5, False)
    assert low.weight == 0.0
    fused = fuse(("f", front), [("l", low)], 1.0)
    assert np.array_equal(fused.probs, front.probs) and list(fused.weights) == ["f"]

    # In the decision path: a stream whose newest frame sees nobody drops out at once.
    left = evidence(clf, left_clip, 570)
    seen: list[Fused] = []
    from proxima.control import CommandController

    decisions = FusedDecisions(
        CommandController(["f", "l"], "main"),
        ControlSettings(),
        EngineSettings(fusion="on", fusion_overrule_below=1.0),
        listener=lambda stream, t, fused: seen.append(fused),
    )
    decisions.process(StreamUpdate("l", 1.0, Sight.FULL, "", 0.0, evidence=left))
    decisions.process(StreamUpdate("f", 1.1, Sight.FULL, "", 0.0, evidence=front))
    assert list(seen[-1].weights) == ["f", "l"]
    decisions.process(StreamUpdate("l", 1.15, Sight.NONE))  # nobody in the left view
    decisions.process(StreamUpdate("f", 1.2, Sight.FULL, "", 0.0, evidence=front))
    assert list(seen[-1].weights) == ["f"] and np.array_equal(seen[-1].probs, front.probs)
    decisions.process(StreamUpdate("l", 1.3, Sight.FULL, "", 0.0, evidence=left))
    decisions.process(StreamUpdate("f", 1.9, Sight.FULL, "", 0.0, evidence=front))
    assert list(seen[-1].weights) == ["f"]  # the left window is too old (max age 0.4 s)


def _script_streams(clips: dict[tuple[str, str], Clip]) -> dict[str, StitchedStream]:
    plan = [("hover", 4.0), ("have_command", 5.0), ("move_to_left", 5.0), ("have_command", 5.0),
            ("move_upward", 5.0), ("land", 6.0)]  # fmt: skip
    return stitch_views(list(clips.values()), plan, ("f", "l"), part="all", seed=1)


def test_fusion_off_is_todays_engine_and_one_stream_on_decides_the_same(
    clf: MemoClassifier, clips: Clips
) -> None:
    streams = _script_streams(clips)
    control = ControlSettings()
    off = engine_run_views([streams["f"]], control, EngineSettings(), clf)
    on = engine_run_views([streams["f"]], control, EngineSettings(fusion="on"), clf)
    assert [c["command"] for c in off.commands] == [
        "have_command", "move_to_left", "have_command", "move_upward", "land", "hover"
    ]  # fmt: skip
    assert off.commands == on.commands and off.arming == on.arming
    assert not off.fused and len(on.fused["f"]) == len(off.own["f"])
    for (t0, fused), (t1, own) in zip(on.fused["f"], off.own["f"], strict=True):
        assert t0 == t1 and np.allclose(fused, own, atol=1e-4)  # events round to 4 digits

    from proxima.engine.runner import Engine
    from proxima.events import EventBus

    engine = Engine([StreamSpec(name="f", uri="replay:x.csv")], EventBus(), classifier=clf)
    assert engine.fusion is None and engine.merge.controller is engine.controller


def test_priority_still_routes_every_command_to_the_controlled_drone(
    clf: MemoClassifier, clips: Clips, tmp_path: Path
) -> None:
    """The main camera loses the feet from move_to_left on: the left camera drives, and
    its (fused) commands go to the main drone."""
    streams = _script_streams(clips)
    for stream in streams.values():  # both see the whole operator until the blank
        stream.visibility[:, list(FEET)] = 1.0
    apply_blank(streams["f"], Blank(9.8, 40.0, "feet"))
    from proxima.engine.runner import Engine
    from proxima.events import CommandEvent, EventBus, HandoverEvent

    specs = []
    for rank, (view, drone) in enumerate((("f", "main"), ("l", "secondary"))):
        path = tmp_path / f"{view}.csv"
        streams[view].write(path)
        specs.append(StreamSpec(name=view, uri=f"replay:{path}@30", priority=rank, drone=drone))
    events: list[Event] = []
    bus = EventBus()
    bus.add_listener(events.append)
    fused_by: set[str] = set()
    engine = Engine(
        specs, bus, settings=EngineSettings(fusion="on"), realtime=False, classifier=clf
    )
    assert engine.fusion is not None and engine.drone == "main"
    engine.fusion.listener = lambda stream, t, fused: (
        fused_by.add(stream) if len(fused.weights) > 1 else None
    )
    engine.run()
    handovers = [e for e in events if isinstance(e, HandoverEvent)]
    commands = [e for e in events if isinstance(e, CommandEvent)]
    assert [(h.from_stream, h.to_stream) for h in handovers][:2] == [("", "f"), ("f", "l")]
    assert {c.drone for c in commands} == {"main"}
    taken = handovers[1].t
    assert {c.stream for c in commands if c.t < taken} == {"f"}
    assert {c.stream for c in commands if c.t > taken and c.stream} == {"l"}
    assert [c.command for c in commands if c.t > taken and c.stream] == [
        "have_command", "move_upward", "land"
    ]  # fmt: skip
    assert fused_by == {"f", "l"}  # both streams' decisions had the other's evidence


def test_a_view_that_disagrees_does_not_overrule_by_default(
    clf: MemoClassifier, clips: Clips
) -> None:
    front = evidence(clf, clips[("move_upward", "f")], 570)
    other = evidence(clf, clips[("hover", "l")], 300)  # another gesture, read confidently
    assert clf.labels[int(np.argmax(other.probs))] == "hover" and other.probs.max() > 0.9
    kept = fuse(("f", front), [("l", other)], SHIPPED)
    assert list(kept.weights) == ["f"] and np.array_equal(kept.probs, front.probs)
    mixed = fuse(("f", front), [("l", other)], 1.0)  # without the guard it would count
    assert list(mixed.weights) == ["f", "l"] and mixed.probs.max() < front.probs.max()


@pytest.mark.parametrize("arms", [True, False])
def test_fused_evidence_arms_only_when_allowed(
    clf: MemoClassifier, clips: Clips, arms: bool
) -> None:
    """Two cameras see a real `have_command` while the driving stream's own decision has
    not named it yet: with `fusion_arms` the fused decision arms control; without, only
    the stream's own `have_command` does."""
    from proxima.control import CommandController
    from proxima.events import ArmingEvent

    decisions = FusedDecisions(
        CommandController(["f", "l"], "main"),
        ControlSettings(),
        EngineSettings(fusion="on", fusion_arms=arms),
    )
    front, left = clips[("have_command", "f")], clips[("have_command", "l")]
    events: list[Event] = []
    for k in range(30):
        t, row = 1.0 + 0.17 * k, 200 + 5 * k
        decisions.process(
            StreamUpdate("l", t, Sight.FULL, "", 0.0, evidence=evidence(clf, left, row))
        )
        update = StreamUpdate(
            "f", t + 0.01, Sight.FULL, "", 0.0, evidence=evidence(clf, front, row)
        )
        events += decisions.process(update)
    armed = [e for e in events if isinstance(e, ArmingEvent) and e.armed]
    assert bool(armed) is arms
    if not arms:  # the stream's own decision still arms
        own = StreamUpdate(
            "f", 7.0, Sight.FULL, "have_command", 0.99, evidence=evidence(clf, front, 350)
        )
        assert any(isinstance(e, ArmingEvent) and e.armed for e in decisions.process(own))
