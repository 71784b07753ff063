"""End-to-end training, as the CLI runs it: data -> split -> windows -> pipeline ->
model -> checkpoint. Scoring a checkpoint is `proxima.evaluation.metrics`."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import torch

from proxima.gesture.calibration import fit_temperature
from proxima.gesture.classifier import GestureClassifier, save_checkpoint
from proxima.gesture.clip import Clip, DataError
from proxima.gesture.datasets import load_data
from proxima.gesture.features import Pipeline, make_pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.idle import trim_idle
from proxima.gesture.models import DEFAULT_PIPELINE, build_model
from proxima.gesture.robust import CaptureSource, history_rows
from proxima.gesture.train import (
    EpochLog,
    TrainConfig,
    check_config,
    chosen_schedule,
    fit,
    fit_schedule,
    pair_mask,
    predict_logits,
    validation_features,
)
from proxima.gesture.windows import (
    WINDOW,
    SplitParts,
    Windows,
    make_windows,
    parse_calibration,
    split_clips,
    validation_parts,
)

# Fine-tuning (`init`) trains at this fraction of the configured learning rate.
FINE_TUNE_LR = 0.25


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


def calibration_fit_parts(
    parts: SplitParts, stride: int, max_gap: int, share: float, window: int = WINDOW
) -> tuple[list[Clip], list[Clip], int]:
    """(fit parts, validation parts, repeats) of a `calibrate:` split: the inner split's
    training part splits into fit and validation tails as always; the calibration parts
    (too short to lose a tail) only fit, repeated `repeats` times to make about `share`
    (0 < share < 1) of the fit windows; each copy is augmented afresh, so the repeats
    are not identical. Validation therefore holds no frame of the
    held-out clips.

    Raises:
        DataError: `share` outside (0, 1).
    """
    if not 0.0 < share < 1.0:
        raise DataError(f"calibration share {share:g}: must lie between 0 and 1 (exclusive)")
    calib_ids = {id(c) for c in parts.calibration}
    inner = [c for c in parts.train if id(c) not in calib_ids]
    fit_parts, val_parts = validation_parts(inner, window)
    n_inner = len(make_windows(fit_parts, window, stride, max_gap))
    n_calib = len(make_windows(parts.calibration, window, stride, max_gap))
    repeats = 1
    if n_calib:
        repeats = max(1, round(share * n_inner / ((1 - share) * n_calib)))
    return list(fit_parts) + list(parts.calibration) * repeats, list(val_parts), repeats


def load_init(
    path: str | Path, split: str, model_name: str, window: int = WINDOW
) -> GestureClassifier:
    """The checkpoint a calibration fine-tunes: it must have trained on the calibration
    split's inner split, so it has never seen the held-out clips (the shipped model,
    trained on every clip, has).

    Raises:
        DataError: not a calibration split, or a checkpoint of another split or model.
    """
    calibration = parse_calibration(split)
    if calibration is None:
        raise DataError(f"--init fine-tunes a calibration split (calibrate:...), not {split!r}")
    clf = GestureClassifier.load(path)
    trained_on = clf.metadata.get("split")
    if trained_on != calibration[0]:
        raise DataError(
            f"--init {path}: trained on split {trained_on!r}, not {calibration[0]!r}: "
            "a calibration fine-tunes the inner split's model, which never saw the held-out clips"
        )
    if clf.model_name != model_name:
        raise DataError(f"--init {path}: a {clf.model_name} model, not {model_name}")
    if clf.window != window:
        raise DataError(f"--init {path}: {clf.window}-frame windows, not {window}")
    return clf


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

    `init`: with a calibration split (see `load_init`), fine-tune that checkpoint, with
    its pipeline, for `cfg.epochs` at `FINE_TUNE_LR` of the rate, without early stopping
    (the validation tails hold no frame of the new view or people, so they cannot say
    when it has adapted); with any other split, start from its weights and pipeline
    instead of fresh ones and train as usual (e.g. a model pretrained on synthetic clips).

    Raises:
        ValueError: `init` is another model or pipeline than this run's.
    """
    t0 = time.perf_counter()
    check_config(cfg)
    calibrating = init is not None and parse_calibration(split) is not None
    win = cfg.window
    start = None
    if init is not None and not calibrating:
        start = start_checkpoint(init, model_name, pipeline_name)
    data = load_data(data_specs)
    init_clf = load_init(init, split, model_name, win) if init is not None and calibrating else None
    parts = split_clips(data.clips, split, WINDOW, data.uav_dir)  # the protocol's gaps
    train = [trim_idle(c, win) for c in parts.train] if cfg.trim_idle else parts.train
    repeats = 0
    if parts.calibration:
        fit_parts, val_parts, repeats = calibration_fit_parts(
            parts, cfg.stride, cfg.max_gap, cfg.calibration_share, win
        )
    else:
        fit_parts, val_parts = validation_parts(train, win)
    names: list[str] = []
    fit_w = make_windows(fit_parts, win, cfg.stride, cfg.max_gap, names)
    val_w = make_windows(val_parts, win, cfg.stride, cfg.max_gap, names)
    # the refit's whole training part, with the calibration's weight as in fit
    whole_parts = list(train) + list(parts.calibration) * max(repeats - 1, 0)
    sources: dict[str, CaptureSource | None] = {"fit": None, "val": None, "whole": None}
    if cfg.augment == "capture":  # the rows before each window (robust.py)
        rows = history_rows(cfg.capture_mix)
        for key, ps in (("fit", fit_parts), ("val", val_parts), ("whole", whole_parts)):
            if key != "whole" or cfg.refit:
                sources[key] = CaptureSource.from_parts(ps, win, cfg.stride, cfg.max_gap, rows)
    if on_start:
        on_start(len(fit_w), len(val_w), fit_w.skipped + val_w.skipped)
    if start is not None:
        pipeline: Pipeline = start.pipeline  # fitted with the weights (paper: its scaling)
    elif init_clf is not None:
        pipeline = init_clf.pipeline
    else:
        pipeline = make_pipeline(pipeline_name or DEFAULT_PIPELINE[model_name])
        pipeline.fit(to_metric(fit_w.xyz, fit_w.aspect))

    def initial_model() -> torch.nn.Module:
        torch.manual_seed(cfg.seed)  # the initial weights too: one seed, one model
        model = build_model(model_name, num_features=pipeline.num_features)
        if start is not None:
            model.load_state_dict(start.model.state_dict())
        return model

    if init_clf is not None:
        model = init_clf.model
        tune = replace(cfg, lr=cfg.lr * FINE_TUNE_LR)
        history = fit(model, pipeline, fit_w, None, tune, on_epoch, None, sources["fit"], None)
    else:
        model = initial_model()
        history = fit(
            model, pipeline, fit_w, val_w, cfg, on_epoch, None, sources["fit"], sources["val"]
        )
    refit_history: list[EpochLog] = []
    refit_windows = 0
    if cfg.refit and len(val_w) and init_clf is None:
        # the whole training part: fit, the gaps before the validation tails, the tails
        whole = make_windows(whole_parts, win, cfg.stride, cfg.max_gap)
        lrs = chosen_schedule(history, cfg.lr)
        if on_refit:
            on_refit(len(whole), len(lrs))
        model = initial_model()
        refit_history = fit_schedule(model, pipeline, whole, cfg, lrs, on_epoch, sources["whole"])
        refit_windows = len(whole)
    # Calibration on the validation tails, as the model meets them (capture and filter
    # drawn once with a fixed seed when augmenting); none without validation windows.
    calib = None
    if len(val_w):
        xv = validation_features(pipeline, val_w, cfg, sources["val"])
        calib = fit_temperature(predict_logits(model, xv), val_w.labels, pair_mask(val_w, cfg))
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
        "calibration_repeats": repeats,
        "init": str(init) if init is not None else None,
    }
    temperature = calib.temperature if calib else 1.0
    path = save_checkpoint(out, model, model_name, pipeline, win, meta, temperature)
    return TrainResult(path, history, len(fit_w), len(val_w), fit_w.skipped + val_w.skipped,
                       time.perf_counter() - t0, refit_history)  # fmt: skip


def start_checkpoint(
    path: str | Path, model_name: str, pipeline_name: str | None
) -> GestureClassifier:
    """The checkpoint a run starts from (`--init`, and federated runs' `init`), checked to
    be the same model and pipeline. Its window may differ from the run's: neither model's
    weights depend on the window's length (the TCN pools over time, the LSTM reads its
    last step), so the 60-frame synthetic start serves 30-frame runs too (measured in
    docs/experiments.md, twenty-second session).

    Raises:
        FileNotFoundError, ValueError: not a checkpoint, or another model or pipeline.
    """
    start = GestureClassifier.load(path)
    wanted = pipeline_name or DEFAULT_PIPELINE[model_name]
    if start.model_name != model_name or start.pipeline.name != wanted:
        raise ValueError(
            f"{path}: --init is a {start.model_name} model with the {start.pipeline.name!r} "
            f"pipeline, but this run trains {model_name} with {wanted!r}"
        )
    return start
