"""What the live pose path adds to a simulated camera's clean landmarks, frame by frame.

The capture model (`proxima.gesture.capture`, docs/capture.md) measured the live pose
path's jitter against the person's size in the frame and each landmark's visibility,
and the frame-to-frame noise of the visibility itself. A simulated camera knows the
person's real size in its own image, so these two effects (the capture model's effects
6 and 7) are applied here per frame, with the same measured curves; the geometric
effects the capture model imitates for recordings (distance, elevation, yaw, roll,
parts leaving the frame) are not imitated here: the simulated camera produces them.
The jitter is white from frame to frame (the measured lag-1 correlation, 0.05 pooled, is
taken as 0, as the capture model's default).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from proxima.gesture.capture import measured
from proxima.gesture.geometry import Z_SCALE


@dataclass(frozen=True)
class CaptureNoise:
    """`jitter` and `visibility_noise` as multiples of the measured live-path values
    (the capture model's parameters of the same names and ranges; 0 turns one off);
    `depth_jitter` scales the measured ratio of z's jitter to x and y's (`Z_OVER_XY`, 23
    in the metric frame), so depth noise can be studied apart (docs/sim.md: it decides
    whether a side camera reads the gestures at all).

    Raises:
        ValueError: (constructor) a value outside 0..8 (jitter, depth_jitter) or 0..4
            (visibility).
    """

    jitter: float = 1.0
    visibility_noise: float = 1.0
    depth_jitter: float = 1.0

    def __post_init__(self) -> None:
        if not 0.0 <= self.jitter <= 8.0:
            raise ValueError(f"jitter must lie in 0..8 (x the measured), got {self.jitter}")
        if not 0.0 <= self.depth_jitter <= 8.0:
            raise ValueError(f"depth_jitter must lie in 0..8, got {self.depth_jitter}")
        if not 0.0 <= self.visibility_noise <= 4.0:
            raise ValueError(
                f"visibility_noise must lie in 0..4 (x the measured), got {self.visibility_noise}"
            )

    @property
    def off(self) -> bool:
        return self.jitter == 0 and self.visibility_noise == 0

    def apply(
        self, xyz: np.ndarray, visibility: np.ndarray, aspect: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """One person's landmarks, (..., 33, 3) normalised and (..., 33) (one frame or
        several), with the live path's jitter (std by the person's height in the image
        in each frame and each landmark's visibility; z `Z_OVER_XY` times more, as
        measured) and visibility noise; fresh draws for every frame."""
        if self.off:
            return xyz, visibility
        scale = np.array([aspect, 1.0, aspect * Z_SCALE])
        m = np.asarray(xyz, np.float64) * scale  # metric: image-height units
        vis = np.asarray(visibility, np.float64)
        d = (m[..., 11, :2] + m[..., 12, :2] - m[..., 23, :2] - m[..., 24, :2]) / 2
        torso = np.maximum(np.linalg.norm(d, axis=-1), 1e-3)[..., None]  # (..., 1)
        if self.jitter > 0:
            height = measured.STATURE_TORSO * torso
            sd = self.jitter * measured.jitter_torso(height) * torso
            sd_j = sd * measured.visibility_factor(vis)  # (..., 33)
            e = rng.standard_normal(m.shape)
            m[..., :2] += sd_j[..., None] * e[..., :2]
            m[..., 2] += self.depth_jitter * measured.Z_OVER_XY * sd_j * e[..., 2]
        if self.visibility_noise > 0:
            noise = self.visibility_noise * measured.visibility_noise_sd(vis)
            vis = np.clip(vis + noise * rng.standard_normal(vis.shape), 0.0, 1.0)
        return (m / scale).astype(np.float32), vis.astype(np.float32)
