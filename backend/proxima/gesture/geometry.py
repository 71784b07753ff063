"""Coordinate frames for landmarks: normalised image coordinates -> a metric-consistent
frame (x, y, z share one scale), and rotations in it.

MediaPipe normalises x by the image width and y by its height; on a 16:9 video a step of
0.1 in x is 1.78 times longer than 0.1 in y. Rotating such coordinates shears the body,
so every rotation here happens after `to_metric`.
"""

from __future__ import annotations

import numpy as np

from proxima.gesture.skeleton import L_HIP, L_SHOULDER, R_HIP, R_SHOULDER

# MediaPipe's z is documented as "roughly the scale of x", but on the LASER side views
# a shoulder line turned by its own z comes out 2.9 times the front view's width. With
# z scaled by 0.35 the turned width matches the front view (0.64 / 0.71 / 0.72 torso
# lengths for f / r / l) and the side views' yaw comes out at 73-78 degrees, near the 70
# that 2D foreshortening gives.
Z_SCALE = 0.35


def to_metric(xyz: np.ndarray, aspect: np.ndarray | float) -> np.ndarray:
    """(..., T, 33, 3) normalised -> same shape in units of the image height, y down, z
    away from the camera. `aspect` (width / height) is a scalar or one per leading index
    (e.g. (N,) for windows (N, T, 33, 3))."""
    a = np.asarray(aspect, np.float32)
    a = a.reshape(a.shape + (1,) * (xyz.ndim - a.ndim))
    out = xyz.astype(np.float32, copy=True)
    out[..., 0:1] *= a
    out[..., 2:3] *= a * Z_SCALE
    return out


def rotation_matrix(ax: float, ay: float, az: float) -> np.ndarray:
    """Rotation by angles (radians) about x, then y (vertical), then z (optical axis)."""
    cx, sx = np.cos(ax), np.sin(ax)
    cy, sy = np.cos(ay), np.sin(ay)
    cz, sz = np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return (rz @ ry @ rx).astype(np.float32)


def hip_centre(xyz: np.ndarray) -> np.ndarray:
    """(..., T, 33, 3) -> (..., T, 1, 3): midpoint of the hips per frame."""
    return (xyz[..., L_HIP : L_HIP + 1, :] + xyz[..., R_HIP : R_HIP + 1, :]) / 2


def torso_length(xyz: np.ndarray) -> np.ndarray:
    """(..., T, 33, 3) -> (..., 1, 1, 1): median over the window of the distance from the
    hips' midpoint to the shoulders' midpoint (unchanged by any turn of the camera,
    unlike the shoulder width)."""
    sh = (xyz[..., L_SHOULDER, :] + xyz[..., R_SHOULDER, :]) / 2
    hp = (xyz[..., L_HIP, :] + xyz[..., R_HIP, :]) / 2
    length = np.linalg.norm(sh - hp, axis=-1)  # (..., T)
    return np.maximum(np.median(length, axis=-1), 1e-3)[..., None, None, None]


def facing_yaw(xyz: np.ndarray) -> np.ndarray:
    """(..., T, 33, 3) metric -> (...,) yaw angle (radians) that turns the body's
    left-right axis (shoulders and hips, summed over the window) onto +x, i.e. makes
    the operator face the camera."""
    axis = (
        xyz[..., L_SHOULDER, :] - xyz[..., R_SHOULDER, :] + xyz[..., L_HIP, :] - xyz[..., R_HIP, :]
    ).sum(axis=-2)  # (..., 3)
    return np.arctan2(axis[..., 2], axis[..., 0])
