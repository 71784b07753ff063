"""The engine's hooks on real LASER replays: frame taps (each frame and update, in the
stream thread; a replacement frame reaches recognition; a failing tap is logged and
changes nothing) and the classifier swap from another thread (the new model from the
next window on, the filter emptied)."""

from __future__ import annotations

import logging
import threading
from pathlib import Path

import numpy as np
import pytest

from proxima.control import StreamUpdate, decision_filter
from proxima.engine import Engine, StreamSpec, Tap
from proxima.events import EventBus, GestureEvent
from proxima.types import Frame, Pose

FEET = list(range(27, 33))


def _clip(laser_dir: Path, name: str) -> Path:
    matches = sorted(laser_dir.glob(f"DJI_*_{name}.MP4.csv"))
    assert matches, f"no LASER clip *_{name}.MP4.csv in {laser_dir}"
    return matches[0]


def _gestures(engine: Engine, bus: EventBus) -> list[GestureEvent]:
    events: list[GestureEvent] = []
    bus.add_listener(lambda e: events.append(e) if isinstance(e, GestureEvent) else None)
    engine.run()
    assert all(s.error is None for s in engine.stats.values()), engine.stats
    return events


def _run(uri: str, classifier, *taps: dict) -> tuple[Engine, list[GestureEvent], list[Tap]]:  # type: ignore[no-untyped-def]
    """The stream through an engine with these taps (add_tap keywords), flat out."""
    bus = EventBus()
    engine = Engine([StreamSpec(name="main", uri=uri)], bus, realtime=False, classifier=classifier)
    added = [engine.add_tap("main", **tap) for tap in taps]
    return engine, _gestures(engine, bus), added


def test_a_tap_sees_every_frame_and_update_in_the_stream_thread(laser_dir, classifier) -> None:
    uri = f"replay:{_clip(laser_dir, 'hover_f')}@30"
    frames: list[tuple[float, str]] = []
    updates: list[tuple[Frame, StreamUpdate]] = []

    def on_frame(frame: Frame) -> None:
        frames.append((frame.t, threading.current_thread().name))

    engine, plain, _ = _run(uri, classifier)
    tap = {"on_frame": on_frame, "on_update": lambda f, u: updates.append((f, u))}
    tapped, events, _ = _run(uri, classifier, tap)
    n = tapped.stats["main"].frames
    assert n == engine.stats["main"].frames > 60
    assert len(frames) == len(updates) == n
    assert {name for _, name in frames} == {"stream main"}
    assert [t for t, _ in frames] == [f.t for f, _ in updates] == [u.t for _, u in updates]
    assert all(u.stream == "main" for _, u in updates)
    # Looking changes nothing: the same recognitions as without the tap.
    assert [(e.t, e.probs) for e in events] == [(e.t, e.probs) for e in plain]
    with pytest.raises(KeyError):
        tapped.add_tap("side", on_frame=on_frame)
    with pytest.raises(ValueError, match="on_frame or on_update"):
        tapped.add_tap("main")


def test_a_replacement_frame_reaches_recognition_and_a_tap_can_be_removed(
    laser_dir, classifier
) -> None:
    uri = f"replay:{_clip(laser_dir, 'hover_f')}@30"

    def feet_out(frame: Frame) -> Frame:  # as a camera that lost the operator's feet
        assert frame.pose is not None
        vis = np.array(frame.pose.visibility, np.float32)
        vis[FEET] = 0.0
        pose = Pose(t=frame.pose.t, xyz=frame.pose.xyz, visibility=vis)
        return Frame(t=frame.t, index=frame.index, pose=pose)

    bus = EventBus()
    poses: list[list[float]] = []
    bus.add_listener(lambda e: poses.append(e.visibility) if e.type == "pose" else None)
    engine = Engine([StreamSpec(name="main", uri=uri)], bus, realtime=False, classifier=classifier)
    tap = engine.add_tap("main", on_frame=feet_out)
    engine.run()
    assert len(poses) == engine.stats["main"].frames
    assert all(max(v[i] for i in FEET) == 0.0 for v in poses)
    assert any(v[0] > 0.5 for v in poses)  # the rest of the body as recorded
    engine.remove_tap(tap)
    engine.remove_tap(tap)  # unregistering twice is harmless


