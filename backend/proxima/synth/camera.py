"""A virtual pinhole camera in the world (local NED) and MediaPipe's image conventions.

Pose: `position` in NED metres; `yaw_deg` the heading the lens points to (clockwise from
north), `pitch_deg` up positive (a drone camera looking down has a negative pitch),
`roll_deg` right side down positive: the aerospace Z-Y-X order MAVLink attitudes use, so
a camera mounted on a simulated vehicle composes with the vehicle's (roll, pitch, yaw).
Intrinsics: horizontal field of view and resolution, square pixels, principal point at
the image centre, no distortion.

`project` gives pixel-normalised coordinates as MediaPipe reports them: x and y in 0..1
across the image (y down; points outside the image fall outside 0..1), and for landmarks
`mediapipe_z` gives depth relative to the hips' midpoint in x's scale (smaller = nearer).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

# Camera body axes (forward, right, down) -> optical axes (x right, y down, z forward).
_BODY_TO_OPTICAL = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def rotation_zyx(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Body-to-world rotation of aerospace angles (radians): yaw about down, then pitch
    about the new right axis, then roll about the new forward axis."""
    cy, sy = np.cos(yaw), np.sin(yaw)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cr, sr = np.cos(roll), np.sin(roll)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


@dataclass(frozen=True)
class Camera:
    """A pinhole camera; see the module docstring for its conventions."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    hfov_deg: float = 70.0
    width: int = 1920
    height: int = 1080

    def __post_init__(self) -> None:
        if not 1.0 <= self.hfov_deg <= 179.0:
            raise ValueError(f"hfov_deg must be in 1..179 degrees, got {self.hfov_deg}")
        if self.width < 1 or self.height < 1:
            raise ValueError(f"resolution must be positive, got {self.width}x{self.height}")

    @property
    def aspect(self) -> float:
        return self.width / self.height

    @property
    def focal_px(self) -> float:
        """Focal length in pixels (the same for x and y: square pixels)."""
        return self.width / 2 / np.tan(np.deg2rad(self.hfov_deg) / 2)

    @property
    def vfov_deg(self) -> float:
        return float(np.rad2deg(2 * np.arctan(self.height / 2 / self.focal_px)))

    def world_to_camera(self) -> np.ndarray:
        """(3, 3) rotation taking world (NED) vectors to optical (right, down, forward)."""
        r = rotation_zyx(*np.deg2rad([self.yaw_deg, self.pitch_deg, self.roll_deg]))
        return _BODY_TO_OPTICAL @ r.T

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) -> optical frame (..., 3): x right, y down, z forward (m)."""
        rel = np.asarray(points, np.float64) - np.asarray(self.position, np.float64)
        return rel @ self.world_to_camera().T

    def project(self, points: np.ndarray, near: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
        """World points (..., 3) -> (normalised image xy (..., 2), depth (...,) in metres
        along the optical axis). Points nearer than `near` (or behind the camera) have no
        image position: their xy is projected as if they were `near` metres ahead, so it
        stays finite, and the caller must treat them as unseen (depth tells which)."""
        c = self.to_camera(points)
        depth = c[..., 2]
        z = np.maximum(depth, near)
        f = self.focal_px
        x = (self.width / 2 + f * c[..., 0] / z) / self.width
        y = (self.height / 2 + f * c[..., 1] / z) / self.height
        return np.stack([x, y], axis=-1), depth

    def pixel(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) -> pixel coordinates (..., 2) (continuous: (0, 0) is the
        image's top-left corner, (width, height) its bottom-right)."""
        xy, _ = self.project(points)
        return xy * np.array([self.width, self.height])

    def to_dict(self) -> dict[str, object]:
        d = asdict(self)
        d["position"] = [round(float(v), 4) for v in self.position]
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in d.items()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Camera:
        d = dict(d)
        d["position"] = tuple(d["position"])
        return cls(**d)

    @classmethod
    def looking_at(
        cls,
        position: np.ndarray | tuple[float, float, float],
        target: np.ndarray | tuple[float, float, float],
        roll_deg: float = 0.0,
        hfov_deg: float = 70.0,
        width: int = 1920,
        height: int = 1080,
    ) -> Camera:
        """A camera at `position` whose optical axis passes through `target` (both NED).

        Raises:
            ValueError: position and target coincide.
        """
        d = np.asarray(target, np.float64) - np.asarray(position, np.float64)
        horiz = float(np.hypot(d[0], d[1]))
        if horiz == 0 and d[2] == 0:
            raise ValueError("camera position and target coincide")
        yaw = float(np.rad2deg(np.arctan2(d[1], d[0]))) if horiz > 0 else 0.0
        pitch = float(np.rad2deg(np.arctan2(-d[2], horiz)))
        p = np.asarray(position, np.float64)
        pos = (float(p[0]), float(p[1]), float(p[2]))
        return cls(pos, yaw, pitch, roll_deg, hfov_deg, width, height)


def mediapipe_z(
    depth: np.ndarray, hip_depth: np.ndarray, camera: Camera, gain: float | np.ndarray = 1.0
) -> np.ndarray:
    """MediaPipe's z for landmarks at `depth` (..., 33) metres: the depth relative to the
    hips' midpoint (`hip_depth` (..., 1)), in the units of normalised x (a metre at the
    hips' depth spans focal / (hip_depth * width) of the image width), times `gain`."""
    scale = camera.focal_px / (np.maximum(hip_depth, 1e-3) * camera.width)
    return gain * (depth - hip_depth) * scale
