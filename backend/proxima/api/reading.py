"""The model's own reading of a recorded take: what the Labelling and Calibration pages
show beside the gesture chosen, warning when they differ."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np

_lock = threading.Lock()
_classifiers: dict[str, Any] = {}


def classifier_at(path: str | Path) -> Any:
    """The classifier of a checkpoint file (one model or an ensemble), loaded once per path.

    Raises:
        FileNotFoundError, ValueError: not a gesture checkpoint.
    """
    from proxima.gesture.ensemble import load_checkpoint

    key = str(path)
    with _lock:
        if key not in _classifiers:
            _classifiers[key] = load_checkpoint(key)
        return _classifiers[key]


def model_in_use(console: Any, stream: str | None = None) -> tuple[Any, str]:
    """(classifier, path) of the model the live engine runs (for `stream`: its own if
    one was promoted for it), else the shipped one."""
    from proxima.gesture.classifier import default_checkpoint

    active = console.promoter.active_checkpoint(stream) if console.promoter else None
    path = str(active or default_checkpoint())
    return classifier_at(path), path


def model_reading(clf: Any, xyz: np.ndarray) -> dict[str, Any]:
    """The mean of `clf`'s probabilities over the windows of a take (N, 33, 3) (a take
    shorter than the model's window is padded with its first frame): the top gesture,
    its confidence, each gesture's probability, the frames and the window."""
    xyz = np.asarray(xyz, np.float32)
    n, w = len(xyz), clf.window
    padded = n < w
    if padded:
        xyz = np.concatenate([np.repeat(xyz[:1], w - n, axis=0), xyz])
    starts = range(0, len(xyz) - w + 1, max(1, w // 4))
    windows = np.stack([xyz[i : i + w] for i in starts])
    probs = clf.predict(windows).mean(axis=0)
    top = int(probs.argmax())
    return {
        "gesture": clf.labels[top],
        "confidence": round(float(probs[top]), 4),
        "probs": {g: round(float(p), 4) for g, p in zip(clf.labels, probs, strict=True)},
        "frames": n,
        "window": w,
        "padded": padded,
    }
