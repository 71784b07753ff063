"""Model, local training and scoring for federated runs: the centralised code
(`proxima.gesture.models`, `features`, `train`) with Flower's ArrayRecord at the edges.

Nothing here knows about Flower's apps or engines; the ClientApp and ServerApp are thin
wrappers around these functions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch
from flwr.app import Array, ArrayRecord
from torch import nn

from proxima.federated.config import ConfigError, FLConfig
from proxima.gesture.features import Pipeline, make_pipeline
from proxima.gesture.models import build_model
from proxima.gesture.train import (
    TrainConfig,
    chosen_schedule,
    evaluate_loss,
    features,
    fit,
    validation_features,
)
from proxima.gesture.windows import Windows


def new_model(cfg: FLConfig) -> tuple[nn.Module, Pipeline]:
    """A freshly initialised model (seeded, so every party starts identical) and the
    scale-free feature pipeline."""
    pipeline = make_pipeline(cfg.pipeline)
    torch.manual_seed(cfg.seed)
    return build_model(cfg.model, num_features=pipeline.num_features), pipeline


def start_model(cfg: FLConfig) -> tuple[nn.Module, Pipeline]:
    """The global model of round 0: `new_model`, or with `cfg.init` that checkpoint's
    weights (pretraining the drones then fine-tune; the drones need no copy of it, they
    receive the weights in round 1).

    Raises:
        ConfigError: `init` cannot be read, or is another model or pipeline than the run's.
    """
    model, pipeline = new_model(cfg)
    if not cfg.init:
        return model, pipeline
    from proxima.gesture.workflow import start_checkpoint

    try:
        start = start_checkpoint(cfg.init, cfg.model, cfg.pipeline)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"run config 'init': {exc}") from None
    set_weights(model, get_weights(start.model))
    return model, pipeline


def get_weights(model: nn.Module) -> dict[str, np.ndarray]:
    return {k: v.detach().cpu().numpy().copy() for k, v in model.state_dict().items()}


def named_arrays(record: ArrayRecord) -> dict[str, np.ndarray]:
    """Flower's ArrayRecord as named numpy arrays."""
    return {k: a.numpy() for k, a in record.items()}


def arrays_of(named: dict[str, np.ndarray]) -> ArrayRecord:
    """Named numpy arrays as Flower's ArrayRecord."""
    return ArrayRecord({k: Array(np.ascontiguousarray(v, np.float32)) for k, v in named.items()})


def set_weights(model: nn.Module, weights: dict[str, np.ndarray]) -> None:
    """Load weights (float arrays by state-dict key).

    Raises:
        ValueError: a missing or unexpected key, or an array of the wrong shape.
    """
    own = model.state_dict()
    if set(weights) != set(own):
        missing, extra = sorted(set(own) - set(weights)), sorted(set(weights) - set(own))
        raise ValueError(f"weights do not fit the model: missing {missing}, unexpected {extra}")
    for k, v in own.items():
        if tuple(np.shape(weights[k])) != tuple(v.shape):
            raise ValueError(
                f"weight {k!r}: shape {np.shape(weights[k])}, model has {tuple(v.shape)}"
            )
    model.load_state_dict(
        {k: torch.as_tensor(np.asarray(weights[k]), dtype=v.dtype) for k, v in own.items()}
    )


def proximal_penalty(model: nn.Module, mu: float) -> Callable[[nn.Module], torch.Tensor] | None:
    """FedProx's (mu / 2) * ||w - w_global||^2 against the weights the model has now."""
    if mu <= 0:
        return None
    anchor = [p.detach().clone() for p in model.parameters()]

    def penalty(m: nn.Module) -> torch.Tensor:
        return (mu / 2) * sum(
            ((p - a) ** 2).sum() for p, a in zip(m.parameters(), anchor, strict=True)
        )  # type: ignore[return-value]

    return penalty


def control_step(
    correction: dict[str, np.ndarray] | None, lr: float
) -> Callable[[nn.Module], None] | None:
    """SCAFFOLD's drift correction, applied after every optimiser step: w -= lr (c - c_i),
    with c and c_i in the units of an AdamW step (`next_control`), so each step moves
    the way the fleet's average step did rather than the way this drone's view pulls."""
    if not correction:
        return None

    def step(model: nn.Module) -> None:
        with torch.no_grad():
            for name, p in model.named_parameters():
                if name not in correction:
                    raise ValueError(f"control variates lack parameter {name!r}")
                p.sub_(lr * torch.as_tensor(correction[name], dtype=p.dtype))

    return step


