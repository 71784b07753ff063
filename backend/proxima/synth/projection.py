"""The body's 3D landmarks seen through a `Camera`: MediaPipe-style image landmarks,
visibility and whether the person would be detected at all.

Visibility (0..1, as MediaPipe reports it) is the product of
- a base value per body part (MediaPipe's medians on the LASER front view: face and
  torso 0.99-1.0, arms 0.97-0.99, feet 0.96);
- occlusion: a limb point behind the torso (a box from just below the hips to the top
  of the shoulders, as deep as the chest) or behind another limb (capsules around upper
  arms, forearms, thighs and shanks; each point a ball of its own limb's radius) falls
  toward `OCCLUDED` (LASER side views: the far elbow 0.17-0.18, the far wrist 0.27-0.39,
  the far knee 0.41-0.56). Face and torso points are not
  occluded by the body, as MediaPipe reports them visible even in profile (0.95-1.0), but
  the face fades when the head faces away from the camera;
- the far side: MediaPipe reports limb points beyond the body's middle (in depth) as
  less visible even where nothing hides them (a far arm held out in front of the chest
  in a 70-degree view); such points fade by up to `FAR_SIDE` from 0.03 to 0.13 statures
  behind the torso's centre;
- the frame: points outside the image fade with their distance from its edge, points
  behind the camera are 0.

A frame counts as detected (MediaPipe found the person) when the shoulders' and the
hips' midpoints are in front of the camera and inside the image, the torso spans at
least `MIN_TORSO_PX` pixels, and at least 17 of the 33 landmarks are inside the image;
undetected frames carry no landmarks, as in the LASER recordings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from proxima.gesture.geometry import Z_SCALE
from proxima.synth.anthropometry import BodyShape
from proxima.synth.body import FACE, LIMBS, TORSO
from proxima.synth.camera import Camera, mediapipe_z

# MediaPipe's z on LASER is about 1 / Z_SCALE times the metric scale of x (geometry.py):
# synthetic z gets the same gain, so the feature pipelines (which turn the body by its z)
# treat it like the real one. (The limbs' ends come out deeper still in the real side
# views, 1.2-2 times the torso's gain; giving the synthetic limbs those gains made the
# real-data model agree less with the synthetic gestures, 0.89 against 0.92, so the gain
# is one for all landmarks: docs/synth.md.)
MEDIAPIPE_Z_GAIN = 1.0 / Z_SCALE
OCCLUDED = 0.12
FAR_SIDE = 0.85
MIN_TORSO_PX = 12.0
NEAR = 0.05

_BASE = np.full(33, 0.98)
_BASE[list(FACE)] = 0.995
_BASE[list(TORSO)] = 0.995
_BASE[17:23] = 0.96  # hand points
_BASE[27:33] = 0.96  # ankles and feet

# Limb points a capsule must not occlude: its own ends, and a forearm's hand points.
_OWN = {
    0: {11, 13},
    1: {13, 15, 17, 19, 21},
    2: {12, 14},
    3: {14, 16, 18, 20, 22},
    4: {23, 25},
    5: {25, 27, 29, 31},
    6: {24, 26},
    7: {26, 28, 30, 32},
}


@dataclass
class ImageLandmarks:
    """Landmarks as one camera sees them, T frames: `xyz` (T, 33, 3) normalised (x, y in
    0..1 of the image, z MediaPipe's depth), `visibility` (T, 33), `detected` (T,)."""

    xyz: np.ndarray
    visibility: np.ndarray
    detected: np.ndarray
    width: int
    height: int

    @property
    def aspect(self) -> float:
        return self.width / self.height


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def _box_cover(
    cam: np.ndarray, pts: np.ndarray, centre: np.ndarray, axes: np.ndarray, half: np.ndarray
) -> np.ndarray:
    """Length (T, N) of each camera->point ray inside an oriented box before the point.
    cam (3,), pts (T, N, 3), centre (T, 3), axes (T, 3, 3) rows, half (3,)."""
    o = np.einsum("tij,tj->ti", axes, cam - centre)[:, None, :]  # (T, 1, 3)
    d = np.einsum("tij,tnj->tni", axes, pts - cam)  # (T, N, 3), ray = o + s d, s in 0..1
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - o) / d
        t2 = (half - o) / d
    lo = np.where(
        np.abs(d) < 1e-12, np.where(np.abs(o) <= half, -np.inf, np.inf), np.minimum(t1, t2)
    )
    hi = np.where(
        np.abs(d) < 1e-12, np.where(np.abs(o) <= half, np.inf, -np.inf), np.maximum(t1, t2)
    )
    enter = np.clip(lo.max(axis=-1), 0.0, 1.0)
    leave = np.clip(hi.min(axis=-1), 0.0, 1.0)
    return np.maximum(leave - enter, 0.0) * np.linalg.norm(pts - cam, axis=-1)


