"""The moving-average filter on explicit recognition sequences."""

import numpy as np
import pytest

from proxima.control import MovingAverageFilter
from proxima.types import GESTURES


def onehot(name: str, p: float = 1.0) -> np.ndarray:
    """A probability vector with `p` on `name` and the rest spread evenly."""
    v = np.full(len(GESTURES), (1.0 - p) / (len(GESTURES) - 1))
    v[GESTURES.index(name)] = p
    return v


def test_needs_three_recognitions_before_deciding() -> None:
    f = MovingAverageFilter(GESTURES, size=3, threshold=0.5)
    assert f.update(0.0, onehot("hover")).action == ""
    assert f.update(0.2, onehot("hover")).action == ""
    out = f.update(0.4, onehot("hover"))
    assert out.action == "hover"
    assert out.confidence == pytest.approx(1.0)


def test_single_blip_at_a_transition_is_suppressed() -> None:
    f = MovingAverageFilter(GESTURES, size=3, threshold=0.6)
    for i in range(3):
        f.update(i * 0.2, onehot("move_to_left", 0.9))
    blip = f.update(0.6, onehot("land", 0.99))  # one confident wrong window
    assert blip.action == "move_to_left"  # (0.9 + 0.9 + 0.0008) / 3 >= 0.6
    assert f.update(0.8, onehot("move_to_left", 0.9)).action == "move_to_left"


def test_disagreement_gives_no_action_below_threshold() -> None:
    f = MovingAverageFilter(GESTURES, size=3, threshold=0.8)
    f.update(0.0, onehot("hover", 0.95))
    f.update(0.2, onehot("land", 0.95))
    out = f.update(0.4, onehot("hover", 0.95))
    assert out.action == ""
    assert out.confidence < 0.8


def test_pause_between_recognitions_empties_the_filter() -> None:
    f = MovingAverageFilter(GESTURES, size=3, threshold=0.5, reset_after_s=1.0)
    for i in range(3):
        f.update(i * 0.2, onehot("hover"))
    # Two seconds without recognitions (operator out of view): old ones must not count.
    assert f.update(2.4, onehot("land")).action == ""
    f.update(2.6, onehot("land"))
    assert f.update(2.8, onehot("land")).action == "land"


def test_wrong_length_is_rejected() -> None:
    f = MovingAverageFilter(GESTURES)
    with pytest.raises(ValueError, match="expected 13 probabilities"):
        f.update(0.0, np.ones(12) / 12)


def test_a_command_with_its_own_threshold_passes_on_less_evidence() -> None:
    # wave_off (the abort) at 0.7; everything else still needs 0.9.
    f = MovingAverageFilter(GESTURES, size=3, threshold=0.9, thresholds={"wave_off": 0.7})
    for i in range(3):
        out = f.update(i * 0.2, onehot("wave_off", 0.75))
    assert out.action == "wave_off"
    g = MovingAverageFilter(GESTURES, size=3, threshold=0.9, thresholds={"wave_off": 0.7})
    for i in range(3):
        out = g.update(i * 0.2, onehot("land", 0.75))
    assert out.action == ""
