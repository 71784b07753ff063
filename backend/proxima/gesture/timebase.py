"""Windows on the training clock: poses received at any rate, resampled to 30 per second.

A camera at 15 fps delivers a 30-pose window that spans 2 s, so a gesture in it moves
twice as fast as in the 30 fps recordings and the previous gesture stays in it twice as
long. Resampling the last (size - 1) / rate seconds onto `size` instants keeps the span
the model trained on. The live window (`proxima.engine.window`, clock `time`) and the
capture-noised training windows (`proxima.gesture.robust`) share this function.
"""

from __future__ import annotations

import numpy as np

RATE_HZ = 30.0  # the LASER recordings' rate, the instants windows are resampled to


def resample_windows(
    t: np.ndarray,
    xyz: np.ndarray,
    vis: np.ndarray | None,
    size: int,
    rate: float = RATE_HZ,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Poses at times `t` (N, M), increasing, as `size` poses `1 / rate` s apart ending at
    each row's newest pose: xyz (N, size, 33, 3), visibility (N, size, 33) or None.
    Linear interpolation between the received poses; an instant before the oldest one
    takes the oldest (callers give rows that cover the span).
    """
    t = np.asarray(t, np.float64)
    n, m = t.shape
    grid = t[:, -1:] - (size - 1 - np.arange(size))[None, :] / rate  # (N, size)
    # index of the first received pose at or after each instant (1..M-1)
    right = (t[:, None, :] < grid[:, :, None] - 1e-9).sum(axis=2)
    right = np.clip(right, 1, max(m - 1, 1)) if m > 1 else np.zeros_like(right)
    left = np.maximum(right - 1, 0)
    rows = np.arange(n)[:, None]
    t_l, t_r = t[rows, left], t[rows, right]
    w = np.clip((grid - t_l) / np.maximum(t_r - t_l, 1e-12), 0.0, 1.0)
    out_xyz = (1.0 - w)[..., None, None] * xyz[rows, left] + w[..., None, None] * xyz[rows, right]
    if vis is None:
        return out_xyz, None
    out_vis = (1.0 - w)[..., None] * vis[rows, left] + w[..., None] * vis[rows, right]
    return out_xyz, out_vis
