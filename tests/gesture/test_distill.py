"""Distillation (`proxima train --teacher A,B`): the student is taught the mean of real
checkpoints' calibrated probabilities, the same mean the engine's ensemble gives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.distill import DistillLoss, Teacher
from proxima.gesture.ensemble import EnsembleClassifier
from proxima.gesture.geometry import to_metric
from proxima.gesture.train import PairLoss

ROOT = Path(__file__).resolve().parents[2]
MEMBERS = (  # two real models of one window length and pipeline (tests/data/README.md)
    ROOT / "tests" / "data" / "gesture-capture-60.pt",
    ROOT / "tests" / "data" / "gesture-no-capture.pt",
)


def _windows(laser_clips, n: int = 60):
    """(xyz windows, aspect, labels) from the start of one clip of every gesture."""
    clips = {c.gesture: c for c in laser_clips if c.view == "f" and len(c) >= n + 20}
    xyz = np.stack([c.xyz[10 : 10 + n] for c in clips.values()])
    return xyz, next(iter(clips.values())).aspect


def test_the_teacher_is_the_engines_ensemble_of_its_checkpoints(laser_clips) -> None:
    xyz, aspect = _windows(laser_clips)
    first = GestureClassifier.load(MEMBERS[0])
    teacher = Teacher.load(",".join(map(str, MEMBERS)), first.pipeline)
    x = torch.from_numpy(first.pipeline.transform(to_metric(xyz, aspect), True).astype(np.float32))
    ensemble = EnsembleClassifier.load(MEMBERS).predict(xyz, aspect)
    np.testing.assert_allclose(teacher(x).numpy(), ensemble, atol=1e-5)


def test_the_loss_mixes_the_labels_and_the_teachers_probabilities(laser_clips) -> None:
    xyz, aspect = _windows(laser_clips)
    first = GestureClassifier.load(MEMBERS[0])
    teacher = Teacher.load([str(p) for p in MEMBERS], first.pipeline)
    x = torch.from_numpy(first.pipeline.transform(to_metric(xyz, aspect), True).astype(np.float32))
    y = torch.arange(len(x)) % 13
    logits = torch.randn(len(x), 13, generator=torch.Generator().manual_seed(0))
    label = PairLoss(0.05)
    soft = -(teacher(x) * torch.log_softmax(logits, 1)).sum(1).mean()
    for w in (0.25, 1.0):
        got = DistillLoss(label, teacher, w)(logits, y, None, x)
        assert torch.allclose(got, (1 - w) * label(logits, y) + w * soft)
    # taught only the teachers, the loss is least at their probabilities
    at_teacher = DistillLoss(label, teacher, 1.0)(torch.log(teacher(x)), y, None, x)
    assert at_teacher < DistillLoss(label, teacher, 1.0)(logits, y, None, x)
    with pytest.raises(ValueError, match="in \\(0, 1\\]"):
        DistillLoss(label, teacher, 0.0)
    with pytest.raises(ValueError, match="feature windows"):
        DistillLoss(label, teacher, 0.5)(logits, y)


def test_a_teacher_must_read_the_students_features(laser_dir, tmp_path) -> None:
    out = tmp_path / "s.pt"
    result = CliRunner().invoke(
        app, ["train", "--data", str(laser_dir), "--split", "temporal", "--out", str(out),
              "--pipeline", "body-image", "--teacher", str(MEMBERS[0]), "--epochs", "1",
              "--stride", "30", "--threads", "1", "--window", "60"],
    )  # fmt: skip
    assert result.exit_code == 2
    assert "teacher" in result.output and "pipeline body" in result.output
    assert not out.exists()


def test_the_distilled_student_is_closer_to_its_teachers(laser_dir, laser_clips, tmp_path) -> None:
    """Two short real trainings from the same seed, one taught the two checkpoints'
    ensemble only (`--distill 1`): on held-out-part windows the distilled student's
    probabilities are nearer the ensemble's (KL divergence) than the label-taught one's."""
    teachers = ",".join(map(str, MEMBERS))
    paths = {}
    for name, extra in (("labels", []), ("distilled", ["--teacher", teachers, "--distill", "1"])):
        paths[name] = tmp_path / f"{name}.pt"
        result = CliRunner().invoke(
            app, ["train", "--data", str(laser_dir), "--split", "temporal", "--out",
                  str(paths[name]), "--epochs", "3", "--stride", "12", "--threads", "1",
                  "--window", "60", *extra],
        )  # fmt: skip
        assert result.exit_code == 0, result.output
    clips = [c for c in laser_clips if len(c) >= 100]
    xyz = np.stack([c.xyz[len(c) - 60 :] for c in clips])  # the clips' ends: test parts
    aspect = clips[0].aspect
    target = EnsembleClassifier.load(MEMBERS).predict(xyz, aspect)

    def kl(path: Path) -> float:
        p = GestureClassifier.load(path).predict(xyz, aspect)
        return float(np.mean(np.sum(target * (np.log(target + 1e-9) - np.log(p + 1e-9)), 1)))

    assert kl(paths["distilled"]) < 0.8 * kl(paths["labels"])
    meta = GestureClassifier.load(paths["distilled"]).metadata["train_config"]
    assert meta["teacher"] == teachers and meta["distill"] == 1.0
