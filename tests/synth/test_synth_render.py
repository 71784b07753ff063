"""The rendered synthetic operator: ray hits at known points, MediaPipe finding the
rendered person where the geometry puts it, and `proxima synth --seen-by mediapipe`."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.laser import load_laser_csv
from proxima.gesture.skeleton import MIRROR
from proxima.pose import PoseEstimator
from proxima.synth.anthropometry import nominal_body
from proxima.synth.body import Placement, Stance, world_landmarks
from proxima.synth.dataset import load_synth_dir
from proxima.synth.motion import IDLE_LABEL, draw_gesture, perform
from proxima.synth.pose_model import match_sides
from proxima.synth.projection import ImageLandmarks, project_landmarks
from proxima.synth.render import Renderer, hit_capsule, hit_ellipsoid, sample_look
from proxima.synth.views import orbit_camera


def test_rays_hit_a_capsule_and_an_ellipsoid_where_geometry_says() -> None:
    origin = np.array([5.0, 0.0, 0.5])
    rays = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-0.8, 0.0, 0.6]])
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    t, n = hit_capsule(origin, rays, np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.2)
    assert abs(t[0] - 4.8) < 1e-9  # the side, square on
    assert np.allclose(n[0], [1, 0, 0])
    assert np.isinf(t[1])  # parallel to the axis, beside it: a miss
    assert np.isinf(t[2])  # rises 0.6 per 0.8 across: 4.25 m up by the axis
    radii = np.array([0.3, 0.1, 0.2])
    t, n = hit_ellipsoid(origin, rays[:1], np.array([0.0, 0.0, 0.5]), np.eye(3), radii)
    assert abs(t[0] - 4.7) < 1e-9 and np.allclose(n[0], [1, 0, 0])


def _scene(azimuth: float) -> tuple[np.ndarray, object, object]:
    rng = np.random.default_rng(3)
    body = nominal_body()
    placement = Placement(heading_deg=0.0)
    steps = [draw_gesture(IDLE_LABEL, rng, duration_s=0.3), draw_gesture("move_to_left", rng)]
    world = world_landmarks(body, perform(steps, rng).posture, placement, Stance())
    cam = orbit_camera(placement, 0.55 * body.stature, azimuth, 8.0, 4.0, hfov_deg=65.0)
    return world, body, cam


def test_mediapipe_finds_the_rendered_operator_where_the_projection_puts_it() -> None:
    world, body, cam = _scene(0.0)
    rng = np.random.default_rng(0)
    renderer = Renderer(cam, sample_look(rng), float(world[:, 27:33, 2].max()) + 0.02)
    truth = project_landmarks(world, cam, body).xyz
    errors = []
    with PoseEstimator(num_poses=1) as est:
        for t in range(0, 30):
            image = renderer.frame(world[t], body, rng)
            assert image.shape == (360, 640, 3) and image.dtype == np.uint8
            poses = est.estimate(cv2.cvtColor(image, cv2.COLOR_RGB2BGR), t / 30)
            assert len(poses) == 1, f"frame {t}: MediaPipe found {len(poses)} people"
            errors.append(np.linalg.norm(poses[0].xyz[:, :2] - truth[t, :, :2], axis=-1))
    err = np.median(np.array(errors), axis=0)
    # Shoulders and hips within 3 % of the frame; the operator's left is the image's right.
    assert err[[11, 12, 23, 24]].max() < 0.03, err[[11, 12, 23, 24]]
    assert poses[0].xyz[11, 0] > poses[0].xyz[12, 0]


def test_synth_seen_by_mediapipe_writes_clips_the_loader_reads(tmp_path: Path) -> None:
    def args(out: Path, seen_by: str) -> list[str]:
        return ["synth", "--out", str(out), "--clips", "2", "--seed", "4",
                "--seen-by", seen_by, "--max-frames", "12", "--render-width", "480",
                "--views", "left:-80..-70:5..10"]  # fmt: skip

    out = tmp_path / "rendered"
    result = CliRunner().invoke(app, [*args(out, "mediapipe"), "--sides", "exact"])
    assert result.exit_code == 0, result.output
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["seen_by"] == "mediapipe:pose_landmarker_full.task@480px,sides=exact"
    assert [e["frames"] for e in manifest["clip_list"]] == [12, 12]
    clips = load_synth_dir(out)
    assert [c.gesture for c in clips] == ["all_clear", "have_command"]
    first = load_laser_csv(out / manifest["clip_list"][0]["file"])
    assert 0 < len(first) <= 12 and first.view == "l"
    # The same seed seen by geometry: the same people and cameras, so MediaPipe's
    # shoulders lie near the exact ones, but not on them.
    exact = tmp_path / "exact"
    assert CliRunner().invoke(app, args(exact, "geometry")).exit_code == 0
    truth = load_laser_csv(exact / manifest["clip_list"][0]["file"])
    common = np.intersect1d(first.frames, truth.frames)
    a = first.xyz[np.isin(first.frames, common)][:, [11, 12], :2]
    b = truth.xyz[np.isin(truth.frames, common)][:, [11, 12], :2]
    assert len(common) > 0 and 0 < np.median(np.abs(a - b)) < 0.05
    bad = CliRunner().invoke(app, ["synth", "--out", str(tmp_path / "x"), "--seen-by", "eyes"])
    assert bad.exit_code == 2 and "expected 'geometry' or 'mediapipe'" in bad.output
    bad = CliRunner().invoke(
        app, ["synth", "--out", str(tmp_path / "y"), "--seen-by", "mediapipe", "--sides", "l"]
    )
    assert bad.exit_code == 2 and "expected 'exact' or 'mediapipe'" in bad.output


def test_match_sides_relabels_the_frames_read_as_facing_away(laser_dir: Path) -> None:
    rng = np.random.default_rng(0)

    def landmarks(xyz: np.ndarray, vis: np.ndarray) -> ImageLandmarks:
        return ImageLandmarks(xyz, vis, np.ones(len(xyz), bool), 1920, 1080)

    for name, view in (("DJI_0164_move_to_left_f", "f"), ("DJI_0166_move_to_left_l", "l")):
        clip = load_laser_csv(laser_dir / f"{name}.MP4.csv")
        xyz, vis = clip.xyz[:90], clip.visibility[:90]
        # The exact projection stands in as the real pose plus pose-model jitter.
        exact = landmarks(xyz + rng.normal(0, 0.005, xyz.shape), vis)
        _, swapped = match_sides(landmarks(xyz, vis), exact)
        assert not swapped.any(), f"{view}: {swapped.sum()} frames swapped that were not"
        seen_xyz = xyz.copy()
        seen_xyz[30:50] = xyz[30:50][:, MIRROR]  # read as facing away
        fixed, swapped = match_sides(landmarks(seen_xyz, vis), exact)
        if view == "f":  # left and right lie apart: every swapped frame found, no other
            assert np.flatnonzero(swapped).tolist() == list(range(30, 50))
            assert np.array_equal(fixed.xyz, xyz)
        else:  # a side view: both arms project close, so only clear swaps are undone
            assert not swapped[:30].any() and not swapped[50:].any()
            assert np.array_equal(fixed.xyz[swapped], xyz[swapped])
    with pytest.raises(ValueError, match="differ in shape"):
        match_sides(landmarks(xyz, vis), landmarks(xyz[:10], vis[:10]))
