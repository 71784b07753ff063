"""Several gesture classifiers as one: the mean of their calibrated probabilities.

Members trained with different seeds make part of their confident mistakes on different
windows, so the mean keeps the consistent evidence and damps a single member's blip: three
seeds of the capture recipe cut the moving average's wrong commands on held-out streams
by about 40 %; the errors all members share stay (docs/experiments.md, "The full-length
capture recipe held out, seeds and ensembles"). Each member is 0.2 MB and a window costs
it well under a millisecond, small against the pose estimator's frame. The engine loads
one for a `checkpoint` of comma-joined paths (`proxima.engine.load_classifier`), as do
the benchmarks.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from proxima.gesture.classifier import GestureClassifier


class EnsembleClassifier:
    """The mean of `members`' probabilities; members share window and labels."""

    def __init__(self, members: Sequence[GestureClassifier]) -> None:
        if not members:
            raise ValueError("an ensemble needs at least one member")
        first = members[0]
        for m in members[1:]:
            if (
                m.window != first.window
                or tuple(m.labels) != tuple(first.labels)
                or m.window_clock != first.window_clock
            ):
                raise ValueError(
                    f"ensemble members disagree: window {m.window} / {first.window}, "
                    f"labels {len(m.labels)} / {len(first.labels)}, "
                    f"window clock {m.window_clock} / {first.window_clock}"
                )
        self.members = list(members)
        self.window = first.window
        self.window_clock = first.window_clock
        self.labels = tuple(first.labels)
        self.model_name = "+".join(m.model_name for m in members)

    @classmethod
    def load(cls, paths: Sequence[str | Path]) -> EnsembleClassifier:
        """The ensemble of the checkpoints at `paths` (see `GestureClassifier.load`)."""
        return cls([GestureClassifier.load(p) for p in paths])

    def predict(self, xyz: np.ndarray, aspect: float | np.ndarray = 16 / 9) -> np.ndarray:
        """Mean softmax probabilities (N, 13) of the members for windows (N, W, 33, 3)."""
        probs = [m.predict(xyz, aspect) for m in self.members]
        return np.mean(probs, axis=0)


def load_checkpoint(path: str | Path | None) -> GestureClassifier | EnsembleClassifier:
    """The classifier at `path` (default: the shipped checkpoint); comma-joined paths
    (`a.pt,b.pt,c.pt`) are an ensemble of those checkpoints.

    Raises:
        FileNotFoundError: no such checkpoint.
        ValueError: the file is not a Proxima gesture checkpoint, or ensemble members
            disagree on window or labels.
    """
    if path is not None and "," in str(path):
        return EnsembleClassifier.load([p.strip() for p in str(path).split(",") if p.strip()])
    return GestureClassifier.load(path)
