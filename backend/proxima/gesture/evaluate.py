"""Metrics for a checkpoint on a split's test windows: per window (accuracy, macro
precision / recall / F1, per class, confusion, per camera view) and per clip (one
decision per clip from its windows' mean probabilities), plus a confusion-matrix
picture."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

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


def plot_confusion(confusion: list[list[int]], path: str | Path, title: str) -> Path:
    """Row-normalised confusion matrix as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cm = np.asarray(confusion, float)
    norm = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
    fig, ax = plt.subplots(figsize=(8, 7))
    ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(GESTURES)), GESTURES, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(GESTURES)), GESTURES, fontsize=8)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(title, fontsize=10)
    for i in range(len(GESTURES)):
        for j in range(len(GESTURES)):
            if cm[i, j]:
                ax.text(j, i, f"{norm[i, j]:.2f}", ha="center", va="center", fontsize=6,
                        color="white" if norm[i, j] > 0.5 else "black")  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
