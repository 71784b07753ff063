"""The temporal-split error analysis (proxima.evaluation.temporal_errors): its accuracy is
the one `proxima evaluate` reports for the same checkpoint, and its wrong stretches are
exact."""

from pathlib import Path

import numpy as np
import pytest
import torch

from proxima.evaluation.metrics import evaluate_checkpoint
from proxima.evaluation.plots import plot_temporal_errors
from proxima.evaluation.temporal_errors import analyse, nearest_labels, stretches

# a real trained model of the analysis's 60-frame windows (tests/data/README.md)
SHIPPED = Path(__file__).resolve().parents[2] / "tests" / "data" / "gesture-capture-60.pt"


def test_stretches_are_runs_of_one_wrong_label() -> None:
    labels = ["a", "b", "c"]
    truth = np.zeros(9, dtype=int)
    pred = np.array([0, 1, 1, 2, 0, 0, 2, 2, 0])
    assert stretches(pred, truth, labels) == [
        {"start": 1, "length": 2, "predicted": "b"},
        {"start": 3, "length": 1, "predicted": "c"},
        {"start": 6, "length": 2, "predicted": "c"},
    ]
    assert stretches(truth, truth, labels) == []


def test_nearest_labels_finds_the_closest_row() -> None:
    train = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    got = nearest_labels(train, np.array([7, 8, 9]), np.array([[9.0, 1.0], [1.0, 8.0], [0.1, 0]]))
    assert got.tolist() == [8, 9, 7]


def test_analysis_agrees_with_evaluate(small_checkpoint: Path, laser_dir: Path, tmp_path) -> None:
    result = analyse([small_checkpoint, SHIPPED], str(laser_dir))
    plot_temporal_errors(result, tmp_path / "errors.png")
    assert (tmp_path / "errors.png").stat().st_size > 10_000
    evaluated = evaluate_checkpoint(small_checkpoint, [str(laser_dir)], "temporal")
    assert result["test_windows"] == evaluated["windows"]
    small, shipped = result["models"]
    assert abs(small["accuracy"] - evaluated["accuracy"]) < 1e-9
    assert small["wrong"] > 0  # four coarse epochs leave errors to lay out
    assert small["wrong"] == sum(c["wrong"][0] for c in result["clips"])
    assert result["wrong_in_every_model"] <= min(small["wrong"], shipped["wrong"])
    assert small["wrong_and_nearest_neighbour_agrees"] <= small["wrong_and_nearest_neighbour_wrong"]
    # One person, same views: the model-free check is far above chance (1/13).
    assert 0.5 < result["nearest_neighbour_accuracy"] <= 1.0
    for clip in result["clips"]:
        assert sum(s["length"] for s in clip["model_stretches"][0]) == clip["wrong"][0]


def test_a_checkpoint_with_other_labels_is_refused(small_checkpoint: Path, laser_dir, tmp_path):
    blob = torch.load(small_checkpoint, weights_only=False)
    blob["labels"] = list(reversed(blob["labels"]))
    other = tmp_path / "other-labels.pt"
    torch.save(blob, other)
    with pytest.raises(ValueError, match=r"other-labels\.pt: labels"):
        analyse([other], str(laser_dir))
