"""Gesture classifiers and their configs (one file: a model is its config + weights).

Both map (N, W, F) feature windows to (N, 13) logits; softmax is applied at inference.
- `paper-lstm`: the paper's table, LSTM 30 -> LSTM 64 -> Dense 64 ReLU -> Dropout 0.2 ->
  Dense 32 ReLU -> Dense 13. The table lists "ReLU" for the LSTM layers (Keras'
  `activation="relu"`). torch.nn.LSTM has no such option and a ReLU LSTM written as a
  Python loop trains about 4x and infers about 10x slower, so we keep the standard tanh
  cell and clip gradients at 1.0, which is what keeps the paper's network from
  collapsing to a constant prediction.
- `tcn` (default): a temporal convolutional network, residual dilated 1D convolutions
  with GroupNorm (not BatchNorm: FedAvg would average running statistics), then mean and
  max pooling over time. It sees the whole window at once, is translation-invariant in
  time, and is about 10x faster than the LSTM on a CPU.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import torch
from torch import nn

NUM_CLASSES = 13


@dataclass
class PaperLSTMConfig:
    num_features: int = 99
    num_classes: int = NUM_CLASSES
    dropout: float = 0.2


class PaperLSTM(nn.Module):
    def __init__(self, cfg: PaperLSTMConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.lstm1 = nn.LSTM(cfg.num_features, 30, batch_first=True)
        self.lstm2 = nn.LSTM(30, 64, batch_first=True)
        self.head = nn.Sequential(
            nn.Linear(64, 64),
            nn.ReLU(),
            nn.Dropout(cfg.dropout),
            nn.Linear(64, 32),
            nn.ReLU(),
            nn.Linear(32, cfg.num_classes),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # x: (N, W, F)
        h, _ = self.lstm1(x)  # (N, W, 30)
        h, _ = self.lstm2(h)  # (N, W, 64)
        return self.head(h[:, -1])  # last step -> (N, 13)


@dataclass
class TCNConfig:
    num_features: int = 80
    num_classes: int = NUM_CLASSES
    channels: int = 64
    kernel: int = 5
    dilations: tuple[int, ...] = (1, 2, 4, 8)
    dropout: float = 0.2


class _Block(nn.Module):
    def __init__(self, ch: int, kernel: int, dilation: int, dropout: float) -> None:
        super().__init__()
        pad = dilation * (kernel - 1) // 2
        self.net = nn.Sequential(
            nn.Conv1d(ch, ch, kernel, padding=pad, dilation=dilation),
            nn.GroupNorm(8, ch),
            nn.GELU(),
            nn.Dropout(dropout),
            nn.Conv1d(ch, ch, 1),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.net(x)


class TCN(nn.Module):
    def __init__(self, cfg: TCNConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.stem = nn.Sequential(
            nn.Conv1d(cfg.num_features, cfg.channels, 1), nn.GroupNorm(8, cfg.channels)
        )
        self.blocks = nn.Sequential(
            *[_Block(cfg.channels, cfg.kernel, d, cfg.dropout) for d in cfg.dilations]
        )
        self.head = nn.Sequential(
            nn.Dropout(cfg.dropout), nn.Linear(2 * cfg.channels, cfg.num_classes)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # x: (N, W, F)
        h = self.blocks(self.stem(x.transpose(1, 2)))  # (N, C, W)
        pooled = torch.cat([h.mean(dim=2), h.amax(dim=2)], dim=1)  # (N, 2C)
        return self.head(pooled)  # (N, 13)


MODELS = {"paper-lstm": (PaperLSTM, PaperLSTMConfig), "tcn": (TCN, TCNConfig)}
DEFAULT_MODEL = "tcn"
# The feature pipeline each model is trained with unless told otherwise.
DEFAULT_PIPELINE = {"paper-lstm": "paper", "tcn": "body"}


def build_model(name: str, **config: object) -> nn.Module:
    """A fresh model by name; `config` overrides its config dataclass' fields."""
    if name not in MODELS:
        raise ValueError(f"unknown model {name!r}; choose from {sorted(MODELS)}")
    cls, cfg_cls = MODELS[name]
    if "dilations" in config:
        config["dilations"] = tuple(config["dilations"])  # type: ignore[arg-type]
    return cls(cfg_cls(**config))


def model_config(model: nn.Module) -> dict[str, Any]:
    """The config a model was built from (as `build_model` takes it back).

    Raises:
        TypeError: `model` is none of the models in `MODELS`.
    """
    if not isinstance(model, PaperLSTM | TCN):
        raise TypeError(f"{type(model).__name__} is not a gesture model ({sorted(MODELS)})")
    return asdict(model.cfg)
