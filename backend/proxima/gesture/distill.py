"""Distillation: a student model taught an ensemble's calibrated probabilities beside the
labels, so that one checkpoint (what calibration, federated runs and promotion handle)
behaves like several. On held-out streams an ensemble of two 30-frame seeds gives as many
commands as one model with a third to a half of the wrong motion commands under `field`
(docs/experiments.md, "Twenty-eighth session"): its members disagree on the confusable
stretches, which damps the confidence the evidence rule sums.

The teachers read the student's own feature windows (the same pipeline, fitted state
included), after the epoch's augmentation, so the soft target follows every capture draw.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import torch
from torch import nn

from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.features import Pipeline


class Teacher:
    """The mean of checkpoints' calibrated probabilities for feature windows (N, W, F)."""

    def __init__(self, members: Sequence[GestureClassifier]) -> None:
        if not members:
            raise ValueError("distillation needs at least one teacher checkpoint")
        self.members = list(members)

    @classmethod
    def load(cls, paths: str | Sequence[str | Path], pipeline: Pipeline) -> Teacher:
        """The teachers at `paths` (comma-joined or a list), checked to read `pipeline`'s
        features as the student does.

        Raises:
            ValueError: a teacher's pipeline or features differ from the student's.
        """
        if isinstance(paths, str):
            paths = [p.strip() for p in paths.split(",") if p.strip()]
        members = [GestureClassifier.load(p) for p in paths]
        for path, m in zip(paths, members, strict=True):
            if m.pipeline.name != pipeline.name or m.pipeline.num_features != pipeline.num_features:
                raise ValueError(
                    f"teacher {path}: pipeline {m.pipeline.name} ({m.pipeline.num_features} "
                    f"features), the student's is {pipeline.name} ({pipeline.num_features})"
                )
        return cls(members)

    @torch.no_grad()
    def __call__(self, x: torch.Tensor) -> torch.Tensor:
        probs = [torch.softmax(m.model.eval()(x) / m.temperature, dim=1) for m in self.members]
        return torch.stack(probs).mean(dim=0)


class DistillLoss(nn.Module):
    """(1 - `weight`) x the label loss + `weight` x the cross-entropy of the student's
    probabilities against the teacher's (the KL divergence up to the teacher's entropy)."""

    def __init__(self, label_loss: nn.Module, teacher: Teacher, weight: float) -> None:
        super().__init__()
        if not 0.0 < weight <= 1.0:
            raise ValueError(f"distillation weight must be in (0, 1], got {weight}")
        self.label_loss = label_loss
        self.teacher = teacher
        self.weight = weight

    def forward(
        self,
        logits: torch.Tensor,
        y: torch.Tensor,
        either: torch.Tensor | None = None,
        x: torch.Tensor | None = None,
    ) -> torch.Tensor:
        if x is None:
            raise ValueError("distillation needs the batch's feature windows")
        soft = -(self.teacher(x) * torch.log_softmax(logits, dim=1)).sum(dim=1).mean()
        return (1 - self.weight) * self.label_loss(logits, y, either) + self.weight * soft
