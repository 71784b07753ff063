"""End-to-end training, as the CLI runs it: data -> split -> windows -> pipeline ->
model -> checkpoint. Scoring a checkpoint is `proxima.evaluation.metrics`."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import torch

from proxima.gesture.calibration import fit_temperature
from proxima.gesture.classifier import save_checkpoint
from proxima.gesture.clip import Clip
from proxima.gesture.datasets import load_data
from proxima.gesture.features import make_pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.models import DEFAULT_PIPELINE, build_model
from proxima.gesture.robust import CaptureSource, history_rows
from proxima.gesture.train import (
    EpochLog,
    TrainConfig,
    check_augment,
    chosen_schedule,
    fit,
    fit_schedule,
    predict_logits,
    validation_features,
)
from proxima.gesture.windows import WINDOW, Windows, make_windows, split_clips, validation_parts


@dataclass
class TrainResult:
    checkpoint: Path
    history: list[EpochLog]
    train_windows: int
    val_windows: int
    skipped_windows: int
    seconds: float
    # the refit on the whole training part (empty when off or without validation)
    refit_history: list[EpochLog] = field(default_factory=list)


def fit_and_validation_windows(
    train: Sequence[Clip], stride: int, max_gap: int
) -> tuple[Windows, Windows]:
    """Windows of a split's training part: (fit, validation), where validation is the
    tail of each clip's part (see `validation_parts`)."""
    fit_parts, val_parts = validation_parts(train, WINDOW)
    names: list[str] = []
    fit_w = make_windows(fit_parts, WINDOW, stride, max_gap, names)
    return fit_w, make_windows(val_parts, WINDOW, stride, max_gap, names)


def train_model(
    data_specs: Sequence[str] | None,
    model_name: str,
    split: str,
    out: str | Path,
    cfg: TrainConfig,
    pipeline_name: str | None = None,
    command: str = "",
    on_epoch: Callable[[EpochLog], None] | None = None,
    on_start: Callable[[int, int, int], None] | None = None,
    on_refit: Callable[[int, int], None] | None = None,
) -> TrainResult:
    """Train a model on a split's training part and save a self-contained checkpoint.

    Early stopping chooses the epochs on the validation tails; with `cfg.refit` a fresh
    model then trains on the whole training part for those epochs, at the learning
    rates the first run used, and is the one saved. `on_refit(windows, epochs)` is
    called when the refit starts; `on_epoch` is called for both runs' epochs."""
    t0 = time.perf_counter()
    check_augment(cfg)
    data = load_data(data_specs)
    train = split_clips(data.clips, split, WINDOW, data.uav_dir).train
    fit_w, val_w = fit_and_validation_windows(train, cfg.stride, cfg.max_gap)
    fit_parts, val_parts = validation_parts(train, WINDOW)
    sources: dict[str, CaptureSource | None] = {"fit": None, "val": None, "whole": None}
    if cfg.augment == "capture":  # the rows before each window (robust.py)
        rows = history_rows(cfg.capture_mix)
        for key, parts in (("fit", fit_parts), ("val", val_parts), ("whole", train)):
            if key != "whole" or cfg.refit:
                sources[key] = CaptureSource.from_parts(
                    parts, WINDOW, cfg.stride, cfg.max_gap, rows
                )
    if on_start:
        on_start(len(fit_w), len(val_w), fit_w.skipped + val_w.skipped)
    pipeline = make_pipeline(pipeline_name or DEFAULT_PIPELINE[model_name])
    pipeline.fit(to_metric(fit_w.xyz, fit_w.aspect))
    torch.manual_seed(cfg.seed)  # the initial weights too: one seed, one model
    model = build_model(model_name, num_features=pipeline.num_features)
    history = fit(
        model, pipeline, fit_w, val_w, cfg, on_epoch, None, sources["fit"], sources["val"]
    )
    refit_history: list[EpochLog] = []
    refit_windows = 0
    if cfg.refit and len(val_w):
        # the whole training part: fit, the gaps before the validation tails, the tails
        whole = make_windows(train, WINDOW, cfg.stride, cfg.max_gap)
        lrs = chosen_schedule(history, cfg.lr)
        if on_refit:
            on_refit(len(whole), len(lrs))
        torch.manual_seed(cfg.seed)
        model = build_model(model_name, num_features=pipeline.num_features)
        refit_history = fit_schedule(model, pipeline, whole, cfg, lrs, on_epoch, sources["whole"])
        refit_windows = len(whole)
    # Calibration on the validation tails, as the model meets them (capture and filter
    # drawn once with a fixed seed when augmenting); none without validation windows.
    calib = None
    if len(val_w):
        xv = validation_features(pipeline, val_w, cfg, sources["val"])
        calib = fit_temperature(predict_logits(model, xv), val_w.labels)
    meta = {
        "command": command,
        "split": split,
        "data": [str(f) for f in data.folders],
        "data_sha256": data.fingerprint(),
        "train_config": cfg.to_dict(),
        "epochs_run": len(history),
        "train_windows": len(fit_w),
        "val_windows": len(val_w),
        "refit_epochs": len(refit_history),
        "refit_windows": refit_windows,
        "temperature_fit": calib.to_dict() if calib else None,
    }
    temperature = calib.temperature if calib else 1.0
    path = save_checkpoint(out, model, model_name, pipeline, WINDOW, meta, temperature)
    return TrainResult(path, history, len(fit_w), len(val_w), fit_w.skipped + val_w.skipped,
                       time.perf_counter() - t0, refit_history)  # fmt: skip
