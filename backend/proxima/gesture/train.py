"""Training: the same loop serves centralised training (`proxima train`) and each
federated client's local epochs.

Early stopping keeps the best weights by validation loss; ReduceLROnPlateau lowers the
learning rate when validation stalls; gradients are clipped at 1.0 (the paper's LSTM
collapses to a constant prediction without it); everything is seeded. `fit_schedule`
replays a run's learning rates on more data without validation (the refit, workflow.py).
With `augment = "capture"` (the default) every epoch's windows are redrawn through the
capture model and the live One Euro filter (gesture/robust.py), and validation windows
once, with a fixed seed, the same way.
"""

from __future__ import annotations

import copy
import random
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from torch import nn

from proxima.control.evidence import THUMB_GESTURES, hands_seen
from proxima.gesture.augment import mirror, rotate, time_warp, transitions
from proxima.gesture.features import Pipeline
from proxima.gesture.geometry import to_metric
from proxima.gesture.robust import AUGMENTS, CAPTURE_MIX, CaptureSource, capture_windows
from proxima.gesture.windows import MIN_WINDOW, WINDOW, Windows
from proxima.types import GESTURES

MIN_DELTA = 1e-4  # the least fall in validation loss that counts as better
THUMB_PAIR = ("label", "either")
PAIR = [GESTURES.index(g) for g in THUMB_GESTURES]


def thumb_unseen(w: Windows, hand: str = "right", min_visibility: float = 0.5) -> np.ndarray:
    """(N,) bool: windows of `all_clear` / `not_clear` whose recording does not see the
    thumb hand by the engine's rule (`control.evidence.hands_seen`; OpenPose clips have no
    hand points, so none of theirs does)."""
    return np.isin(w.labels, PAIR) & ~hands_seen(w.vis, hand, min_visibility)


def label_logp(logp: np.ndarray, labels: np.ndarray, either: np.ndarray | None) -> np.ndarray:
    """(N,) log-probability of each window's label under `logp` (N, C); windows marked in
    `either` score the thumb pair's summed probability."""
    ll = logp[np.arange(len(labels)), labels]
    if either is None:
        return ll
    return np.where(either, np.logaddexp(logp[:, PAIR[0]], logp[:, PAIR[1]]), ll)


def pair_mask(w: Windows, cfg: TrainConfig) -> np.ndarray | None:
    """The windows taught the thumb pair (`cfg.thumb_pair` "either"), else None."""
    return thumb_unseen(w) if cfg.thumb_pair == "either" else None


class PairLoss(nn.Module):
    """Cross-entropy with label smoothing (as `nn.CrossEntropyLoss`) where a window marked
    `either` is scored on the probability of the thumb pair together (-log(p_a + p_n))."""

    def __init__(self, label_smoothing: float) -> None:
        super().__init__()
        self.eps = label_smoothing

    def forward(
        self, logits: torch.Tensor, y: torch.Tensor, either: torch.Tensor | None = None
    ) -> torch.Tensor:
        logp = torch.log_softmax(logits, dim=1)
        nll = -logp.gather(1, y[:, None])[:, 0]
        if either is not None:
            nll = torch.where(either, -torch.logsumexp(logp[:, PAIR], dim=1), nll)
        return ((1 - self.eps) * nll - self.eps * logp.mean(dim=1)).mean()