def test_a_failing_tap_is_logged_and_never_stops_recognition(
    laser_dir, classifier, caplog: pytest.LogCaptureFixture
) -> None:
    uri = f"replay:{_clip(laser_dir, 'hover_f')}@30"
    _, plain, _ = _run(uri, classifier)
    with caplog.at_level(logging.WARNING, logger="proxima.engine.taps"):
        engine, events, (broken, wrong) = _run(
            uri,
            classifier,
            {"on_frame": lambda f: 1 / 0, "on_update": lambda f, u: [][1]},
            {"on_frame": lambda f: "not a frame"},
        )
    assert [(e.t, e.probs) for e in events] == [(e.t, e.probs) for e in plain]
    frames = engine.stats["main"].frames
    assert broken.failures == 2 * frames and wrong.failures == frames
    errors = [r for r in caplog.records if r.levelno == logging.ERROR]
    assert len(errors) == 3  # each failing callable logged once, not once per frame
    assert errors[0].exc_info is not None and errors[0].exc_info[0] is ZeroDivisionError
    assert "stream main" in errors[0].getMessage()
    assert "returned str, not a Frame" in " ".join(r.getMessage() for r in errors)


@pytest.fixture(scope="module")
def second_checkpoint(tmp_path_factory, classifier) -> Path:
    """A real second checkpoint: the shipped members' architecture and pipeline, freshly
    initialised (untrained), so its probabilities differ from the shipped model's."""
    import torch

    from proxima.gesture.classifier import save_checkpoint
    from proxima.gesture.ensemble import members_of
    from proxima.gesture.models import build_model, model_config

    torch.manual_seed(7)
    first = members_of(classifier)[0]  # the shipped model is an ensemble of such models
    model = build_model(first.model_name, **model_config(first.model))
    path = tmp_path_factory.mktemp("models") / "untrained.pt"
    meta = {"purpose": "swap test"}
    return save_checkpoint(path, model, first.model_name, first.pipeline, first.window, meta)


@pytest.mark.slow
def test_swapping_the_classifier_from_another_thread_mid_stream(
    laser_dir, classifier, second_checkpoint
) -> None:
    from proxima.engine import load_classifier

    other = load_classifier(second_checkpoint)
    uri = f"replay:{_clip(laser_dir, 'move_downward_f')}@150"
    ref_old = {e.t: e.probs for e in _run(uri, classifier)[1]}
    ref_new = {e.t: e.probs for e in _run(uri, other)[1]}
    assert ref_old.keys() == ref_new.keys() and len(ref_old) > 100
    assert all(ref_old[t] != ref_new[t] for t in ref_old)  # the two models tell apart

    bus = EventBus()
    engine = Engine([StreamSpec(name="main", uri=uri)], bus, realtime=True, classifier=classifier)
    with pytest.raises(RuntimeError, match="not started"):
        engine.swap_classifier(other)
    seen: list[GestureEvent] = []
    actions: list[tuple[float, float]] = []
    bus.add_listener(lambda e: seen.append(e) if isinstance(e, GestureEvent) else None)
    bus.add_listener(lambda e: actions.append((e.t, e.confidence)) if e.type == "action" else None)
    with bus.subscribe(types=["gesture"]) as sub:
        engine.start()
        for _ in range(20):  # a while into the stream, in this (the test's) thread
            assert sub.get(timeout=30) is not None
        (swap,) = engine.swap_classifier(other)
        assert swap.wait(5.0) and not swap.replaced
    assert engine.wait(60)
    assert engine.classifier("main") is other
    assert swap.t is not None and 0 < swap.t < engine.stats["main"].last_t
    # Every window the stream classified, each by the model in place at its frame.
    assert [e.t for e in seen] == sorted(ref_old)
    before = [e for e in seen if e.t < swap.t]
    after = [e for e in seen if e.t >= swap.t]
    assert len(before) >= 20 and len(after) >= 20
    assert all(e.probs == ref_old[e.t] for e in before)
    assert all(e.probs == ref_new[e.t] for e in after)
    # The rule was emptied: the first decision after the swap is a fresh rule's.
    first = next(c for t, c in actions if t >= swap.t)
    fresh = decision_filter(engine.control, other.labels).update(swap.t, after[0].probs)
    assert first == pytest.approx(fresh.confidence, abs=1e-3)


def test_a_swap_on_an_ended_stream_applies_at_once(laser_dir, classifier, second_checkpoint):  # type: ignore[no-untyped-def]
    from proxima.engine import load_classifier

    engine, _, _ = _run(f"replay:{_clip(laser_dir, 'hover_f')}@30", classifier)
    other = load_classifier(second_checkpoint)
    first, second = engine.swap_classifier(other), engine.swap_classifier(classifier)
    assert first[0].applied.is_set() and first[0].t is None
    assert second[0].applied.is_set() and engine.classifier("main") is classifier
