"""A capture model: what a drone camera and the live pose path do to landmark sequences
(jitter by person size and visibility, distance, camera elevation, yaw and roll, frame
rate and lost frames, body parts out of frame or hidden), each effect a parameter with
a documented range and a measured default. See docs/capture.md.

    from proxima.gesture.capture import condition
    model = condition("field")              # or CaptureModel(jitter=2.0, roll_deg=10)
    xyz, vis = model.apply_windows(w.xyz, w.vis, rng, aspect=w.aspect, has_z=w.has_z)
    captured = model.apply_clip(clip, rng)  # a whole recording, before windowing
"""

from __future__ import annotations

from proxima.gesture.capture.conditions import CONDITIONS, EFFECTS, FIELD, LEVELS, condition
from proxima.gesture.capture.model import (
    LOSS_MODES,
    MAX_GAP_S,
    PARTS,
    SOURCE_FPS,
    TRAIN_MAX_GAP_S,
    Captured,
    CaptureError,
    CaptureModel,
)
from proxima.gesture.capture.windows import live_windows

__all__ = [
    "CONDITIONS",
    "EFFECTS",
    "FIELD",
    "LEVELS",
    "LOSS_MODES",
    "MAX_GAP_S",
    "PARTS",
    "SOURCE_FPS",
    "TRAIN_MAX_GAP_S",
    "CaptureError",
    "CaptureModel",
    "Captured",
    "condition",
    "live_windows",
]
