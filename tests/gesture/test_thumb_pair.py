"""`--thumb-pair either`: all_clear / not_clear windows that cannot show the thumb are
taught only "one of the two" (train.thumb_unseen, train.PairLoss)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torch import nn
from typer.testing import CliRunner

from proxima.cli import app
from proxima.gesture.calibration import fit_temperature, nll
from proxima.gesture.classifier import GestureClassifier
from proxima.gesture.datasets import load_data
from proxima.gesture.train import PAIR, PairLoss, TrainConfig, check_config, thumb_unseen
from proxima.gesture.windows import make_windows

THUMB = ("all_clear", "not_clear")


def _pair_windows(clips, view: str | None, source: str):
    chosen = [
        c for c in clips
        if c.source == source and c.gesture in THUMB and (view is None or c.view == view)
    ]  # fmt: skip
    return make_windows(chosen, 30, 15, 5)


@pytest.fixture(scope="module")
def clips(laser_dir, uav_dir):
    return load_data([str(laser_dir), str(uav_dir)]).clips


def test_the_windows_that_cannot_show_the_thumb_are_those_the_engine_withholds(clips) -> None:
    # UAV-Gesture (OpenPose) has no hand points; LASER's front view sees the right hand,
    # its left view hides it behind the body.
    uav = _pair_windows(clips, None, "uav-gesture")
    front = _pair_windows(clips, "f", "laser")
    left = _pair_windows(clips, "l", "laser")
    assert len(uav) and len(front) and len(left)
    assert thumb_unseen(uav).all()
    assert not thumb_unseen(front).any()
    assert thumb_unseen(left).mean() > 0.9
    # other gestures are never marked, whatever the hand
    hover = make_windows([c for c in clips if c.gesture == "hover"], 30, 15, 5)
    assert not thumb_unseen(hover).any()


def test_the_pair_loss_is_cross_entropy_and_ignores_the_split_within_the_pair() -> None:
    gen = torch.Generator().manual_seed(0)
    logits = torch.randn(64, 13, generator=gen)
    y = torch.tensor([PAIR[i % 2] for i in range(32)] + list(range(13)) * 2 + [0] * 6)
    ref = nn.CrossEntropyLoss(label_smoothing=0.05)(logits, y)
    loss = PairLoss(0.05)
    assert torch.allclose(loss(logits, y), ref)
    assert torch.allclose(loss(logits, y, torch.zeros(64, dtype=torch.bool)), ref)
    pair, y_pair = logits[:32], y[:32]  # windows of the pair
    either = torch.ones(32, dtype=torch.bool)
    swapped = pair.clone()
    swapped[:, PAIR] = pair[:, PAIR[::-1]]
    # marked windows score the pair together: swapping its two logits changes nothing,
    # where unmarked windows' loss does change
    assert torch.allclose(loss(pair, y_pair, either), loss(swapped, y_pair, either))
    assert not torch.allclose(loss(pair, y_pair), loss(swapped, y_pair))
    # and putting the pair's mass on the wrong member of the pair costs nothing extra
    sure = torch.full((1, 13), -10.0)
    sure[0, PAIR[1]] = 10.0
    label = torch.tensor([PAIR[0]])
    as_named = loss(sure, torch.tensor([PAIR[1]]))
    assert torch.allclose(loss(sure, label, torch.tensor([True])), as_named, atol=1e-6)
    assert loss(sure, label) > as_named + 10


def test_the_temperature_fit_scores_marked_windows_on_the_pair() -> None:
    rng = np.random.default_rng(0)
    logits = rng.normal(size=(200, 13)) * 3
    labels = np.where(rng.random(200) < 0.5, PAIR[0], PAIR[1])
    logits[np.arange(200), PAIR[0]] += 4  # the model says all_clear whatever the thumb
    mask = np.ones(200, dtype=bool)
    assert nll(logits, labels, 1.0, mask) < nll(logits, labels, 1.0)
    fit = fit_temperature(logits, labels, mask)
    assert fit.nll_after <= fit.nll_before + 1e-9


def test_an_unknown_thumb_pair_rule_is_refused() -> None:
    with pytest.raises(ValueError, match="thumb pair 'guess'"):
        check_config(TrainConfig(thumb_pair="guess"))


def test_train_takes_the_rule_and_the_checkpoint_records_it(laser_dir, tmp_path) -> None:
    out = tmp_path / "either.pt"
    result = CliRunner().invoke(
        app, ["train", "--data", str(laser_dir), "--split", "temporal", "--out", str(out),
              "--threads", "1", "--epochs", "1", "--stride", "16", "--thumb-pair", "either"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    clf = GestureClassifier.load(out)
    assert clf.metadata["train_config"]["thumb_pair"] == "either"
    assert clf.temperature > 0
    bad = CliRunner().invoke(
        app, ["train", "--data", str(laser_dir), "--split", "temporal", "--out",
              str(tmp_path / "bad.pt"), "--epochs", "1", "--thumb-pair", "guess"],
    )  # fmt: skip
    assert bad.exit_code != 0 and "thumb pair 'guess'" in bad.output
    assert not (tmp_path / "bad.pt").exists()
