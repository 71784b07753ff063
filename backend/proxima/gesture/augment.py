"""Training-time augmentation, applied to metric coordinates (see geometry.py).

- The paper's rotation: -15..15 degrees about x, y and z, about the hips' centre.
- Yaw (rotation about the vertical axis) by a wider angle to imitate other camera views;
  only for windows with depth (LASER), since turning a flat 2D skeleton is meaningless.
- Time warp: each window replayed at a random speed (1 +- `max_change`) about its
  centre, with a small random shift, by linear interpolation between frames; frames
  that would fall outside the window repeat its edge. Operators repeat a gesture at
  their own pace, and the test part of a clip is often slower or faster than the start.
- Left-right mirroring: x -> -x with each landmark swapped for its twin. Mirroring turns
  the operator's left arm into the right one, so the labels that name a side swap:
  move_to_left <-> move_to_right. The right-handed gestures (all_clear, have_command,
  not_clear) become their left-handed performance and keep their labels; every other
  gesture is symmetric or keeps its meaning.
"""

from __future__ import annotations

import numpy as np

from proxima.gesture.geometry import hip_centre, rotation_matrix
from proxima.gesture.skeleton import MIRROR
from proxima.types import GESTURES

MIRROR_LABEL = np.arange(len(GESTURES))
_L, _R = GESTURES.index("move_to_left"), GESTURES.index("move_to_right")
MIRROR_LABEL[_L], MIRROR_LABEL[_R] = _R, _L


def mirror(metric: np.ndarray, labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mirror windows (N, W, 33, 3) left-right and map their labels accordingly."""
    centre = hip_centre(metric)
    out = metric[:, :, MIRROR, :].copy()
    out[..., 0] = 2 * centre[..., 0] - out[..., 0]
    return out, MIRROR_LABEL[labels]


def time_warp(metric: np.ndarray, rng: np.random.Generator, max_change: float = 0.2) -> np.ndarray:
    """Resample each window (N, W, ...) at a random speed in [1 - max_change,
    1 + max_change] about its centre, shifted by up to 10% of the window."""
    n, w = metric.shape[:2]
    speed = rng.uniform(1 - max_change, 1 + max_change, size=(n, 1))
    shift = rng.uniform(-0.1, 0.1, size=(n, 1)) * w
    t = np.clip((np.arange(w) - w / 2) * speed + w / 2 + shift, 0, w - 1)
    lo = np.floor(t).astype(np.int64)
    hi = np.minimum(lo + 1, w - 1)
    frac = (t - lo).reshape(n, w, *([1] * (metric.ndim - 2)))
    rows = np.arange(n)[:, None]
    return metric[rows, lo] * (1 - frac) + metric[rows, hi] * frac


def rotate(
    metric: np.ndarray,
    rng: np.random.Generator,
    max_deg: float = 15.0,
    max_yaw_deg: float = 0.0,
    has_z: np.ndarray | None = None,
) -> np.ndarray:
    """Rotate each window by random angles about its hips' centre: uniform in
    +-max_deg about x, y, z, plus uniform +-max_yaw_deg extra yaw where `has_z`."""
    n = len(metric)
    angles = np.deg2rad(rng.uniform(-max_deg, max_deg, size=(n, 3)))
    if max_yaw_deg:
        extra = np.deg2rad(rng.uniform(-max_yaw_deg, max_yaw_deg, size=n))
        angles[:, 1] += extra if has_z is None else np.where(has_z, extra, 0.0)
    rot = np.stack([rotation_matrix(*a) for a in angles])  # (N, 3, 3)
    centre = hip_centre(metric).mean(axis=1, keepdims=True)  # (N, 1, 1, 3)
    return np.einsum("nwjc,nkc->nwjk", metric - centre, rot) + centre
