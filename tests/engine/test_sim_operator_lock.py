"""The operator lock against people who are not the operator, on a simulated camera:
its frames list every person it sees (`Frame.poses`), the engine picks the operator
among them with the same `OperatorTracker` as for MediaPipe's people (no MediaPipe is
loaded), and only the operator's gestures become commands."""

from __future__ import annotations

from pathlib import Path

import pytest

from proxima.engine import Engine, StreamSpec
from proxima.events import CommandEvent, EventBus, GestureEvent, PoseEvent

SCENE = """
fps = 30
seed = 5
[operator]
heading_deg = 180.0
script = "hover:4,have_command:4,move_to_right:4,wave_off:4"
[[bystanders]]            # signals commands of their own, 2.5 m to the operator's left
behaviour = "gestures"
north = 1.5
east = 2.5
heading_deg = 200.0
script = "have_command:4,move_upward:5,land:7"
[[bystanders]]            # moves their arms at random, 3 m behind on the other side
behaviour = "arms"
north = 3.0
east = -3.0
heading_deg = 160.0
"""


@pytest.fixture(autouse=True)
def clean_registry():  # type: ignore[no-untyped-def]
    from proxima.sim import registry

    registry.reset()
    yield
    registry.reset()


def run(uri: str, classifier, sure_at: float = 0.9):  # type: ignore[no-untyped-def]
    """Commands, poses and confident recognitions (gesture names, confidence >= sure_at)
    of one engine run on `uri`."""
    bus = EventBus()
    commands: list[CommandEvent] = []
    poses: list[PoseEvent] = []
    sure: set[str] = set()
    bus.add_listener(lambda e: commands.append(e) if isinstance(e, CommandEvent) else None)
    bus.add_listener(lambda e: poses.append(e) if isinstance(e, PoseEvent) else None)
    bus.add_listener(
        lambda e: (
            sure.add(e.gesture) if isinstance(e, GestureEvent) and e.confidence >= sure_at else None
        )
    )
    engine = Engine([StreamSpec(name="cam", uri=uri)], bus, realtime=False, classifier=classifier)
    stages = []
    engine.add_tap(
        "cam", on_frame=lambda f: stages.append(engine.pipelines["cam"]._pose_stage) or None
    )
    engine.run()
    stage = stages[-1]
    assert stage is not None and stage.estimator is None  # the tracker only: no MediaPipe
    return commands, poses, sure, engine


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_commands_come_from_the_operator_only(tmp_path: Path, classifier) -> None:  # type: ignore[no-untyped-def]
    scene = tmp_path / "lock.toml"
    scene.write_text(SCENE)
    # The camera 5 m in front of the operator sees all three people.
    commands, poses, sure, engine = run(f"sim:{scene}?at=-5,0,2&pitch=-8&yaw=0", classifier)
    from proxima.sim import registry

    (s,) = registry.scenes()
    view = next(iter(s.views().values()))
    assert sum(p.pose is not None for p in view.people) == 3, view.people
    got = [c.command for c in commands if c.stream]
    assert got[:3] == ["have_command", "move_to_right", "wave_off"], got
    # After wave_off the operator lowers the arms into the closing stance, which the
    # shipped models read as have_command at 0.9 (the ensemble and one member alike):
    # with have_command at 12 nats that re-arms in the scene's last frames (17.5 needs
    # about 0.5 s more than the scene has). A misreading of the synthetic operator's
    # closing stance (docs/experiments.md, "Twenty-ninth session"), not of the lock.
    assert set(got[3:]) <= {"have_command"} and all(c.t > 20 for c in commands[3:]), got
    assert engine.stats["cam"].error is None and len(poses) > 0.9 * s.frames
    assert not sure & {"move_upward", "land"}, sure  # the signaller's were never read
    # The signaller's gestures are read when a camera follows them: the same scene, a
    # camera that frames the signaller alone (land peaks near 0.9 there, and a loaded
    # machine drops frames, so "read" is 0.8 here).
    registry.reset()
    _, _, theirs, _ = run(f"sim:{scene}?at=-3.5,2.5,2&look=1.5,2.5,1&hfov=40", classifier, 0.8)
    assert {"move_upward", "land"} <= theirs, theirs
