"""The 3D view's cameras and simulated people: frusta from a drone's pose and mount,
lines of sight coloured by its stream's sight, the synthetic people where they stand."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest

from proxima.drone.events import DroneStateEvent
from proxima.events import EventBus, PoseEvent
from proxima.settings import Settings
from proxima.sim import registry
from proxima.sim.mount import CameraMount
from proxima.sim.uri import parse_sim_uri
from proxima.synth.camera import Camera
from proxima.viz.cameras import (
    SIGHT_COLORS,
    frustum_corners,
    frustum_segments,
    operator_point,
    scene_people,
)
from proxima.viz.model import SIGHT_STALE_S, SceneModel
from proxima.viz.scene import FleetView


@pytest.fixture(autouse=True)
def clean_registry() -> Iterator[None]:
    registry.reset()
    yield
    registry.reset()


def _settings() -> Settings:
    return Settings(
        drones=[
            {"name": "main", "connection": "udpin:127.0.0.1:1", "home": (0.0, -5.0, 0.0),
             "camera": {"pitch_deg": -10.0, "hfov_deg": 60.0}},
        ],
        streams=[{"name": "front", "uri": "sim:operator", "drone": "main"}],
        server={"viser_port": 0},
    )  # fmt: skip


def test_the_frustum_is_the_cameras_view() -> None:
    cam = Camera(
        (0.0, 0.0, -2.0), yaw_deg=90.0, pitch_deg=0.0, hfov_deg=90.0, width=200, height=100
    )
    c = frustum_corners(cam, depth=2.0)
    np.testing.assert_allclose(c[0], [0.0, 0.0, -2.0])
    # Looking east, 90 degrees wide: the far corners 2 m east, 2 m to either side.
    np.testing.assert_allclose(c[1:, 1], 2.0, atol=1e-9)
    np.testing.assert_allclose(sorted(c[1:, 0]), [-2.0, -2.0, 2.0, 2.0], atol=1e-9)
    np.testing.assert_allclose(sorted(c[1:, 2]), [-3.0, -3.0, -1.0, -1.0], atol=1e-9)
    # Each far corner projects onto an image corner.
    xy, _ = cam.project(c[1:])
    np.testing.assert_allclose(xy, [[0, 0], [1, 0], [1, 1], [0, 1]], atol=1e-9)
    segs = frustum_segments(cam, 2.0)
    assert segs.shape == (8, 2, 3)
    np.testing.assert_allclose(segs[0, 0], [0.0, 0.0, 2.0])  # the view's frame: z up


def test_the_model_places_each_camera_and_colours_its_sight() -> None:
    now = [100.0]
    model = SceneModel(_settings(), clock=lambda: now[0])
    assert model.snapshot()["drones"]["main"]["camera"] is None
    model.apply(DroneStateEvent(t=0.0, drone="main", link="ok", position=[0.0, 0.0, -2.5],
                                attitude=[0.0, 0.0, math.radians(20)]))  # fmt: skip
    d = model.snapshot()["drones"]["main"]
    cam = d["camera"]
    assert cam.position == pytest.approx((-5.0 + 0.1 * math.cos(math.radians(20)),
                                          0.1 * math.sin(math.radians(20)), -2.5))  # fmt: skip
    assert cam.yaw_deg == pytest.approx(20.0) and cam.pitch_deg == pytest.approx(-10.0)
    assert cam.hfov_deg == 60.0 and d["sight"] == "none"
    zero = np.zeros((33, 3)).tolist()
    model.apply(PoseEvent(t=1.0, stream="front", xyz=zero, visibility=[1.0] * 33, sight="partial"))
    assert model.snapshot()["drones"]["main"]["sight"] == "partial"
    now[0] += SIGHT_STALE_S + 0.1  # the stream published no pose since: it sees nobody
    assert model.snapshot()["drones"]["main"]["sight"] == "none"


def test_simulated_people_stand_where_they_are() -> None:
    uri = parse_sim_uri("sim:operator?script=hover:2&bystanders=1")
    scene = registry.scene_for(uri)
    assert scene_people(scene) == []  # no camera looked yet
    cam = CameraMount().camera((-5.0, 0.0, -2.0), (0.0, 0.0, 0.0))
    scene.view(cam, 40, camera_name="main")
    people = scene_people(scene)
    assert [(n, op) for n, op, _ in people] == [("operator", True), ("bystander1", False)]
    op = people[0][2]
    assert op.shape[1:] == (2, 3)
    assert 0.0 <= op[..., 2].min() < 0.15 and 1.4 < op[..., 2].max() < 2.0  # feet to head, z up
    assert np.abs(op[..., :2]).max() < 0.6  # at the origin
    by = people[1][2][..., :2].mean(axis=(0, 1))
    np.testing.assert_allclose(by, [2.6, 1.0], atol=0.5)  # east 2.6, north 1 (x east, y north)
    np.testing.assert_allclose(operator_point(scene, (9, 9, 9))[:2], [0.0, 0.0], atol=0.2)
    assert operator_point(None, (1.0, 2.0, 1.0)).tolist() == [1.0, 2.0, 1.0]


def test_fleet_view_draws_frusta_sight_lines_and_people() -> None:
    bus = EventBus()
    view = FleetView(_settings(), bus).start()
    try:
        scene = registry.scene_for(parse_sim_uri("sim:operator?script=hover:2"))
        scene.view(CameraMount().camera((-5.0, 0.0, -2.0), (0.0, 0.0, 0.0)), 10, camera_name="x")
        bus.publish(DroneStateEvent(t=0.0, drone="main", link="ok", position=[0.0, 0.0, -2.5],
                                    attitude=[0.0, 0.0, 0.0]))  # fmt: skip
        bus.publish(PoseEvent(t=0.0, stream="front", xyz=np.zeros((33, 3)).tolist(),
                              visibility=[1.0] * 33, sight="full"))  # fmt: skip
        deadline = time.monotonic() + 5
        want = {"/cameras/main/frustum", "/cameras/main/sight", "/people/operator"}
        while not want <= set(view._handles) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert want <= set(view._handles), sorted(view._handles)
        assert view.model.snapshot()["drones"]["main"]["sight"] == "full"
        assert SIGHT_COLORS["full"] != SIGHT_COLORS["none"]
    finally:
        view.stop()
