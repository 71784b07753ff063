"""Windows of a captured recording, cut as the live engine's `PoseWindow` cuts them."""

from __future__ import annotations

import itertools

import numpy as np

from proxima.gesture.capture.model import MAX_GAP_S, Captured, CaptureError


def live_windows(
    captured: Captured, size: int = 60, stride: int = 5, max_gap_s: float = MAX_GAP_S
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The windows the engine would classify in `captured`: `size` consecutive received
    poses, the first once `size` have arrived after a (re)start, then every `stride`
    poses; a pause over `max_gap_s` restarts (engine/window.py). Returns xyz
    (N, size, 33, 3), visibility (N, size, 33) and each window's end time (N,).

    Raises:
        CaptureError: size or stride below 1.
    """
    if size < 1 or stride < 1:
        raise CaptureError(f"window size and stride must be >= 1, got {size}, {stride}")
    t = captured.t
    breaks = np.flatnonzero(np.diff(t) > max_gap_s + 1e-9) + 1
    bounds = np.r_[0, breaks, len(t)]
    ends = [np.arange(a + size - 1, b, stride) for a, b in itertools.pairwise(bounds)]
    end = np.concatenate(ends).astype(np.int64) if ends else np.zeros(0, np.int64)
    rows = end[:, None] + np.arange(1 - size, 1)[None, :]
    return captured.xyz[rows], captured.visibility[rows], t[end]