@dataclass
class TrainConfig:
    epochs: int = 60
    patience: int = 15  # epochs without a better validation loss before stopping
    batch_size: int = 64
    lr: float = 2e-3
    weight_decay: float = 1e-4
    clip_norm: float = 1.0
    lr_patience: int = 4
    lr_factor: float = 0.5
    seed: int = 0
    stride: int = 4
    max_gap: int = 5
    # Frames a window holds (the engine reads it from the checkpoint). Splits keep their
    # 60-frame gaps whatever the window, so every length is scored on the same test parts.
    window: int = WINDOW
    rotate_deg: float = 15.0  # the paper's augmentation
    yaw_deg: float = 30.0  # extra yaw for windows with depth
    time_warp: float = 0.2  # +- change of speed (0.8x to 1.2x); 0 = off
    transitions: float = 0.0  # share of windows turned into a gesture onset; 0 = off
    # Start moving gestures' training clips where at most half a window of the opening
    # rest is left (gesture/idle.py): a window of rest shows no gesture.
    trim_idle: bool = True
    # On: unseen side views 0.34 / 0.50 -> 0.55 / 0.76 (the other side view, mirrored,
    # looks like the unseen one); the temporal split stays within its seed-to-seed spread.
    mirror: bool = True
    label_smoothing: float = 0.05
    # After early stopping, train a fresh model on the whole training part (validation
    # tails included) for the epochs it chose. Off: it raised the temporal split's window
    # accuracy (seeds 0-2, 0.920 / 0.931 / 0.935 -> 0.939 / 0.937 / 0.940) but made the
    # live model confidently wrong, mostly on the left view's not_clear (docs/gesture.md).
    refit: bool = False
    threads: int = 2
    # "capture": windows redrawn each epoch through the capture model and the live One
    # Euro filter (gesture/robust.py); "none": the recordings as they are, unfiltered.
    augment: str = "capture"
    capture_mix: list = field(default_factory=lambda: [list(m) for m in CAPTURE_MIX])
    # "time": capture-noised windows at camera rates under 30 fps are resampled to the
    # recordings' 30 per second (gesture/timebase.py), as the engine's `window_clock =
    # "time"` does live; "poses": the last received poses, whatever their rate; "mixed":
    # half each way (the engine then resamples). Measured: docs/experiments.md.
    window_clock: str = "poses"
    # With a calibrate: split, the calibration clips' share of each epoch: their few
    # windows (5 s of each clip: about 300 against 4,300 of the inner training part) are
    # repeated to make it (workflow.calibration_fit_parts). Half (with 12 fine-tuning
    # epochs) beat a quarter (6 epochs) on 5 of 6 unseen views and people, by 2 points on
    # average (docs/experiments.md, "Calibration with capture-trained models").
    calibration_share: float = 0.5
    # "label": every window is taught its recorded label. "either": an all_clear or
    # not_clear window that does not see the thumb hand (the engine's hand rule: UAV-Gesture
    # has no hand points, a side view can hide the hand) is taught only "one of the two",
    # so data that cannot show the thumb does not teach a guess from the arm.
    thumb_pair: str = "label"
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)


def seed_everything(seed: int) -> np.random.Generator:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)
    return np.random.default_rng(seed)


def features(pipeline: Pipeline, w: Windows) -> np.ndarray:
    """Model input (N, W, F) for windows, without augmentation."""
    return pipeline.transform(to_metric(w.xyz, w.aspect), w.has_z)


def check_config(cfg: TrainConfig) -> None:
    """Raises ValueError for an unknown `cfg.augment` or a window outside
    MIN_WINDOW..WINDOW frames."""
    if cfg.augment not in AUGMENTS:
        raise ValueError(f"augment {cfg.augment!r}: choose from {', '.join(AUGMENTS)}")
    if cfg.thumb_pair not in THUMB_PAIR:
        raise ValueError(f"thumb pair {cfg.thumb_pair!r}: choose {' or '.join(THUMB_PAIR)}")
    if cfg.window_clock not in ("poses", "time", "mixed"):
        raise ValueError(f"window clock {cfg.window_clock!r}: choose poses, time or mixed")
    if not MIN_WINDOW <= cfg.window <= WINDOW:
        raise ValueError(
            f"window {cfg.window} frames: must lie between {MIN_WINDOW} and {WINDOW} "
            f"(the splits' gaps are {WINDOW} frames)"
        )


def validation_features(
    pipeline: Pipeline, w: Windows, cfg: TrainConfig, source: CaptureSource | None = None
) -> np.ndarray:
    """Model input for validation (early stopping, the temperature): with capture
    augmentation the windows drawn once through it (seed `cfg.seed + 1`), else as they are."""
    if cfg.augment != "capture":
        return features(pipeline, w)
    src = source if source is not None else CaptureSource.from_windows(w)
    xyz = capture_windows(w, src, cfg.capture_mix, np.random.default_rng(cfg.seed + 1),
                          w.xyz.shape[1], clock=cfg.window_clock)  # fmt: skip
    return pipeline.transform(to_metric(xyz, w.aspect), w.has_z)


