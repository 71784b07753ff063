"""The camera mount follows the vehicle: its position and heading from the vehicle's
telemetry (the simulated vehicle behind a `MemoryLink`, flown by real commands), and what
the camera sees changes with them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from proxima.drone.link import Telemetry
from proxima.drone.memory import ManualClock, MemoryLink
from proxima.drone.sim import SimConfig
from proxima.sim.config import OperatorConfig, SceneConfig, build_scene
from proxima.sim.mount import CameraMount
from proxima.synth.camera import rotation_zyx
from proxima.types import Sight

HOME = (-5.0, 0.0, 0.0)  # the vehicle's origin in the scene: 5 m south of the operator


def _flying(clock: ManualClock, altitude: float = 2.5) -> MemoryLink:
    link = MemoryLink("main", SimConfig(max_accel=8.0, max_climb=4.0), clock=clock)
    link.connect()
    assert link.takeoff(altitude).ok
    assert link.wait_for(lambda t: t.landed == "in_air" and abs(t.altitude - altitude) < 0.05, 20)
    return link


def _settle(
    link: MemoryLink, target: tuple[float, float, float], yaw_deg: float = 0.0
) -> Telemetry:
    """Wait until the vehicle is still at `target`, heading `yaw_deg`."""

    def there(t: Telemetry) -> bool:
        turned = abs((math.degrees(t.yaw) - yaw_deg + 180) % 360 - 180) < 0.01
        still = math.hypot(*(t.velocity or (1.0, 0.0, 0.0))) < 0.005
        return t.distance_to(target) < 0.01 and still and turned

    tel = link.wait_for(there, 10.0)
    assert tel is not None, link.telemetry()
    return tel


def test_the_mount_follows_position_and_yaw() -> None:
    clock = ManualClock()
    link = _flying(clock)
    mount = CameraMount(offset_m=(0.2, 0.05, 0.1), pitch_deg=-10.0)
    for yaw_deg, target in (
        (0.0, (0.0, 0.0, -2.5)),
        (90.0, (1.0, -2.0, -3.0)),
        (-135.0, (0.5, 0.5, -2.0)),
    ):
        assert link.goto_local(*target, yaw=math.radians(yaw_deg)).ok
        tel = _settle(link, target, yaw_deg)
        assert tel.position is not None
        cam = mount.camera_for(tel, HOME)
        assert cam is not None
        # The lens sits at the offset, turned with the vehicle's heading (gimbal: level).
        body = rotation_zyx(tel.yaw, 0.0, 0.0)
        want = np.asarray(HOME) + np.asarray(tel.position) + body @ np.asarray(mount.offset_m)
        np.testing.assert_allclose(cam.position, want, atol=1e-9)
        lens = np.add(HOME[:2], target[:2]) + body[:2] @ np.asarray(mount.offset_m)
        np.testing.assert_allclose(cam.position[:2], lens, atol=0.02)
        assert (cam.yaw_deg - yaw_deg + 180) % 360 - 180 == pytest.approx(0.0, abs=0.01)
        assert cam.pitch_deg == pytest.approx(-10.0) and cam.roll_deg == pytest.approx(0.0)


def test_a_fixed_mount_tilts_with_the_airframe() -> None:
    clock = ManualClock()
    link = _flying(clock)
    assert link.goto_local(10.0, 0.0, -2.5).ok
    clock.advance(0.3)  # accelerating north: the nose pitches down
    tel = link.telemetry()
    assert tel is not None and tel.attitude is not None and tel.attitude[1] < -0.1
    fixed = CameraMount(pitch_deg=-10.0, gimbal=False).camera_for(tel, HOME)
    level = CameraMount(pitch_deg=-10.0).camera_for(tel, HOME)
    assert fixed is not None and level is not None
    assert level.pitch_deg == pytest.approx(-10.0)
    assert fixed.pitch_deg == pytest.approx(-10.0 + math.degrees(tel.attitude[1]), abs=1e-6)


def test_no_position_no_camera() -> None:
    tel = Telemetry(received=0.0, system_id=1, autopilot="ardupilot", mode="GUIDED", armed=False,
                    landed="on_ground")  # fmt: skip
    assert CameraMount().camera_for(tel, HOME) is None


def test_what_the_camera_sees_follows_the_vehicle() -> None:
    """Climbing takes the operator's feet out of a camera pitched 8 degrees down (the
    closed-loop handover); turning away loses the operator altogether."""
    scene = build_scene(SceneConfig(operator=OperatorConfig(script="hover:3")), "mount-test")
    clock = ManualClock()
    link = _flying(clock, 2.5)
    mount = CameraMount(pitch_deg=-8.0)

    def sight() -> Sight:
        tel = link.telemetry()
        assert tel is not None
        return scene.view(mount.camera_for(tel, HOME), 45).operator_sight

    assert sight() == Sight.FULL
    assert link.goto_local(0.0, 0.0, -3.5).ok
    _settle(link, (0.0, 0.0, -3.5))
    assert sight() == Sight.PARTIAL
    view = scene.view(mount.camera_for(link.telemetry(), HOME), 45)  # type: ignore[arg-type]
    feet = view.people[0].pose.visibility[27:33]  # type: ignore[union-attr]
    assert feet.max() < 0.2  # below the image's lower edge
    assert link.goto_local(0.0, 0.0, -3.5, yaw=math.radians(90)).ok
    _settle(link, (0.0, 0.0, -3.5), 90.0)
    assert sight() == Sight.NONE  # looking east, past the operator
