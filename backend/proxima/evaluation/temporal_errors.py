"""Where a temporal-split model goes wrong, and whether the data could have told it.

Every LASER clip's held-out part (its last 30%, windows at stride 3, as `proxima
evaluate --split temporal` scores them) is laid out in time twice: the model's decision
for each window, and a model-free check, the label of the nearest training window
(1-nearest neighbour over all LASER clips' training parts, on coarse poses: the body
pipeline's joint positions, hip-centred, torso-scaled and turned to face the camera,
averaged over six 10-frame chunks). Where the model is wrong and the nearest training
window carries the same wrong label, that test stretch looks more like another gesture's
training data than like its own: a better-trained model of the same recordings cannot
be expected to get it right; more recordings can. With several checkpoints (e.g. seeds
of one recipe), the windows every model gets wrong are counted too: if they alone exceed
what a target allows, no choice among these models reaches it.
`bench/temporal_errors.py` runs it and draws `plots.plot_temporal_errors`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from proxima.gesture.windows import Windows

CHUNK = 10  # frames averaged into one coarse pose


def stretches(pred: np.ndarray, truth: np.ndarray, labels: Sequence[str]) -> list[dict[str, Any]]:
    """Runs of consecutive wrong windows with one predicted label, in window order."""
    out: list[dict[str, Any]] = []
    for i, (p, y) in enumerate(zip(pred.tolist(), truth.tolist(), strict=True)):
        if p == y:
            continue
        last = out[-1] if out else None
        if last and last["start"] + last["length"] == i and last["predicted"] == labels[p]:
            last["length"] += 1
        else:
            out.append({"start": i, "length": 1, "predicted": labels[p]})
    return out


def coarse(windows: Windows) -> np.ndarray:
    """Windows -> (N, W // CHUNK * 17 * 2): the shared joints' 2D positions in the body
    pipeline's canonical frame (hip-centred, torso-scaled, facing the camera), averaged
    over each CHUNK frames."""
    from proxima.gesture.features import BodyPipeline
    from proxima.gesture.geometry import to_metric
    from proxima.gesture.skeleton import COMMON

    can = BodyPipeline().canonical(to_metric(windows.xyz, windows.aspect), windows.has_z)
    n, w = can.shape[:2]
    pos = can[:, : w - w % CHUNK, list(COMMON), :2].reshape(n, w // CHUNK, CHUNK, -1)
    return pos.mean(axis=2).reshape(n, -1)


def nearest_labels(train: np.ndarray, train_labels: np.ndarray, test: np.ndarray) -> np.ndarray:
    """The label of each test row's nearest training row (squared Euclidean)."""
    sq = (train**2).sum(axis=1)
    out = np.empty(len(test), dtype=train_labels.dtype)
    for i in range(0, len(test), 256):
        block = test[i : i + 256]
        dist = sq[None, :] - 2 * block @ train.T  # + |block|^2, constant per row
        out[i : i + 256] = train_labels[dist.argmin(axis=1)]
    return out


def analyse(checkpoints: Sequence[str | Path], data: str | None) -> dict[str, Any]:
    """Each checkpoint's decisions on the temporal split's test windows beside the
    nearest training window's label (see the module); the JSON-ready result.

    Raises:
        FileNotFoundError: a checkpoint is missing.
        ValueError: a checkpoint is not a checkpoint, or its window or labels are not
            the temporal split's.
    """
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.datasets import load_data
    from proxima.gesture.train import features, predict_proba
    from proxima.gesture.windows import WINDOW, make_windows, split_clips
    from proxima.types import GESTURES

    laser = load_data([data or "laser"])
    parts = split_clips(laser.clips, "temporal", WINDOW, laser.uav_dir)
    names: list[str] = []
    test = make_windows(parts.test, WINDOW, 3, 5, names)
    train = make_windows(parts.train, WINDOW, 2, 5, names)
    nn = nearest_labels(coarse(train), train.labels, coarse(test))
    truth = test.labels  # indices into GESTURES
    labels = list(GESTURES)
    models, preds = [], []
    for path in checkpoints:
        clf = GestureClassifier.load(path)
        if clf.window != WINDOW:
            raise ValueError(f"{path}: window {clf.window}, the temporal split uses {WINDOW}")
        if list(clf.labels) != labels:
            raise ValueError(f"{path}: labels {list(clf.labels)} are not {labels}")
        pred = predict_proba(clf.model, features(clf.pipeline, test)).argmax(axis=1)
        wrong = pred != truth
        preds.append(pred)
        models.append(
            {
                "checkpoint": str(path),
                "accuracy": float((~wrong).mean()),
                "wrong": int(wrong.sum()),
                "wrong_and_nearest_neighbour_wrong": int((wrong & (nn != truth)).sum()),
                # ... and of those, the very label the model gave.
                "wrong_and_nearest_neighbour_agrees": int((wrong & (nn == pred)).sum()),
            }
        )
    every = np.all([p != truth for p in preds], axis=0)
    clips = []
    for c in np.unique(test.clip):
        sel = np.flatnonzero(test.clip == c)
        if not any((p[sel] != truth[sel]).any() for p in preds):
            continue
        clips.append(
            {
                "clip": names[c],
                "gesture": labels[int(truth[sel[0]])],
                "truth": int(truth[sel[0]]),
                "windows": len(sel),
                "wrong": [int((p[sel] != truth[sel]).sum()) for p in preds],
                "wrong_in_every_model": int(every[sel].sum()),
                "nearest_neighbour_wrong": int((nn[sel] != truth[sel]).sum()),
                "model_stretches": [stretches(p[sel], truth[sel], labels) for p in preds],
                "predictions": [p[sel].tolist() for p in preds],
                "nearest_neighbour": nn[sel].tolist(),
            }
        )
    return {
        "labels": labels,
        "test_windows": len(test),
        "train_windows_searched": len(train),
        "nearest_neighbour_accuracy": float((nn == truth).mean()),
        "models": models,
        "wrong_in_every_model": int(every.sum()),
        "wrong_in_every_model_and_nearest_neighbour_wrong": int((every & (nn != truth)).sum()),
        "clips": clips,
    }