def augmented(
    pipeline: Pipeline,
    metric: np.ndarray | None,
    w: Windows,
    cfg: TrainConfig,
    rng: np.random.Generator,
    source: CaptureSource | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """One epoch's augmented features and labels: from precomputed metric windows, or
    (`metric` None, capture augmentation) from windows redrawn through the capture model
    and the live filter, then the geometric augmentations."""
    labels = w.labels
    if metric is None:
        src = source if source is not None else CaptureSource.from_windows(w)
        xyz = capture_windows(w, src, cfg.capture_mix, rng, w.xyz.shape[1], clock=cfg.window_clock)
        metric = to_metric(xyz, w.aspect)
    if cfg.transitions:
        metric = transitions(metric, labels, w.scene, rng, cfg.transitions)
    if cfg.time_warp:
        metric = time_warp(metric, rng, cfg.time_warp)
    if cfg.rotate_deg or cfg.yaw_deg:
        metric = rotate(metric, rng, cfg.rotate_deg, cfg.yaw_deg, w.has_z)
    if cfg.mirror:
        flip = rng.random(len(metric)) < 0.5
        m2, l2 = mirror(metric[flip], labels[flip])
        metric = metric.copy()
        labels = labels.copy()
        metric[flip], labels[flip] = m2, l2
    return pipeline.transform(metric, w.has_z), labels


@torch.no_grad()
def predict_logits(model: nn.Module, x: np.ndarray, batch: int = 512) -> np.ndarray:
    """The model's logits (N, 13) for feature windows (N, W, F)."""
    model.eval()
    out = [model(torch.from_numpy(x[i : i + batch])).numpy() for i in range(0, len(x), batch)]
    return np.concatenate(out) if out else np.zeros((0, 13), np.float32)


def softmax(logits: np.ndarray, temperature: float = 1.0) -> np.ndarray:
    """Softmax of logits / temperature along the last axis."""
    z = np.asarray(logits, np.float64) / temperature
    z = np.exp(z - z.max(axis=-1, keepdims=True))
    return (z / z.sum(axis=-1, keepdims=True)).astype(np.float32)


def predict_proba(
    model: nn.Module, x: np.ndarray, batch: int = 512, temperature: float = 1.0
) -> np.ndarray:
    """Softmax probabilities (N, 13) for feature windows (N, W, F), of the logits divided
    by `temperature` (1: the model's own; a fitted one calibrates them, calibration.py)."""
    return softmax(predict_logits(model, x, batch), temperature)


def evaluate_loss(
    model: nn.Module, x: np.ndarray, y: np.ndarray, either: np.ndarray | None = None
) -> tuple[float, float]:
    """(mean cross-entropy, accuracy) on feature windows; `either` (N,) marks windows
    scored on the thumb pair's summed probability (`thumb_unseen`)."""
    if len(x) == 0:
        return float("nan"), float("nan")
    p = predict_proba(model, x)
    loss = -label_logp(np.log(np.clip(p, 1e-9, 1)), y, either).mean()
    return float(loss), float((p.argmax(1) == y).mean())


@dataclass
class EpochLog:
    epoch: int
    train_loss: float
    val_loss: float
    val_accuracy: float
    lr: float
    seconds: float


def _train_epoch(
    model: nn.Module,
    opt: torch.optim.Optimizer,
    loss_fn: nn.Module,
    pipeline: Pipeline,
    metric: np.ndarray | None,
    train: Windows,
    cfg: TrainConfig,
    rng: np.random.Generator,
    penalty: Callable[[nn.Module], torch.Tensor] | None = None,
    source: CaptureSource | None = None,
    after_step: Callable[[nn.Module], None] | None = None,
    either: torch.Tensor | None = None,
) -> float:
    """One epoch over freshly augmented windows (`either`: `pair_mask` of `train`);
    returns the mean training loss."""
    x, y = augmented(pipeline, metric, train, cfg, rng, source)
    order = rng.permutation(len(x))
    model.train()
    total = 0.0
    for i in range(0, len(order), cfg.batch_size):
        idx = order[i : i + cfg.batch_size]
        xb, yb = torch.from_numpy(x[idx]), torch.from_numpy(y[idx])
        opt.zero_grad()
        loss = loss_fn(model(xb), yb, None if either is None else either[idx])
        (loss + penalty(model) if penalty is not None else loss).backward()
        nn.utils.clip_grad_norm_(model.parameters(), cfg.clip_norm)
        opt.step()
        if after_step is not None:
            after_step(model)
        total += loss.item() * len(idx)
    return total / max(len(order), 1)


def _start(
    model: nn.Module, train: Windows, cfg: TrainConfig
) -> tuple[
    np.random.Generator, np.ndarray | None, torch.optim.Optimizer, nn.Module, torch.Tensor | None
]:
    """What every run sets up first: (the seeded rng, the metric windows (None with
    capture augmentation: redrawn each epoch), the optimiser, the loss, the windows taught
    the thumb pair (`pair_mask`; None: every window its label)), with torch's threads and
    seeds set."""
    check_config(cfg)
    torch.set_num_threads(cfg.threads)
    rng = seed_everything(cfg.seed)
    metric = None if cfg.augment == "capture" else to_metric(train.xyz, train.aspect)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    mask = pair_mask(train, cfg)
    either = None if mask is None else torch.from_numpy(mask)
    return rng, metric, opt, PairLoss(cfg.label_smoothing), either


def fit(
    model: nn.Module,
    pipeline: Pipeline,
    train: Windows,
    val: Windows | None,
    cfg: TrainConfig,
    on_epoch: Callable[[EpochLog], None] | None = None,
    penalty: Callable[[nn.Module], torch.Tensor] | None = None,
    source: CaptureSource | None = None,
    val_source: CaptureSource | None = None,
    after_step: Callable[[nn.Module], None] | None = None,
    keep_best: bool = True,
    average_from: int | None = None,
) -> list[EpochLog]:
    """Train `model` in place; with `val`, stop early and restore the best weights
    (`keep_best` False: every epoch runs and the last weights stay; `val` is still scored).
    `average_from` E (with `keep_best` False): the model ends as the mean of its weights
    after each epoch from E on (stochastic weight averaging over the run's tail).

    The pipeline must already be fitted. `penalty(model)`, if given, is added to every
    batch's loss (federated clients use it for FedProx's proximal term); `after_step`
    runs after every optimiser step (SCAFFOLD's drift correction). `source` and
    `val_source` hold the rows before each window for capture augmentation (robust.py;
    without them the frame-rate and loss effects are off). Returns one log entry per epoch.
    """
    rng, metric, opt, loss_fn, either = _start(model, train, cfg)
    xv = (
        validation_features(pipeline, val, cfg, val_source)
        if val is not None and len(val)
        else None
    )
    either_val = pair_mask(val, cfg) if val is not None and len(val) else None
    sched = torch.optim.lr_scheduler.ReduceLROnPlateau(
        opt, factor=cfg.lr_factor, patience=cfg.lr_patience
    )
    best = (float("inf"), copy.deepcopy(model.state_dict()))
    tail = TailAverage()
    history: list[EpochLog] = []
    since_best = 0
    for epoch in range(1, cfg.epochs + 1):
        t0 = time.perf_counter()
        train_loss = _train_epoch(
            model,
            opt,
            loss_fn,
            pipeline,
            metric,
            train,
            cfg,
            rng,
            penalty,
            source,
            after_step,
            either,
        )
        if xv is not None:
            val_loss, val_acc = evaluate_loss(model, xv, val.labels, either_val)  # type: ignore[union-attr]
        else:
            val_loss, val_acc = train_loss, float("nan")
        sched.step(val_loss)
        log = EpochLog(
            epoch,
            train_loss,
            val_loss,
            val_acc,
            opt.param_groups[0]["lr"],
            time.perf_counter() - t0,
        )
        history.append(log)
        if on_epoch:
            on_epoch(log)
        if average_from is not None and epoch >= average_from:
            tail.add(model)
        if val_loss < best[0] - MIN_DELTA:
            best = (val_loss, copy.deepcopy(model.state_dict()))
            since_best = 0
        else:
            since_best += 1
            if xv is not None and keep_best and since_best >= cfg.patience:
                break
    if xv is not None and keep_best:
        model.load_state_dict(best[1])
    elif tail.count:
        model.load_state_dict(tail.mean(model))
    return history


class TailAverage:
    """Running mean of a model's floating-point weights, one `add` per epoch."""

    def __init__(self) -> None:
        self.count = 0
        self.sums: dict[str, torch.Tensor] = {}

    def add(self, model: nn.Module) -> None:
        self.count += 1
        for name, value in model.state_dict().items():
            if value.is_floating_point():
                v = value.detach().to(torch.float64)
                self.sums[name] = self.sums[name] + v if name in self.sums else v.clone()

    def mean(self, model: nn.Module) -> dict[str, torch.Tensor]:
        """The model's state with every floating-point tensor replaced by its mean."""
        state = model.state_dict()
        return {
            name: (self.sums[name] / self.count).to(value.dtype) if name in self.sums else value
            for name, value in state.items()
        }


def chosen_schedule(history: list[EpochLog], lr: float) -> list[float]:
    """The learning rate of each epoch up to the best one (lowest validation loss) of a
    `fit` run that started at `lr`: each log holds the rate after its epoch."""
    best, best_loss = 0, float("inf")
    for i, h in enumerate(history):
        if h.val_loss < best_loss - MIN_DELTA:  # as `fit` chooses
            best, best_loss = i, h.val_loss
    return [lr] + [h.lr for h in history[:best]]


def fit_schedule(
    model: nn.Module,
    pipeline: Pipeline,
    train: Windows,
    cfg: TrainConfig,
    lrs: list[float],
    on_epoch: Callable[[EpochLog], None] | None = None,
    source: CaptureSource | None = None,
) -> list[EpochLog]:
    """Train `model` in place for one epoch per entry of `lrs`, at that learning rate,
    with the same augmentation and clipping as `fit` and no validation (the log's
    validation fields are NaN)."""
    rng, metric, opt, loss_fn, either = _start(model, train, cfg)
    history: list[EpochLog] = []
    for epoch, lr in enumerate(lrs, start=1):
        t0 = time.perf_counter()
        for group in opt.param_groups:
            group["lr"] = lr
        loss = _train_epoch(
            model, opt, loss_fn, pipeline, metric, train, cfg, rng, None, source, None, either
        )
        log = EpochLog(epoch, loss, float("nan"), float("nan"), lr, time.perf_counter() - t0)
        history.append(log)
        if on_epoch:
            on_epoch(log)
    return history
