"""Temperature scaling (Guo et al., ICML 2017): one scalar T fitted on held-out windows
so that softmax(logits / T) is calibrated; the decision rules in control/ read these
probabilities as evidence, so over- or under-confidence would bias them. T is stored in
the checkpoint and applied by `GestureClassifier`; a checkpoint without one has T = 1.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass

import numpy as np

from proxima.gesture.train import label_logp, softmax

T_RANGE = (0.05, 20.0)


@dataclass(frozen=True)
class TemperatureFit:
    """The fitted temperature and the held-out negative log-likelihood before (T = 1)
    and after, with the expected calibration error (15 bins) before and after."""

    temperature: float
    windows: int
    nll_before: float
    nll_after: float
    ece_before: float
    ece_after: float

    def to_dict(self) -> dict:
        return {k: (round(v, 5) if isinstance(v, float) else v) for k, v in asdict(self).items()}


def nll(
    logits: np.ndarray,
    labels: np.ndarray,
    temperature: float = 1.0,
    either: np.ndarray | None = None,
) -> float:
    """Mean negative log-likelihood of `labels` under softmax(logits / temperature);
    windows marked in `either` score the thumb pair together (`train.label_logp`)."""
    z = np.asarray(logits, np.float64) / temperature
    z = z - z.max(axis=1, keepdims=True)
    logp = z - np.log(np.exp(z).sum(axis=1, keepdims=True))
    return float(-label_logp(logp, labels, either).mean())


def ece(probs: np.ndarray, labels: np.ndarray, bins: int = 15) -> float:
    """Expected calibration error of the top class's probability."""
    conf = probs.max(axis=1)
    right = probs.argmax(axis=1) == labels
    edges = np.linspace(0.0, 1.0, bins + 1)
    total = 0.0
    for lo, hi in itertools.pairwise(edges):
        sel = (conf > lo) & (conf <= hi)
        if sel.any():
            total += sel.mean() * abs(right[sel].mean() - conf[sel].mean())
    return float(total)


def fit_temperature(
    logits: np.ndarray, labels: np.ndarray, either: np.ndarray | None = None
) -> TemperatureFit:
    """The T in `T_RANGE` of least NLL on (logits (N, C), labels (N,)): a log-spaced grid,
    then golden-section search around its best (NLL is convex in 1/T). `either`: as `nll`.

    Raises:
        ValueError: no windows, or logits and labels of different lengths.
    """
    logits = np.asarray(logits, np.float64)
    labels = np.asarray(labels, np.int64)
    if len(logits) == 0 or len(logits) != len(labels):
        raise ValueError(
            f"temperature: need windows with labels, got {len(logits)} and {len(labels)}"
        )
    grid = np.geomspace(*T_RANGE, 61)
    k = int(np.argmin([nll(logits, labels, t, either) for t in grid]))
    lo, hi = math.log(grid[max(k - 1, 0)]), math.log(grid[min(k + 1, len(grid) - 1)])
    g = (math.sqrt(5) - 1) / 2
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = nll(logits, labels, math.exp(a), either), nll(logits, labels, math.exp(b), either)
    for _ in range(40):
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = nll(logits, labels, math.exp(a), either)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = nll(logits, labels, math.exp(b), either)
    t = math.exp((lo + hi) / 2)
    return TemperatureFit(
        temperature=t,
        windows=len(labels),
        nll_before=nll(logits, labels, 1.0, either),
        nll_after=nll(logits, labels, t, either),
        ece_before=ece(softmax(logits), labels),
        ece_after=ece(softmax(logits, t), labels),
    )