def _capsule_cover(
    cam: np.ndarray, pts: np.ndarray, size: np.ndarray, a: np.ndarray, b: np.ndarray, radius: float
) -> np.ndarray:
    """How much (T, N, 0..1) of each point, a ball of radius `size` (N,), a capsule a-b
    (T, 3) of `radius` hides from the camera: 1 when the ray to the point passes within
    `radius` of the capsule's axis, fading to 0 at `radius + size`; only what lies before
    the point counts."""
    p0 = np.broadcast_to(cam, pts.shape)
    d1 = pts - p0  # ray direction (T, N, 3)
    d2 = (b - a)[:, None, :]
    r = p0 - a[:, None, :]
    aa = np.sum(d1 * d1, -1)
    ee = np.sum(d2 * d2, -1)
    ff = np.sum(d2 * r, -1)
    cc = np.sum(d1 * r, -1)
    bb = np.sum(d1 * d2, -1)
    denom = aa * ee - bb * bb
    s = np.where(denom > 1e-12, np.clip((bb * ff - cc * ee) / np.maximum(denom, 1e-12), 0, 1), 0.0)
    t = np.clip((bb * s + ff) / np.maximum(ee, 1e-12), 0, 1)
    s = np.clip((bb * t - cc) / np.maximum(aa, 1e-12), 0, 1)
    gap = np.linalg.norm(p0 + d1 * s[..., None] - (a[:, None, :] + d2 * t[..., None]), axis=-1)
    before = s < 1 - (radius + size) / np.maximum(np.sqrt(aa), 1e-9)
    return np.where(before, _smoothstep((radius + size - gap) / size), 0.0)


def _point_sizes(body: BodyShape) -> np.ndarray:
    """(33,) the radius of the limb each landmark sits on (how large a target it is)."""
    size = np.full(33, body.forearm_radius)
    size[[13, 14]] = body.upper_arm_radius
    size[17:23] = 0.6 * body.forearm_radius
    size[[25, 26]] = body.thigh_radius
    size[27:33] = body.shank_radius
    return size


def occlusion(world: np.ndarray, camera: Camera, body: BodyShape) -> np.ndarray:
    """(T, 33) in 0..1: how much of each landmark the body hides from the camera."""
    cam = np.asarray(camera.position, np.float64)
    T = len(world)
    cover = np.zeros((T, 33))
    limbs = np.array([i for i in range(33) if i not in FACE and i not in TORSO])
    size = _point_sizes(body)
    # The torso, a box from just below the hips to the top of the shoulders (above their
    # joints, where the landmarks sit), a little wider than the shoulder landmarks and as
    # deep as the chest.
    sh = (world[:, 11] + world[:, 12]) / 2
    hp = (world[:, 23] + world[:, 24]) / 2
    up = sh - hp
    length = np.linalg.norm(up, axis=-1, keepdims=True)
    up = up / length
    across = world[:, 11] - world[:, 12]
    left = across - np.sum(across * up, -1, keepdims=True) * up
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    axes = np.stack([np.cross(left, up), left, up], axis=1)
    bottom, top = 0.05 * body.stature, 0.035 * body.stature
    centre = hp + up * (length + top - bottom) / 2
    half = np.array(
        [
            body.torso_depth / 2,
            0.6 * body.shoulder_width,
            (float(np.median(length)) + top + bottom) / 2,
        ]
    )
    chord = _box_cover(cam, world[:, limbs], centre, axes, half)
    cover[:, limbs] = _smoothstep(chord / (0.5 * body.torso_depth))
    for k, (i, j, radius_name) in enumerate(LIMBS):
        idx = np.array([n for n in limbs if n not in _OWN[k]])
        c = _capsule_cover(
            cam, world[:, idx], size[idx], world[:, i], world[:, j], getattr(body, radius_name)
        )
        cover[:, idx] = np.maximum(cover[:, idx], c)
    return cover


