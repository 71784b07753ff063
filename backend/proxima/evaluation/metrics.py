"""A checkpoint on a split's test windows: per window (accuracy, macro precision /
recall / F1, per class, confusion, per camera view) and per clip (one decision per clip
from its windows' mean probabilities). `proxima evaluate` writes these fields."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.clip import Clip
from proxima.gesture.datasets import load_data
from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint
from proxima.gesture.train import features, predict_proba
from proxima.gesture.windows import WINDOW, Windows, make_windows, split_clips
from proxima.types import GESTURES


def metrics(y_true: np.ndarray, probs: np.ndarray, clip: np.ndarray) -> dict[str, Any]:
    """The evaluation JSON's fields from labels, probabilities and clip ids per window."""
    from sklearn.metrics import confusion_matrix, precision_recall_fscore_support

    labels = list(range(len(GESTURES)))
    y_pred = probs.argmax(axis=1)
    p, r, f, support = precision_recall_fscore_support(
        y_true, y_pred, labels=labels, zero_division=0
    )
    present = support > 0  # macro averages over the classes the test set has
    clip_true, clip_pred = [], []
    for c in np.unique(clip):
        sel = clip == c
        clip_true.append(int(y_true[sel][0]))
        clip_pred.append(int(probs[sel].mean(axis=0).argmax()))
    return {
        "windows": len(y_true),
        "clips": len(clip_true),
        "accuracy": float((y_pred == y_true).mean()),
        "macro_precision": float(p[present].mean()),
        "macro_recall": float(r[present].mean()),
        "macro_f1": float(f[present].mean()),
        "per_class": {
            g: {
                "precision": float(p[i]),
                "recall": float(r[i]),
                "f1": float(f[i]),
                "support": int(support[i]),
            }
            for i, g in enumerate(GESTURES)
        },
        "confusion": confusion_matrix(y_true, y_pred, labels=labels).tolist(),
        "clip_accuracy": float(np.mean(np.asarray(clip_true) == np.asarray(clip_pred))),
    }


def accuracy_by(group: np.ndarray, y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, Any]:
    """Window accuracy and window count for each value of `group` (e.g. the camera view)."""
    return {
        str(g): {"accuracy": float((y_pred[group == g] == y_true[group == g]).mean()),
                 "windows": int((group == g).sum())}
        for g in np.unique(group)
    }  # fmt: skip


def window_probs(clf: GestureClassifier | EnsembleClassifier, windows: Windows) -> np.ndarray:
    """Probabilities (N, 13) for `windows`: a model's softmax, or an ensemble's mean of
    its members' calibrated probabilities (as the engine runs it)."""
    if isinstance(clf, EnsembleClassifier):  # EnsembleClassifier.predict, with each window's has_z
        probs = [predict_proba(m.model, features(m.pipeline, windows), temperature=m.temperature)
                 for m in clf.members]  # fmt: skip
        return np.mean(probs, axis=0)
    return predict_proba(clf.model, features(clf.pipeline, windows))


def score_windows(
    clf: GestureClassifier | EnsembleClassifier, windows: Windows, clips: Sequence[Clip]
) -> dict[str, Any]:
    """`metrics` of `clf` on `windows` (made from `clips`), plus the accuracy per camera
    view (`per_view`): the LASER side views are where models are weakest. The windows
    may be altered first (noise, dropped frames), as a robustness check does."""
    probs = window_probs(clf, windows)
    result = metrics(windows.labels, probs, windows.clip)
    view_of = {c.name: c.view for c in clips}
    views = np.array([view_of[windows.clip_names[c]] for c in windows.clip])
    result["per_view"] = accuracy_by(views, windows.labels, probs.argmax(axis=1))
    return result


def evaluate_checkpoint(
    checkpoint: str | Path | None,
    data_specs: Sequence[str] | None,
    split: str,
    stride: int = 3,
    max_gap: int = 5,
) -> dict[str, Any]:
    """Metrics of a checkpoint on a split's test windows (see `score_windows`); for the
    split `all`, which has no test part, on the training data itself. Comma-joined paths
    (`a.pt,b.pt`) score their ensemble, as the engine loads it.

    Raises:
        FileNotFoundError, ValueError: the checkpoint is missing or not a checkpoint, or
            ensemble members disagree on window or labels.
        proxima.gesture.clip.DataError: the data cannot be loaded or split.
    """
    clf = load_checkpoint(checkpoint)
    data = load_data(data_specs)
    parts = split_clips(data.clips, split, WINDOW, data.uav_dir)  # the protocol's gaps
    test = parts.test if parts.test else parts.train
    w = make_windows(test, clf.window, stride, max_gap)
    result = score_windows(clf, w, test)
    per_view = result.pop("per_view")  # last, as the JSON always had it
    result.update(split=split, checkpoint=str(checkpoint), skipped_windows=w.skipped,
                  model=clf.model_name, per_view=per_view)  # fmt: skip
    return result
