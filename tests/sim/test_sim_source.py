"""`sim:` streams as the engine opens them: frames carrying every person seen, one clock
for every stream of a scene, and a drone's camera seeing from where the drone is."""

from __future__ import annotations

import math
import threading
import time

import pytest

from proxima.drone.memory import ManualClock, MemoryLink
from proxima.drone.sim import SimConfig
from proxima.ingest import SourceError, open_source
from proxima.sim import registry
from proxima.sim.mount import CameraMount
from proxima.sim.source import SimSource
from proxima.types import Sight, StreamState


def test_frames_carry_the_people_seen_and_no_image() -> None:
    states = []
    with open_source("sim:operator?script=hover:1&bystanders=1", realtime=False,
                     on_state=lambda c: states.append(c.state)) as src:  # fmt: skip
        assert isinstance(src, SimSource)
        frames = list(src)
    assert len(frames) == src.scene.frames and frames[-1].t == pytest.approx((len(frames) - 1) / 30)
    assert all(f.image is None and f.pose is None and f.poses is not None for f in frames)
    assert {len(f.poses) for f in frames} == {2}  # the operator and the bystander
    assert states == [StreamState.LIVE, StreamState.ENDED]
    view = src.scene.views()[src.camera_name]
    assert view.operator_sight == Sight.FULL and view.k == len(frames) - 1


def test_a_looping_scene_goes_on_and_realtime_streams_share_one_clock() -> None:
    uri = "sim:operator?script=hover:0.5&loop=1"
    a = open_source(uri, realtime=True)
    b = open_source(uri + "&at=0,-5,2", realtime=True)
    assert a.scene is b.scene
    got: dict[str, list[tuple[float, float]]] = {"a": [], "b": []}
    until = a.scene.duration_s + 0.5  # into the second pass (the script plus its idles)

    def read(name: str, src: object) -> None:
        for f in src:  # type: ignore[attr-defined]
            got[name].append((f.t, time.monotonic()))
            if f.t >= until:
                break

    threads = [threading.Thread(target=read, args=(n, s)) for n, s in (("a", a), ("b", b))]
    for th in threads:
        th.start()
    for th in threads:
        th.join(until + 10)
    a.close()
    b.close()
    anchor = a.scene.wall_anchor
    assert anchor is not None and len(got["a"]) > a.scene.frames  # it looped
    for rows in got.values():  # each frame at anchor + t, whichever stream
        late = [wall - (anchor + t) for t, wall in rows]
        assert min(late) > -0.002 and sorted(late)[len(late) // 2] < 0.05


def test_a_drone_camera_needs_its_vehicle_and_follows_it() -> None:
    with pytest.raises(SourceError, match="no vehicle of that name is registered"):
        open_source("sim:operator?script=hover:3#main", realtime=False)
    clock = ManualClock()
    link = MemoryLink("main", SimConfig(max_accel=8.0, max_climb=4.0), clock=clock)
    link.connect()
    registry.register_vehicle("main", link.telemetry, (-5.0, 0.0, 0.0), CameraMount(pitch_deg=-8))
    src = open_source("sim:operator?script=hover:6#main", realtime=False)
    frames = iter(src)
    assert next(frames).poses == ()  # on the ground, pitched down: under the torso
    assert link.takeoff(2.5).ok
    link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 2.5) < 0.02, 20.0)
    assert next(frames).poses
    assert src.scene.views()["main"].operator_sight == Sight.FULL  # 5 m away, 2.5 m up
    assert link.goto_local(0.0, 0.0, -3.5).ok
    link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - 3.5) < 0.02, 20.0)
    next(frames)
    view = src.scene.views()["main"]
    assert view.operator_sight == Sight.PARTIAL  # climbed: the feet left the frame
    assert view.camera is not None and -view.camera.position[2] == pytest.approx(3.5, abs=0.03)
    assert link.goto_local(0.0, 0.0, -3.5, yaw=math.radians(180)).ok
    link.wait_for(lambda t: abs(abs(t.yaw) - math.pi) < 1e-3, 5.0)
    assert next(frames).poses == ()  # turned its back on everyone
    src.close()
