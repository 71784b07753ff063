"""Calibrating a model to one camera from a few takes (the console's Calibration page):
each take is one gesture performed before that camera; its first part fine-tunes the
model in use, its last part is held out to show the model before and after.

The split of a take: the last `HOLDOUT_FRACTION` of its rows (at least one window) is
held out, the window before it is dropped (so no training window overlaps a held-out
one: consecutive windows share most of their frames), the rest trains. A take therefore
needs at least three windows of rows (`MIN_TAKE_FRAMES`).

The fine-tuning is the calibration recipe of `proxima train --split calibrate:... --init`
(workflow.py): the existing model, its pipeline, `fit` for a fixed number of epochs at
`FINE_TUNE_LR` of the rate, capture augmentation on, no early stopping (the held-out
parts never steer training), and the model's temperature kept.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.clip import Clip, DataError
from proxima.gesture.windows import WINDOW, make_windows
from proxima.types import GESTURES

HOLDOUT_FRACTION = 0.3
MIN_TAKE_FRAMES = 3 * WINDOW  # training >= 1 window, a window of gap, held out >= 1 window
TRAIN_STRIDE = 3  # takes are short: most starts train
EVAL_STRIDE = 2
MAX_EPOCHS = 40


def split_take(take: Clip, window: int = WINDOW) -> tuple[Clip, Clip]:
    """(training part, held-out part) of one take (see the module's docstring).

    Raises:
        DataError: a take shorter than three windows.
    """
    n = len(take)
    if n < 3 * window:
        raise DataError(
            f"take {take.name} ({take.gesture}) has {n} frames; a take needs at least "
            f"{3 * window} (training, a one-window gap, held out)"
        )
    held = max(window, round(n * HOLDOUT_FRACTION))
    return take.slice(0, n - held - window), take.slice(n - held, n)


def score(clf: Any, parts: Sequence[Clip], stride: int = EVAL_STRIDE) -> dict[str, Any]:
    """Window accuracy of classifier `clf` on clip parts, overall and per gesture (the
    gestures the parts hold): {"accuracy", "windows", "per_gesture": {g: {"accuracy",
    "windows", "read_as"}}}, `read_as` the gesture it reads most often there."""
    w = make_windows(parts, clf.window, stride, max_gap=5)
    if not len(w):
        raise DataError("no held-out windows to score on")
    probs = clf.predict(w.xyz, w.aspect)
    pred = probs.argmax(axis=1)
    per: dict[str, dict[str, Any]] = {}
    for g in sorted(set(w.labels.tolist())):
        sel = w.labels == g
        counts = np.bincount(pred[sel], minlength=len(GESTURES))
        per[GESTURES[g]] = {
            "accuracy": round(float((pred[sel] == g).mean()), 4),
            "windows": int(sel.sum()),
            "read_as": GESTURES[int(counts.argmax())],
        }
    return {
        "accuracy": round(float((pred == w.labels).mean()), 4),
        "windows": len(w),
        "per_gesture": per,
    }


@dataclass
class CalibrationResult:
    checkpoint: Path
    before: dict[str, Any]  # `score` of the model fine-tuned, on the held-out parts
    after: dict[str, Any]  # `score` of the fine-tuned model, on the same parts
    epochs: int
    train_windows: int
    seconds: float
    losses: list[float] = field(default_factory=list)


def calibrate_takes(
    checkpoint: str | Path,
    takes: Sequence[Clip],
    out: str | Path,
    *,
    epochs: int = 12,
    seed: int = 0,
    threads: int = 2,
    metadata: dict[str, Any] | None = None,
    on_epoch: Callable[[int, int, float], None] | None = None,
    on_member: Callable[[int, int], None] | None = None,
) -> CalibrationResult:
    """Fine-tune `checkpoint` on the training parts of `takes` and save it at `out`;
    score it before and after on their held-out parts. An ensemble (the shipped model)
    has each member fine-tuned the same way, one after the other, and is saved as an
    ensemble. `on_member(i, members)` says which member starts (from 1),
    `on_epoch(epoch, epochs, loss)` reports each member's epochs.

    Raises:
        DataError: a take too short, or no training windows.
        ValueError, FileNotFoundError: `checkpoint` is not a gesture checkpoint.
    """
    from proxima.gesture.classifier import save_checkpoint
    from proxima.gesture.ensemble import (
        EnsembleClassifier,
        load_checkpoint,
        members_of,
        save_ensemble,
    )
    from proxima.gesture.robust import CaptureSource, history_rows
    from proxima.gesture.train import EpochLog, TrainConfig, fit
    from proxima.gesture.workflow import FINE_TUNE_LR

    if not 1 <= epochs <= MAX_EPOCHS:
        raise ValueError(f"epochs must be 1..{MAX_EPOCHS}, got {epochs}")
    t0 = time.perf_counter()
    train_parts, held_parts = [], []
    for take in takes:
        a, b = split_take(take)
        train_parts.append(a)
        held_parts.append(b)
    clf = load_checkpoint(checkpoint)
    before = score(clf, held_parts)
    cfg = TrainConfig(
        epochs=epochs, seed=seed, threads=threads, stride=TRAIN_STRIDE, window=clf.window
    )  # the model's own window, as the engine cuts them
    fit_w = make_windows(train_parts, cfg.window, cfg.stride, cfg.max_gap)
    if not len(fit_w):
        raise DataError("the takes' training parts hold no window (frames missing?)")
    source = CaptureSource.from_parts(
        train_parts, cfg.window, cfg.stride, cfg.max_gap, history_rows(cfg.capture_mix)
    )
    tune = replace(cfg, lr=cfg.lr * FINE_TUNE_LR)

    def report(log: EpochLog) -> None:
        if on_epoch:
            on_epoch(log.epoch, epochs, log.train_loss)

    members = members_of(clf)
    losses: list[float] = []
    runs = 0
    for i, member in enumerate(members, 1):
        if on_member:
            on_member(i, len(members))
        history = fit(member.model, member.pipeline, fit_w, None, tune, report, None, source, None)
        member.model.eval()
        losses += [h.train_loss for h in history]
        runs = len(history)
    after = score(clf, held_parts)
    meta = {
        **(metadata or {}),
        "split": "console-calibration",
        "init": str(checkpoint),
        "train_config": tune.to_dict(),
        "epochs_run": runs,
        "train_windows": len(fit_w),
        "calibration_takes": [t.name for t in takes],
        "holdout_fraction": HOLDOUT_FRACTION,
        "held_out_before": before,
        "held_out_after": after,
        "test_accuracy": after["accuracy"],
    }
    if isinstance(clf, EnsembleClassifier):
        for member in members:  # each member's own record says it was tuned, and where
            member.metadata = {**member.metadata, "split": meta["split"], "init": str(checkpoint)}
        path = save_ensemble(out, members, meta)
    else:
        path = save_checkpoint(out, clf.model, clf.model_name, clf.pipeline, clf.window, meta,
                               clf.temperature)  # fmt: skip
    return CalibrationResult(path, before, after, runs, len(fit_w),
                             time.perf_counter() - t0, losses)  # fmt: skip
