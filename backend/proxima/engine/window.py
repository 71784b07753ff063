"""The sliding window of the operator's last poses that the classifier sees."""

from __future__ import annotations

from collections import deque
from typing import Literal

import numpy as np

from proxima.gesture.capture.model import MAX_GAP_S, TRAIN_MAX_GAP_S
from proxima.gesture.timebase import RATE_HZ, resample_windows
from proxima.types import Pose

WindowClock = Literal["poses", "time"]
ClockSetting = Literal["model", "poses", "time"]
# The engine's default (`EngineSettings.window_clock`): the clock the model trained on.
# Models trained on the pose clock lose commands on the time clock (`body` in-sample
# `field` 84.4 % against 86.1 %; `body-smooth-z` held out 76.1 % against 79.9 %,
# docs/experiments.md "Thirty-third session" and "Thirty-fourth session").
DEFAULT_CLOCK: ClockSetting = "model"


def engine_clock(setting: str, model_clock: str) -> WindowClock:
    """The clock a window runs on: `setting` (an engine's `window_clock`), where `model`
    means the clock of the model's training windows (`model_clock`)."""
    if setting == "model":
        return "time" if model_clock == "time" else "poses"
    if setting not in ("poses", "time"):
        raise ValueError(f"window clock must be model, poses or time, got {setting!r}")
    return "time" if setting == "time" else "poses"


class PoseWindow:
    """The last `size` poses of one stream, and when to classify them.

    A pause longer than `max_gap_s` between poses (nobody detected for that long) empties
    the window; a shorter one is bridged, as a field camera loses the operator for a
    moment (`proxima.gesture.capture.MAX_GAP_S`), and `bridged()` says so while the
    window holds one longer than training windows do. `due()` is true once
    the window is full and `stride` poses came since the last classification.

    `clock="time"` keeps the window's span in seconds instead: the poses of the last
    `(size - 1) / rate` seconds, resampled (linear interpolation) onto `size` instants
    `1 / rate` apart that end at the newest pose. A 15 fps camera then fills a 30-frame
    window in 1 s instead of 2, and the gesture moves at the speed the model trained on.
    Classification is due every `stride / rate` seconds. At `rate` fps the two clocks
    give the same windows at the same poses.
    """

    def __init__(
        self,
        size: int = 60,
        stride: int = 5,
        max_gap_s: float = MAX_GAP_S,
        clock: WindowClock = "poses",
        rate: float = RATE_HZ,
    ) -> None:
        if size < 1 or stride < 1:
            raise ValueError(f"window size and stride must be >= 1, got {size}, {stride}")
        if clock not in ("poses", "time"):
            raise ValueError(f"window clock must be 'poses' or 'time', got {clock!r}")
        if not rate > 0:
            raise ValueError(f"window rate must be > 0 Hz, got {rate}")
        self.size = size
        self.stride = stride
        self.max_gap_s = max_gap_s
        self.clock = clock
        self.rate = float(rate)
        self.span_s = (size - 1) / self.rate
        # The time clock keeps poses until the span is covered; a camera faster than
        # `rate` needs more than `size` of them.
        keep = size if clock == "poses" else None
        self._t: deque[float] = deque(maxlen=keep)
        self._xyz: deque[np.ndarray] = deque(maxlen=keep)
        self._vis: deque[np.ndarray] = deque(maxlen=keep)
        self._last_t: float | None = None
        self._since = 0  # poses since the last classification
        self._taken_t: float | None = None  # stream time of the last classification
        self.restarts = 0

    def __len__(self) -> int:
        return len(self._xyz)

    def clear(self) -> None:
        """Forget every pose (the next classification waits for a full window)."""
        self._t.clear()
        self._xyz.clear()
        self._vis.clear()
        self._last_t = None
        self._since = 0
        self._taken_t = None

    def push(self, pose: Pose) -> bool:
        """Add the operator's pose; return True if a gap made the window restart."""
        restarted = False
        if self._last_t is not None and pose.t - self._last_t > self.max_gap_s + 1e-9:
            self.clear()
            self.restarts += 1
            restarted = True
        self._t.append(pose.t)
        self._xyz.append(pose.xyz)
        self._vis.append(pose.visibility)
        self._last_t = pose.t
        self._since += 1
        if self.clock == "time":
            # keep one pose at or before the span's start, drop the older ones
            start = pose.t - self.span_s + 1e-6
            while len(self._t) >= 2 and self._t[1] <= start:
                self._t.popleft()
                self._xyz.popleft()
                self._vis.popleft()
        return restarted

    def longest_pause_s(self) -> float:
        """The longest pause between two of the window's poses (0 with fewer than two):
        over `TRAIN_MAX_GAP_S` the window holds a bridged pause."""
        if len(self._t) < 2:
            return 0.0
        return float(np.max(np.diff(np.fromiter(self._t, float, len(self._t)))))

    def bridged(self) -> bool:
        """Whether the window holds a pause longer than training windows do."""
        return self.longest_pause_s() > TRAIN_MAX_GAP_S + 1e-9

    def full(self) -> bool:
        """Whether the window holds its whole span."""
        if self.clock == "poses":
            return len(self._xyz) == self.size
        return bool(self._t) and self._t[0] <= self._t[-1] - self.span_s + 1e-6

    def due(self) -> bool:
        """Whether to classify now."""
        if not self.full():
            return False
        if self.clock == "poses" or self._taken_t is None:
            return self._since >= self.stride
        return self._t[-1] - self._taken_t >= self.stride / self.rate - 1e-6

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        """The window as xyz (1, size, 33, 3) float32 and visibility (1, size, 33); marks
        it classified."""
        self._since = 0
        self._taken_t = self._t[-1] if self._t else None
        xyz = np.stack(self._xyz)
        vis = np.stack(self._vis)
        if self.clock == "time":
            xyz, vis = self._resampled(xyz, vis)
        return xyz.astype(np.float32, copy=False)[None], vis.astype(np.float32, copy=False)[None]

    def _resampled(self, xyz: np.ndarray, vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        times = np.asarray(self._t, np.float64)[None]
        out_xyz, out_vis = resample_windows(times, xyz[None], vis[None], self.size, self.rate)
        assert out_vis is not None
        return out_xyz[0], out_vis[0]
