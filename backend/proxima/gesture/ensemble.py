"""Several gesture classifiers as one: the mean of their calibrated probabilities.

Members trained with different seeds make part of their confident mistakes on different
windows, so the mean keeps the consistent evidence and damps a single member's blip: on
held-out streams three seeds of the shipped recipe give a third to a tenth of one
model's wrong commands that move a drone (docs/experiments.md, "Twenty-eighth session");
the errors all members share stay. Each member is 0.2 MB and a window costs it well under
a millisecond, small against the pose estimator's frame.

An ensemble is one file (`ENSEMBLE_FORMAT`: each member's checkpoint contents and the
ensemble's own metadata; `save_ensemble`, `proxima ensemble join`) or comma-joined paths
(`a.pt,b.pt,c.pt`); `load_checkpoint` reads both, and one model's file. The shipped model
is such a file.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from proxima.gesture.classifier import (
    ENSEMBLE_FORMAT,
    GestureClassifier,
    created_now,
    read_blob,
    write_blob,
)


class EnsembleClassifier:
    """The mean of `members`' probabilities; members share window and labels."""

    def __init__(
        self, members: Sequence[GestureClassifier], metadata: dict[str, Any] | None = None
    ) -> None:
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
        # the file's own metadata (created, command, members' seeds); {} for joined paths
        self.metadata: dict[str, Any] = dict(metadata or {})

    @classmethod
    def load(cls, paths: Sequence[str | Path]) -> EnsembleClassifier:
        """The ensemble of the one-model checkpoints at `paths` (`GestureClassifier.load`)."""
        return cls([GestureClassifier.load(p) for p in paths])

    def predict(self, xyz: np.ndarray, aspect: float | np.ndarray = 16 / 9) -> np.ndarray:
        """Mean softmax probabilities (N, 13) of the members for windows (N, W, 33, 3)."""
        probs = [m.predict(xyz, aspect) for m in self.members]
        return np.mean(probs, axis=0)


def save_ensemble(
    path: str | Path, members: Sequence[GestureClassifier], metadata: dict[str, Any]
) -> Path:
    """Write `members` as one ensemble file (atomically), each with its own metadata.

    Raises:
        ValueError: fewer than two members, or members that disagree (window, labels).
    """
    if len(members) < 2:
        raise ValueError(f"an ensemble file needs at least two members, got {len(members)}")
    EnsembleClassifier(members)  # the same checks as loading it
    blob = {
        "format": ENSEMBLE_FORMAT,
        "members": [m.blob() for m in members],
        "metadata": {"created": created_now(), **metadata},
    }
    return write_blob(path, blob)


def load_checkpoint(path: str | Path | None) -> GestureClassifier | EnsembleClassifier:
    """The classifier at `path` (default: the shipped checkpoint): one model, an ensemble
    file, or comma-joined paths (`a.pt,b.pt,c.pt`), the ensemble of those checkpoints.

    Raises:
        FileNotFoundError: no such checkpoint.
        ValueError: the file is not a Proxima gesture checkpoint, or ensemble members
            disagree on window or labels.
    """
    if path is not None and "," in str(path):
        return EnsembleClassifier.load([p.strip() for p in str(path).split(",") if p.strip()])
    where, blob = read_blob(path)
    if blob["format"] != ENSEMBLE_FORMAT:
        return GestureClassifier.from_blob(blob, where)
    members = blob.get("members")
    if not isinstance(members, list) or len(members) < 2:
        raise ValueError(f"{where}: an ensemble file without its members")
    models = [GestureClassifier.from_blob(m, f"{where} member {i}") for i, m in enumerate(members)]
    return EnsembleClassifier(models, blob.get("metadata", {}))


def members_of(clf: GestureClassifier | EnsembleClassifier) -> list[GestureClassifier]:
    """The one-model classifiers that make `clf` (itself, for one model)."""
    return list(clf.members) if isinstance(clf, EnsembleClassifier) else [clf]
