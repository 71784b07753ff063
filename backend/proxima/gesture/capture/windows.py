"""Windows of a captured recording, cut as the live engine's `PoseWindow` cuts them."""

from __future__ import annotations

import itertools

import numpy as np

from proxima.gesture.capture.model import MAX_GAP_S, Captured, CaptureError
from proxima.gesture.timebase import RATE_HZ, resample_windows


def live_windows(
    captured: Captured,
    size: int = 60,
    stride: int = 5,
    max_gap_s: float = MAX_GAP_S,
    clock: str = "poses",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The windows the engine would classify in `captured`: `size` consecutive received
    poses, the first once `size` have arrived after a (re)start, then every `stride`
    poses; a pause over `max_gap_s` restarts (engine/window.py). With `clock="time"`,
    the poses of the last (size - 1) / 30 s resampled to `size`, the first once that span
    is covered, then every stride / 30 s. Returns xyz (N, size, 33, 3), visibility
    (N, size, 33) and each window's end time (N,).

    Raises:
        CaptureError: size or stride below 1, or an unknown clock.
    """
    if size < 1 or stride < 1:
        raise CaptureError(f"window size and stride must be >= 1, got {size}, {stride}")
    if clock not in ("poses", "time"):
        raise CaptureError(f"window clock must be poses or time, got {clock!r}")
    t = captured.t
    breaks = np.flatnonzero(np.diff(t) > max_gap_s + 1e-9) + 1
    bounds = np.r_[0, breaks, len(t)]
    if clock == "time":
        return _timed_windows(captured, bounds, size, stride)
    ends = [np.arange(a + size - 1, b, stride) for a, b in itertools.pairwise(bounds)]
    end = np.concatenate(ends).astype(np.int64) if ends else np.zeros(0, np.int64)
    rows = end[:, None] + np.arange(1 - size, 1)[None, :]
    return captured.xyz[rows], captured.visibility[rows], t[end]


def _timed_windows(
    captured: Captured, bounds: np.ndarray, size: int, stride: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = captured.t
    span, every = (size - 1) / RATE_HZ, stride / RATE_HZ
    xs, vs, ends = [], [], []
    for a, b in itertools.pairwise(bounds):
        last: float | None = None
        for e in range(a, b):
            if t[a] > t[e] - span + 1e-6 or (last is not None and t[e] - last < every - 1e-6):
                continue
            last = t[e]
            first = a + int(np.searchsorted(t[a : e + 1], t[e] - span + 1e-6, "right")) - 1
            sl = slice(max(first, a), e + 1)
            x, v = resample_windows(
                t[None, sl], captured.xyz[None, sl], captured.visibility[None, sl], size
            )
            assert v is not None
            xs.append(x[0])
            vs.append(v[0])
            ends.append(t[e])
    if not ends:
        return (np.zeros((0, size, 33, 3), np.float32), np.zeros((0, size, 33), np.float32),
                np.zeros(0))  # fmt: skip
    return (np.stack(xs).astype(np.float32), np.stack(vs).astype(np.float32),
            np.asarray(ends))  # fmt: skip
