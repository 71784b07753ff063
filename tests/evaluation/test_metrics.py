"""`proxima evaluate` (proxima.evaluation.metrics): the named fields, every LASER view
scored on its own, and the confusion picture, for a briefly trained checkpoint."""

from __future__ import annotations

import json

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
