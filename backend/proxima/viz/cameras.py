"""What the 3D view draws for cameras and simulated people, as plain line segments in the
view's world frame (metres, x east, y north, z up), so it can be tested without viser:

- each drone's camera frustum, from the drone's position and heading and its mount
  (`proxima.sim.mount.CameraMount`, the `camera` of the drone's settings);
- a line of sight from each camera to the operator, coloured by how that drone's stream
  sees them (`Sight`: full, partial, none);
- the simulated scene's people (`proxima.sim`): the operator and the bystanders'
  skeletons where they really stand, at the newest frame a camera of the scene took.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from proxima.sim.scene import Scene
from proxima.synth.camera import Camera

SIGHT_COLORS: dict[str, tuple[int, int, int]] = {
    "full": (46, 160, 67),
    "partial": (240, 180, 41),
    "none": (160, 160, 160),
}
FRUSTUM_DEPTH_M = 2.0
SKELETON: tuple[tuple[int, int], ...] = (
    (11, 12),
    (11, 13),
    (13, 15),
    (12, 14),
    (14, 16),
    (11, 23),
    (12, 24),
    (23, 24),
    (23, 25),
    (25, 27),
    (24, 26),
    (26, 28),
    (27, 31),
    (28, 32),
    (27, 29),
    (28, 30),
    (0, 7),
    (0, 8),
    (7, 11),
    (8, 12),
    (15, 19),
    (16, 20),
)


def ned_to_enu(points: np.ndarray) -> np.ndarray:
    """Scene NED points (..., 3) in the view's frame (x east, y north, z up)."""
    p = np.asarray(points, np.float64)
    return np.stack([p[..., 1], p[..., 0], -p[..., 2]], axis=-1)


def frustum_corners(camera: Camera, depth: float = FRUSTUM_DEPTH_M) -> np.ndarray:
    """(5, 3) NED points: the camera centre and the image's corners `depth` m ahead
    (top-left, top-right, bottom-right, bottom-left)."""
    rot = camera.world_to_camera().T  # optical (x right, y down, z forward) -> NED
    hw = np.tan(np.deg2rad(camera.hfov_deg) / 2)
    hh = hw * camera.height / camera.width
    rays = np.array([[-hw, -hh, 1.0], [hw, -hh, 1.0], [hw, hh, 1.0], [-hw, hh, 1.0]])
    centre = np.asarray(camera.position, np.float64)
    return np.vstack([centre, centre + depth * rays @ rot.T])


def frustum_segments(camera: Camera, depth: float = FRUSTUM_DEPTH_M) -> np.ndarray:
    """The frustum as (8, 2, 3) segments in the view's frame: four edges from the centre,
    the far rectangle."""
    c = ned_to_enu(frustum_corners(camera, depth))
    segs = [(c[0], c[i]) for i in range(1, 5)] + [(c[i], c[i % 4 + 1]) for i in range(1, 5)]
    return np.asarray(segs, np.float32)


def sight_line(camera: Camera, target_enu: Sequence[float] | np.ndarray) -> np.ndarray:
    """(1, 2, 3): from the camera to the operator's point, in the view's frame."""
    start = ned_to_enu(np.asarray(camera.position))
    return np.asarray([[start, np.asarray(target_enu, np.float64)]], np.float32)


def skeleton_segments(world_ned: np.ndarray) -> np.ndarray:
    """One person's 33 landmarks (NED) as (K, 2, 3) segments in the view's frame."""
    p = ned_to_enu(world_ned)
    return np.asarray([[p[a], p[b]] for a, b in SKELETON], np.float32)


def scene_frame(scene: Scene) -> int | None:
    """The newest frame any camera of `scene` took (None before the first)."""
    views = scene.views()
    return max((v.k for v in views.values()), default=None)


def scene_people(scene: Scene) -> list[tuple[str, bool, np.ndarray]]:
    """(name, is the operator, skeleton segments) of everyone in the scene at its newest
    frame; empty before any camera looked."""
    k = scene_frame(scene)
    if k is None:
        return []
    return [(p.name, p.operator, skeleton_segments(w)) for p, w in scene.world(k)]


def operator_point(scene: Scene | None, fallback_enu: Sequence[float]) -> np.ndarray:
    """Where a line of sight ends: the simulated operator's chest at the scene's newest
    frame, else `fallback_enu` (the configured operator position, 1 m up)."""
    if scene is not None:
        k = scene_frame(scene)
        if k is not None:
            return ned_to_enu(scene.operator.chest(k))
    return np.asarray(fallback_enu, np.float64)
