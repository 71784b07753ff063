"""End-to-end training, as the CLI runs it: data -> split -> windows -> pipeline ->
model -> checkpoint. Scoring a checkpoint is `proxima.evaluation.metrics`."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import torch

from proxima.gesture.classifier import GestureClassifier, save_checkpoint
from proxima.gesture.clip import Clip
from proxima.gesture.datasets import load_data
from proxima.gesture.features import Pipeline, make_pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.models import DEFAULT_PIPELINE, build_model
from proxima.gesture.train import (
    EpochLog,
    TrainConfig,
    chosen_schedule,
    fit,
    fit_schedule,
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
    init: str | Path | None = None,
) -> TrainResult:
    """Train a model on a split's training part and save a self-contained checkpoint.

    Early stopping chooses the epochs on the validation tails; with `cfg.refit` a fresh
    model then trains on the whole training part for those epochs, at the learning
    rates the first run used, and is the one saved. `on_refit(windows, epochs)` is
    called when the refit starts; `on_epoch` is called for both runs' epochs.

    `init`: a checkpoint whose weights (and feature pipeline) every run starts from
    instead of fresh ones, e.g. a model pretrained on synthetic clips, fine-tuned here.

    Raises:
        ValueError: `init` is another model or pipeline than this run's.
    """
    t0 = time.perf_counter()
    start = _init_checkpoint(init, model_name, pipeline_name) if init is not None else None
    data = load_data(data_specs)
    train = split_clips(data.clips, split, WINDOW, data.uav_dir).train
    fit_w, val_w = fit_and_validation_windows(train, cfg.stride, cfg.max_gap)
    if on_start:
        on_start(len(fit_w), len(val_w), fit_w.skipped + val_w.skipped)
    if start is not None:
        pipeline: Pipeline = start.pipeline  # fitted with the weights (paper: its scaling)
    else:
        pipeline = make_pipeline(pipeline_name or DEFAULT_PIPELINE[model_name])
        pipeline.fit(to_metric(fit_w.xyz, fit_w.aspect))

    def initial_model() -> torch.nn.Module:
        torch.manual_seed(cfg.seed)  # the initial weights too: one seed, one model
        model = build_model(model_name, num_features=pipeline.num_features)
        if start is not None:
            model.load_state_dict(start.model.state_dict())
        return model

    model = initial_model()
    history = fit(model, pipeline, fit_w, val_w, cfg, on_epoch)
    refit_history: list[EpochLog] = []
    refit_windows = 0
    if cfg.refit and len(val_w):
        # the whole training part: fit, the gaps before the validation tails, the tails
        whole = make_windows(train, WINDOW, cfg.stride, cfg.max_gap)
        lrs = chosen_schedule(history, cfg.lr)
        if on_refit:
            on_refit(len(whole), len(lrs))
        model = initial_model()
        refit_history = fit_schedule(model, pipeline, whole, cfg, lrs, on_epoch)
        refit_windows = len(whole)
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
        "init": str(init) if init is not None else None,
    }
    path = save_checkpoint(out, model, model_name, pipeline, WINDOW, meta)
    return TrainResult(path, history, len(fit_w), len(val_w), fit_w.skipped + val_w.skipped,
                       time.perf_counter() - t0, refit_history)  # fmt: skip


def _init_checkpoint(
    path: str | Path, model_name: str, pipeline_name: str | None
) -> GestureClassifier:
    """The checkpoint a run starts from, checked to be the same model and pipeline."""
    start = GestureClassifier.load(path)
    wanted = pipeline_name or DEFAULT_PIPELINE[model_name]
    if start.model_name != model_name or start.pipeline.name != wanted:
        raise ValueError(
            f"{path}: --init is a {start.model_name} model with the {start.pipeline.name!r} "
            f"pipeline, but this run trains {model_name} with {wanted!r}"
        )
    if start.window != WINDOW:
        raise ValueError(f"{path}: --init has {start.window}-frame windows, not {WINDOW}")
    return start
