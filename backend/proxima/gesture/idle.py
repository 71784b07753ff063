"""The operator standing still before a gesture begins.

Many clips open with the operator at rest (arms still) before the gesture's first move:
49 frames in LASER's front-view slow_down. A window that lies wholly in that rest shows
no gesture, yet it carries the clip's label; a 30-frame model learned the rest stance as
slow_down and commanded it to an operator standing still (bench.still_operator). Training
therefore starts each moving gesture's clip where at most half a window of rest is left;
the static signals (hover, land) are rest stances by definition and keep every frame.
"""

from __future__ import annotations

import numpy as np

from proxima.gesture.clip import Clip

ARMS = [13, 14, 15, 16]  # MediaPipe elbows and wrists
STILL_SPEED = 0.006  # normalised image units per frame (x and y each run 0..1)
STATIC_GESTURES = ("hover", "land")  # signalled by holding a stance


def still_prefix(xyz: np.ndarray) -> int:
    """Frames from the start of a clip (T, 33, 3) during which the elbows and wrists stay
    still: their largest 2D step, averaged over 5 frames, at most STILL_SPEED."""
    step = np.linalg.norm(np.diff(xyz[:, ARMS, :2], axis=0), axis=-1).max(axis=1)
    smooth = np.convolve(step, np.ones(5) / 5, mode="same")
    moving = np.flatnonzero(smooth > STILL_SPEED)
    return int(moving[0]) if len(moving) else len(xyz)


def trim_idle(clip: Clip, window: int) -> Clip:
    """`clip` from where its opening rest leaves at most half a `window` before the first
    move (the whole clip for a static signal, or one that never moves)."""
    if clip.gesture in STATIC_GESTURES or len(clip) < 2:
        return clip
    rest = still_prefix(clip.xyz)
    start = rest - window // 2
    if rest >= len(clip) or start <= 0:
        return clip
    return clip.slice(start, len(clip))
