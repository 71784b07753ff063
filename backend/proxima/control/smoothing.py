"""The paper's moving-average filter over the last few recognitions of one stream.

A single window that straddles two gestures often scores a third one with high
confidence; averaging the probabilities of consecutive recognitions (three in the paper)
and asking for a minimum averaged confidence suppresses those blips.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from proxima.control.config import ControlSettings


@dataclass(frozen=True)
class FilteredAction:
    """The filter's decision at stream time `t`: `action` is "" when the filter is not yet
    full or no class reaches the threshold; `confidence` is the best averaged probability."""

    t: float
    action: str
    confidence: float
    probs: np.ndarray


class MovingAverageFilter:
    """Average of the last `size` probability vectors; an action passes at `threshold`,
    or at its own entry in `thresholds` (label -> threshold).

    The filter empties itself when recognitions pause for `reset_after_s` stream seconds
    (the operator left the view, the window restarted), so stale recognitions never mix
    with new ones.
    """

    def __init__(
        self,
        labels: Sequence[str],
        size: int = 3,
        threshold: float = 0.8,
        reset_after_s: float = 1.0,
        thresholds: Mapping[str, float] | None = None,
    ) -> None:
        if size < 1:
            raise ValueError(f"filter size must be >= 1, got {size}")
        self.labels = tuple(labels)
        self.size = size
        self.threshold = threshold
        self.thresholds = dict(thresholds or {})
        self.reset_after_s = reset_after_s
        self._history: deque[np.ndarray] = deque(maxlen=size)
        self._last_t: float | None = None

    @classmethod
    def from_settings(cls, control: ControlSettings, labels: Sequence[str]) -> MovingAverageFilter:
        """The filter `control` describes (size, thresholds, reset) over `labels`."""
        return cls(
            labels,
            control.filter_size,
            control.threshold,
            control.filter_reset_s,
            control.threshold_by_command,
        )

    def reset(self) -> None:
        """Forget every recognition."""
        self._history.clear()
        self._last_t = None

    def update(self, t: float, probs: np.ndarray, bridged: bool = False) -> FilteredAction:
        """Add one recognition (probabilities over `labels`) and decide. Every recognition
        counts alike here (`bridged` is for the evidence rule).

        Raises:
            ValueError: `probs` does not have one entry per label.
        """
        probs = np.asarray(probs, dtype=np.float64).reshape(-1)
        if probs.shape[0] != len(self.labels):
            raise ValueError(f"expected {len(self.labels)} probabilities, got {probs.shape[0]}")
        if self._last_t is not None and t - self._last_t > self.reset_after_s:
            self._history.clear()
        self._last_t = t
        self._history.append(probs)
        mean = np.mean(self._history, axis=0)
        best = int(np.argmax(mean))
        confidence = float(mean[best])
        full = len(self._history) == self.size
        needed = self.thresholds.get(self.labels[best], self.threshold)
        action = self.labels[best] if full and confidence >= needed else ""
        return FilteredAction(t=t, action=action, confidence=confidence, probs=mean)

    def withhold(self, labels: Sequence[str]) -> None:
        """Nothing to drop: the average forgets in `size` recognitions, and with `confirm`
        2 (`AVERAGE_RULE`) two newest windows in a row must see the hand."""
