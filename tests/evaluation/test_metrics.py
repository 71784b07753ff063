"""`proxima evaluate` (proxima.evaluation.metrics): the named fields, every LASER view
scored on its own, and the confusion picture, for a briefly trained checkpoint."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from proxima.cli import app
from proxima.types import GESTURES


def test_evaluate_writes_the_named_fields_and_a_confusion_png(
    small_checkpoint, laser_dir, tmp_path
) -> None:
    out = tmp_path / "metrics.json"
    result = CliRunner().invoke(
        app, ["evaluate", "--checkpoint", str(small_checkpoint), "--data", str(laser_dir),
              "--split", "temporal", "--json", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    m = json.loads(out.read_text())
    for key in ("accuracy", "macro_precision", "macro_recall", "macro_f1", "per_class",
                "confusion", "clip_accuracy"):  # fmt: skip
        assert key in m
    assert set(m["per_class"]) == set(GESTURES)
    assert np.asarray(m["confusion"]).shape == (13, 13)
    assert m["clips"] == 39
    # every LASER view is scored on its own, and together they are the whole test part
    assert set(m["per_view"]) == {"f", "l", "r"}
    assert sum(v["windows"] for v in m["per_view"].values()) == m["windows"]
    overall = sum(v["accuracy"] * v["windows"] for v in m["per_view"].values()) / m["windows"]
    assert abs(overall - m["accuracy"]) < 1e-9
    # four epochs on coarse windows already learn far above chance (1/13)
    assert m["accuracy"] > 0.3
    assert out.with_suffix(".png").stat().st_size > 10_000


def test_evaluate_scores_an_ensemble_of_comma_joined_checkpoints(
    small_checkpoint, laser_dir, tmp_path
) -> None:
    """`--checkpoint a.pt,b.pt` scores the mean of the members' calibrated probabilities,
    as the engine runs an ensemble: two copies of one model score as that model, and a
    second, different member changes the result."""
    from proxima.evaluation.metrics import evaluate_checkpoint

    one = evaluate_checkpoint(small_checkpoint, [str(laser_dir)], "cross-view:l", stride=12)
    twice = evaluate_checkpoint(f"{small_checkpoint},{small_checkpoint}", [str(laser_dir)],
                                "cross-view:l", stride=12)  # fmt: skip
    assert twice["confusion"] == one["confusion"] and twice["windows"] == one["windows"]
    assert twice["model"] == "tcn+tcn"
    # another real 60-frame model (the shipped one has 30-frame windows)
    shipped = Path(__file__).resolve().parents[2] / "tests" / "data" / "gesture-capture-60.pt"
    pair = f"{small_checkpoint},{shipped}"
    out = tmp_path / "pair.json"
    result = CliRunner().invoke(app, ["evaluate", "--checkpoint", pair, "--data", str(laser_dir),
                                      "--split", "cross-view:l", "--stride", "12",
                                      "--json", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    m = json.loads(out.read_text())
    alone = evaluate_checkpoint(shipped, [str(laser_dir)], "cross-view:l", stride=12)
    assert m["confusion"] != one["confusion"] and m["confusion"] != alone["confusion"]
    assert out.with_suffix(".png").stat().st_size > 10_000