def next_control(
    start: dict[str, np.ndarray],
    end: dict[str, np.ndarray],
    steps: int,
    lr: float,
    correction: dict[str, np.ndarray] | None,
) -> dict[str, np.ndarray]:
    """SCAFFOLD's control variate update, "option II": c_i+ = c_i - c + (x - y_i) / (K lr),
    the drone's mean step over its K steps from the fleet's weights x to its own y_i,
    less the correction c - c_i it applied (None: none yet). The models' state dicts are
    their parameters (GroupNorm, no buffers), so weights and variates share keys."""
    return {
        k: ((x - end[k]) / (max(steps, 1) * lr) - (correction[k] if correction else 0.0)).astype(
            np.float32
        )
        for k, x in start.items()
    }


@dataclass
class LocalResult:
    """What a drone reports after its local epochs (no data, only numbers)."""

    num_examples: int
    train_loss: float
    val_loss: float
    val_accuracy: float
    epochs: int
    seconds: float
    steps: int  # optimiser steps up to the weights kept (the best epoch's)
    lr: float  # the round's starting learning rate


def train_local(
    model: nn.Module,
    pipeline: Pipeline,
    fit_w: Windows,
    val_w: Windows,
    cfg: FLConfig,
    server_round: int,
    partition_id: int,
    correction: dict[str, np.ndarray] | None = None,
) -> LocalResult:
    """The paper's local step: `local_epochs` epochs of the centralised loop (AdamW,
    ReduceLROnPlateau, early stopping with best weights, gradient clipping), seeded per
    round and drone, with FedProx's proximal term or SCAFFOLD's `correction` (c - c_i)
    when the strategy asks for it. The
    starting learning rate decays by `lr_decay` per round, standing in for the decay the
    centralised run's ReduceLROnPlateau brings over many epochs. With `local_weights`
    "last" the drone sends the weights after its last local epoch (and that epoch's
    validation figures) instead of its best epoch's; with "mean", the mean of its weights
    after each epoch of the round's second half (epochs E // 2 + 1 to E), a flatter
    point that may average better across drones; its step count (SCAFFOLD's control
    variate) is that of the middle averaged epoch."""
    t0 = time.perf_counter()
    tc = TrainConfig(
        epochs=cfg.local_epochs,
        patience=cfg.patience,
        batch_size=cfg.batch_size,
        lr=cfg.learning_rate * cfg.lr_decay ** max(server_round - 1, 0),
        seed=cfg.seed + 1000 * server_round + partition_id,
        stride=cfg.stride,
        max_gap=cfg.max_gap,
        threads=cfg.threads,
        mirror=cfg.mirror,
        augment=cfg.augment,
    )
    mu = cfg.proximal_mu if cfg.strategy == "fedprox" else 0.0
    keep_best = cfg.local_weights == "best"
    average_from = cfg.local_epochs // 2 + 1 if cfg.local_weights == "mean" else None
    history = fit(
        model,
        pipeline,
        fit_w,
        val_w if len(val_w) else None,
        tc,
        penalty=proximal_penalty(model, mu),
        after_step=control_step(correction, tc.lr),
        keep_best=keep_best,
        average_from=average_from,
    )
    # the weights sent: those `fit` restored (best), the last, or the mean of the round's
    # second half, scored on fit's validation draw; `kept` counts the epochs up to them
    # (the middle averaged epoch for the mean)
    sent = history[-1]
    kept: float = len(history)
    if len(val_w) and keep_best:
        kept = len(chosen_schedule(history, tc.lr))
        sent = history[int(kept) - 1]
    val_loss, val_accuracy = sent.val_loss, sent.val_accuracy
    if average_from is not None:
        kept = (average_from + len(history)) / 2
        if len(val_w):
            xv = validation_features(pipeline, val_w, tc)
            val_loss, val_accuracy = evaluate_loss(model, xv, val_w.labels)
    return LocalResult(
        num_examples=len(fit_w),
        train_loss=float(history[-1].train_loss),
        val_loss=float(val_loss),
        val_accuracy=float(val_accuracy),
        epochs=len(history),
        seconds=time.perf_counter() - t0,
        steps=round(kept * math.ceil(len(fit_w) / tc.batch_size)),
        lr=tc.lr,
    )


class Scorer:
    """Loss and accuracy of weights on fixed windows; features computed once."""

    def __init__(self, cfg: FLConfig, windows: Windows) -> None:
        self.model, self.pipeline = new_model(cfg)
        self.windows = windows
        self.x = features(self.pipeline, windows) if len(windows) else None

    def __call__(self, weights: dict[str, np.ndarray]) -> tuple[float, float]:
        if self.x is None:
            return float("nan"), float("nan")
        set_weights(self.model, weights)
        return evaluate_loss(self.model, self.x, self.windows.labels)
