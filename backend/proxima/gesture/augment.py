"""Training-time augmentation, applied to metric coordinates (see geometry.py).

- The paper's rotation: -15..15 degrees about x, y and z, about the hips' centre.
- Yaw (rotation about the vertical axis) by a wider angle to imitate other camera views;
  only for windows with depth (LASER), since turning a flat 2D skeleton is meaningless.
- Time warp: each window replayed at a random speed (1 +- `max_change`) about its
  centre, with a small random shift, by linear interpolation between frames; frames
  that would fall outside the window repeat its edge. Operators repeat a gesture at
  their own pace, and the test part of a clip is often slower or faster than the start.
- Transitions: a window replaced by the onset of its gesture as a live stream shows it,
  the end of another gesture of the same recording (same person and camera), a linear
  0.5 s move from its last pose, then the first half or more of this window; the label
  stays this window's. Training windows are otherwise always one gesture from edge to
  edge, while a live window at a gesture's start still holds the one before: seeing
  such windows lets the model name the new gesture sooner and with more confidence.
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


def transitions(
    metric: np.ndarray,
    labels: np.ndarray,
    scene: np.ndarray,
    rng: np.random.Generator,
    rate: float,
    transition: int = 15,
    min_share: float = 0.5,
) -> np.ndarray:
    """Replace a `rate` share of windows (N, W, ...) by a gesture onset: the last frames
    of a window of another gesture from the same scene, `transition` frames of linear
    move, then this window's first `min_share`..100% of frames. Labels are unchanged."""
    n, w = metric.shape[:2]
    out = metric.copy()
    by_scene = {s: np.flatnonzero(scene == s) for s in np.unique(scene)}
    for i in np.flatnonzero(rng.random(n) < rate):
        pool = by_scene[scene[i]]
        pool = pool[labels[pool] != labels[i]]
        if not len(pool):
            continue
        j = pool[rng.integers(len(pool))]
        new = int(rng.integers(round(min_share * w), w))
        move = min(transition, w - new)
        before = w - new - move
        frac = (np.arange(1, move + 1) / (move + 1)).reshape(-1, *([1] * (metric.ndim - 2)))
        src, dst = metric[j, -1], metric[i, 0]
        out[i, :before] = metric[j, w - before :]
        out[i, before : before + move] = src + frac * (dst - src)
        out[i, before + move :] = metric[i, :new]
    return out
