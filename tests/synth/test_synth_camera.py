"""The pinhole camera: known points land on the pixels they must, MediaPipe's z and
visibility, points behind the camera."""

from __future__ import annotations

import numpy as np
import pytest

from proxima.synth.anthropometry import nominal_body
from proxima.synth.body import Placement, Posture, world_landmarks
from proxima.synth.camera import Camera, mediapipe_z
from proxima.synth.gestures import IDLE, SPECS
from proxima.synth.projection import project_landmarks
from proxima.synth.views import orbit_camera


def _half_tangents(cam: Camera) -> tuple[float, float]:
    return cam.width / 2 / cam.focal_px, cam.height / 2 / cam.focal_px


def test_centre_and_corners_of_a_level_camera() -> None:
    cam = Camera(position=(0.0, 0.0, -1.5), hfov_deg=90.0, width=1920, height=1080)
    tx, ty = _half_tangents(cam)
    assert tx == pytest.approx(1.0)  # 90 degrees across
    d = 5.0
    ahead = np.array([d, 0.0, -1.5])  # 5 m north, at the camera's height
    np.testing.assert_allclose(cam.pixel(ahead), [960.0, 540.0], atol=1e-9)
    # North-east-down: east is the image's right, down its bottom.
    corners = {(1920, 1080): (d * tx, d * ty), (0, 0): (-d * tx, -d * ty),
               (1920, 0): (d * tx, -d * ty), (0, 1080): (-d * tx, d * ty)}  # fmt: skip
    for (u, v), (east, down) in corners.items():
        p = np.array([d, east, -1.5 + down])
        np.testing.assert_allclose(cam.pixel(p), [u, v], atol=1e-6)
    xy, depth = cam.project(np.array([[d, d * tx, -1.5], [d, 0.0, -1.5 - d * ty / 2]]))
    np.testing.assert_allclose(xy, [[1.0, 0.5], [0.5, 0.25]], atol=1e-9)
    np.testing.assert_allclose(depth, [d, d])


def test_a_known_point_through_a_turned_and_tilted_camera() -> None:
    """A camera 3 m up, facing east and tilted 30 degrees down, sees the ground point
    3 / tan(30 deg) m east of it at the image centre; a point 1 m further north (the
    camera's left) lands focal / depth pixels left of centre."""
    cam = Camera(position=(2.0, 1.0, -3.0), yaw_deg=90.0, pitch_deg=-30.0, hfov_deg=60.0)
    run = 3.0 / np.tan(np.deg2rad(30.0))
    target = np.array([2.0, 1.0 + run, 0.0])
    np.testing.assert_allclose(cam.pixel(target), [960.0, 540.0], atol=1e-6)
    depth = float(np.hypot(run, 3.0))
    left = cam.pixel(target + np.array([1.0, 0.0, 0.0]))
    assert left[0] == pytest.approx(960.0 - cam.focal_px / depth, rel=1e-9)
    assert left[1] == pytest.approx(540.0, abs=1e-6)


def test_roll_turns_the_image() -> None:
    """Rolled 90 degrees right side down, a point to the camera's right (east) appears
    above the image centre."""
    cam = Camera(position=(0.0, 0.0, -1.0), roll_deg=90.0, hfov_deg=70.0)
    u, v = cam.pixel(np.array([4.0, 1.0, -1.0]))
    assert u == pytest.approx(960.0, abs=1e-6)
    assert v == pytest.approx(540.0 - cam.focal_px / 4.0, rel=1e-9)


def test_looking_at_centres_the_target() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        pos, target = rng.uniform(-10, 10, size=(2, 3))
        cam = Camera.looking_at(pos, target, roll_deg=float(rng.uniform(-20, 20)), hfov_deg=50.0)
        np.testing.assert_allclose(cam.pixel(target), [960.0, 540.0], atol=1e-6)
    with pytest.raises(ValueError, match="coincide"):
        Camera.looking_at((1, 2, 3), (1, 2, 3))


def test_points_behind_the_camera_are_unseen() -> None:
    cam = Camera(position=(0.0, 0.0, -1.0))
    xy, depth = cam.project(np.array([[-3.0, 0.5, -1.0], [0.0, 1.0, -1.0]]))
    assert depth[0] < 0 and depth[1] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.isfinite(xy))
    # A body behind the camera: nothing visible, the person not detected.
    body = nominal_body()
    world = world_landmarks(body, Posture.standing(3, IDLE), Placement(north=-4.0))
    seen = project_landmarks(world, cam, body)
    assert not seen.detected.any()
    assert np.all(seen.visibility == 0.0)


def test_mediapipe_z_and_the_frame_edges() -> None:
    body = nominal_body()
    world = world_landmarks(body, Posture.standing(1, SPECS["hover"].right.rest), Placement())
    cam = orbit_camera(Placement(), 0.55 * body.stature, 0.0, 0.0, 4.0)
    seen = project_landmarks(world, cam, body, z_gain=1.0)
    hips = seen.xyz[0, [23, 24], 2]
    assert abs(hips.mean()) < 1e-6  # z is relative to the hips' midpoint
    # A point 1 m nearer than the hips: -1 m in units of the image width at the hips' depth.
    d_hip = float(np.mean(cam.to_camera(world[0, [23, 24]])[:, 2]))
    z = mediapipe_z(np.array([d_hip - 1.0]), np.array([d_hip]), cam, 1.0)
    assert z[0] == pytest.approx(-cam.focal_px / (d_hip * cam.width))
    assert seen.detected[0] and np.all(seen.visibility[0] > 0.9)
    # Turned so the operator is at the image's right edge: half the body out of frame.
    aside = Camera(cam.position, cam.yaw_deg - cam.hfov_deg / 2, cam.pitch_deg, 0.0,
                   cam.hfov_deg)  # fmt: skip
    part = project_landmarks(world, aside, body)
    x, vis = part.xyz[0, :, 0], part.visibility[0]
    assert np.any(x > 1.1) and np.all(vis[x > 1.1] < 0.15)  # well outside: faded
    assert np.all(vis[x < 1.0] > 0.9)  # inside: as before


def test_the_torso_hides_the_far_arm_in_profile() -> None:
    body = nominal_body()
    world = world_landmarks(body, Posture.standing(1, IDLE), Placement())
    side = orbit_camera(Placement(), 0.55 * body.stature, 90.0, 5.0, 4.0)  # the right side
    vis = project_landmarks(world, side, body).visibility[0]
    assert vis[14] > 0.9 and vis[16] > 0.9  # near (right) elbow and wrist
    assert vis[13] < 0.3 and vis[15] < 0.3  # far (left) elbow and wrist
    front = orbit_camera(Placement(), 0.55 * body.stature, 0.0, 5.0, 4.0)
    assert np.all(project_landmarks(world, front, body).visibility[0] > 0.9)
