"""The 3D view: the scene model from real events, and the viser server on loopback."""

from __future__ import annotations

import time

import httpx
import numpy as np

from proxima.drone.events import DroneStateEvent
from proxima.events import EventBus, HandoverEvent, PoseEvent
from proxima.ingest import read_landmark_csv
from proxima.settings import Settings
from proxima.viz.model import SceneModel, ned_to_world, operator_segments
from proxima.viz.scene import FleetView


def _settings(laser_dir) -> Settings:  # type: ignore[no-untyped-def]
    clip = sorted(laser_dir.glob("DJI_*_hover_f.MP4.csv"))[0]
    return Settings(
        drones=[
            {"name": "main", "connection": "udpin:127.0.0.1:1", "home": (0.0, -5.0, 0.0)},
            {
                "name": "second",
                "connection": "udpin:127.0.0.1:2",
                "sysid": 2,
                "home": (4.0, -5.0, 0.0),
            },
        ],
        streams=[
            {"name": "front", "uri": f"replay:{clip}", "drone": "main"},
            {"name": "side", "uri": f"replay:{clip}", "drone": "second", "priority": 1},
        ],
        server={"viser_port": 0},
    )


def test_ned_to_world() -> None:
    home = np.array([4.0, -5.0, 0.0])
    np.testing.assert_allclose(ned_to_world(home, [1.0, 2.0, -3.0]), [6.0, -4.0, 3.0])


def test_scene_model_tracks_drones_driving_and_operator(laser_dir) -> None:  # type: ignore[no-untyped-def]
    settings = _settings(laser_dir)
    model = SceneModel(settings)
    for i in range(5):
        model.apply(
            DroneStateEvent(t=float(i), drone="main", link="ok", position=[0.5 * i, 0.0, -2.0])
        )
    snap = model.snapshot()
    main = snap["drones"]["main"]
    np.testing.assert_allclose(main["position"], [0.0, -3.0, 2.0])
    assert main["trail"].shape == (5, 3)
    assert snap["drones"]["second"]["position"] is None
    model.apply(
        HandoverEvent(
            t=5.0,
            stream="side",
            from_stream="front",
            to_stream="side",
            reason="main lost the operator's feet",
        )
    )
    assert model.snapshot()["driving_drone"] == "second"
    # The operator is drawn from the driving stream's real landmarks, standing upright.
    track = read_landmark_csv(sorted(laser_dir.glob("DJI_*_hover_f.MP4.csv"))[0])
    model.apply(
        PoseEvent(
            t=5.0,
            stream="side",
            xyz=track.xyz[0].tolist(),
            visibility=track.visibility[0].tolist(),
            sight="full",
        )
    )
    op = model.snapshot()["operator"]
    assert op is not None and op.shape[1:] == (2, 3)
    z = op[:, :, 2]
    assert 0.0 <= z.min() < 0.2 and 1.2 < z.max() <= 1.76
    # The other stream's pose does not move the operator; it colours its drone's sight.
    before = model.snapshot()["operator"]
    assert model.snapshot()["drones"]["main"]["sight"] == "none"
    model.apply(
        PoseEvent(
            t=5.0,
            stream="front",
            xyz=track.xyz[1].tolist(),
            visibility=track.visibility[1].tolist(),
            sight="partial",
        )
    )
    np.testing.assert_array_equal(model.snapshot()["operator"], before)
    assert model.snapshot()["drones"]["main"]["sight"] == "partial"


def test_operator_segments_need_enough_landmarks() -> None:
    xyz = np.zeros((33, 3))
    assert operator_segments(xyz, np.zeros(33), np.zeros(3), 1.75) is None


def test_viser_serves_the_scene_on_loopback(laser_dir) -> None:  # type: ignore[no-untyped-def]
    bus = EventBus()
    view = FleetView(_settings(laser_dir), bus).start()
    try:
        assert view.host == "127.0.0.1"
        r = httpx.get(f"http://127.0.0.1:{view.port}/", timeout=5)
        assert r.status_code == 200 and "<html" in r.text.lower()
        for i in range(10):
            bus.publish(
                DroneStateEvent(t=float(i), drone="main", link="ok", position=[0.2 * i, 0.0, -2.0])
            )
        deadline = time.monotonic() + 5
        while view.model.version < 10 and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)
        assert view.model.snapshot()["drones"]["main"]["trail"].shape[0] == 10
        assert "/trails/main" in view._handles and "/drones/main" in view._handles
        # Issue 26, finding 8: the marker is smaller than a 1 m move, even driving.
        from proxima.viz.scene import DRIVING_SCALE, DRONE_RADIUS_M

        assert 2 * DRONE_RADIUS_M * DRIVING_SCALE < 1.0
        assert view._handles["/drones/main"].scale in (1.0, DRIVING_SCALE)
        # Labels of drones side by side are stacked, not drawn over each other.
        bus.publish(DroneStateEvent(t=11.0, drone="second", link="ok", position=[0.0, 0.3, -2.0]))
        deadline = time.monotonic() + 5
        while "/drones/second/label" not in view._handles and time.monotonic() < deadline:
            time.sleep(0.05)
        heights = {
            n: float(view._handles[f"/drones/{n}/label"].position[2]) for n in ("main", "second")
        }
        assert abs(heights["main"] - heights["second"]) >= 0.3, heights
    finally:
        view.stop()