def _face_turned_away(world: np.ndarray, camera: Camera) -> np.ndarray:
    """(T,) 0..1: 0 while the camera sees the face (up to 95 degrees off), 1 from 135."""
    ears = (world[:, 7] + world[:, 8]) / 2
    facing = world[:, 0] - ears
    to_cam = np.asarray(camera.position) - ears
    cos = np.sum(facing * to_cam, -1) / np.maximum(
        np.linalg.norm(facing, axis=-1) * np.linalg.norm(to_cam, axis=-1), 1e-9
    )
    angle = np.rad2deg(np.arccos(np.clip(cos, -1, 1)))
    return _smoothstep((angle - 95) / 40)


def _behind_torso(world: np.ndarray, camera: Camera) -> np.ndarray:
    """(T, 33) metres each landmark lies beyond the torso's centre, along the camera's
    line of sight taken across the body (its height along the body does not count, so a
    camera looking down does not put the feet "behind")."""
    centre = world[:, [11, 12, 23, 24]].mean(axis=1)
    up = (world[:, 11] + world[:, 12] - world[:, 23] - world[:, 24]) / 2
    up = up / np.linalg.norm(up, axis=-1, keepdims=True)
    sight = centre - np.asarray(camera.position)
    sight = sight - np.sum(sight * up, -1, keepdims=True) * up
    sight = sight / np.maximum(np.linalg.norm(sight, axis=-1, keepdims=True), 1e-9)
    return np.einsum("tjc,tc->tj", world - centre[:, None], sight)


def project_landmarks(
    world: np.ndarray,
    camera: Camera,
    body: BodyShape,
    z_gain: float | np.ndarray = MEDIAPIPE_Z_GAIN,
) -> ImageLandmarks:
    """World landmarks (T, 33, 3) (NED metres) -> what `camera` would report. `z_gain`
    (a number or one per landmark) scales the metric depth into MediaPipe's z."""
    xy, depth = camera.project(world, NEAR)
    hip_depth = (depth[:, 23:24] + depth[:, 24:25]) / 2
    z = mediapipe_z(depth, hip_depth, camera, z_gain)
    xyz = np.concatenate([xy, z[..., None]], axis=-1)

    outside = np.maximum.reduce(
        [-xy[..., 0], xy[..., 0] - 1, -xy[..., 1], xy[..., 1] - 1, 0 * xy[..., 0]]
    )
    in_frame = np.exp(-outside / 0.04)
    hidden = occlusion(world, camera, body)
    hidden[:, list(FACE)] = _face_turned_away(world, camera)[:, None]
    behind = _behind_torso(world, camera) - 0.03 * body.stature  # a heel is not "far"
    far = FAR_SIDE * _smoothstep(behind / (0.1 * body.stature))
    far[:, list(FACE) + list(TORSO)] = 0.0
    vis = _BASE * (1 - (1 - OCCLUDED) * hidden) * (1 - far) * in_frame
    vis = np.where(depth > NEAR, vis, 0.0)

    def inside(p: np.ndarray) -> np.ndarray:
        return np.all((p >= 0) & (p <= 1), axis=-1)

    mids = [(11, 12), (23, 24)]
    centre_ok = np.all(
        [
            inside((xy[:, a] + xy[:, b]) / 2) & (depth[:, a] > NEAR) & (depth[:, b] > NEAR)
            for a, b in mids
        ],
        axis=0,
    )
    torso_px = np.linalg.norm(
        ((xy[:, 11] + xy[:, 12]) - (xy[:, 23] + xy[:, 24])) / 2 * [camera.width, camera.height],
        axis=-1,
    )
    enough = np.sum(inside(xy) & (depth > NEAR), axis=-1) >= 17
    detected = centre_ok & (torso_px >= MIN_TORSO_PX) & enough
    return ImageLandmarks(
        xyz.astype(np.float32), vis.astype(np.float32), detected, camera.width, camera.height
    )
