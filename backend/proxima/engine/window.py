"""The sliding window of the operator's last poses that the classifier sees."""

from __future__ import annotations

from collections import deque

import numpy as np

from proxima.types import Pose


class PoseWindow:
    """The last `size` poses of one stream, and when to classify them.

    A pause longer than `max_gap_s` between poses (nobody detected, the operator changed)
    empties the window, as training windows never bridge long gaps. `due()` is true once
    the window is full and `stride` poses came since the last classification.
    """

    def __init__(self, size: int = 60, stride: int = 5, max_gap_s: float = 0.25) -> None:
        if size < 1 or stride < 1:
            raise ValueError(f"window size and stride must be >= 1, got {size}, {stride}")
        self.size = size
        self.stride = stride
        self.max_gap_s = max_gap_s
        self._xyz: deque[np.ndarray] = deque(maxlen=size)
        self._vis: deque[np.ndarray] = deque(maxlen=size)
        self._last_t: float | None = None
        self._since = 0  # poses since the last classification
        self.restarts = 0

    def __len__(self) -> int:
        return len(self._xyz)

    def clear(self) -> None:
        """Forget every pose (the next classification waits for a full window)."""
        self._xyz.clear()
        self._vis.clear()
        self._last_t = None
        self._since = 0

    def push(self, pose: Pose) -> bool:
        """Add the operator's pose; return True if a gap made the window restart."""
        restarted = False
        if self._last_t is not None and pose.t - self._last_t > self.max_gap_s + 1e-9:
            self.clear()
            self.restarts += 1
            restarted = True
        self._xyz.append(pose.xyz)
        self._vis.append(pose.visibility)
        self._last_t = pose.t
        self._since += 1
        return restarted

    def due(self) -> bool:
        """Whether to classify now."""
        return len(self._xyz) == self.size and self._since >= self.stride

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        """The window as xyz (1, size, 33, 3) float32 and visibility (1, size, 33); marks
        it classified."""
        self._since = 0
        xyz = np.stack(self._xyz).astype(np.float32, copy=False)[None]
        vis = np.stack(self._vis).astype(np.float32, copy=False)[None]
        return xyz, vis
