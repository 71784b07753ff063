"""An armed operator standing still, through the real engine with the shipped model
(proxima.evaluation.still): relaxed arms command nothing; the static signals' stances
(hands crossed low in front, arms held out) are read as those signals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from proxima.evaluation.still import back_and_forth, still_operator, still_prefix
from proxima.gesture.data_source import resolve_dataset
from proxima.gesture.laser import load_laser_dir

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "models" / "gesture-default.pt"


def test_back_and_forth_keeps_the_recorded_frames_in_order_both_ways() -> None:
    assert back_and_forth(4, 10).tolist() == [0, 1, 2, 3, 2, 1, 0, 1, 2, 3]
    assert back_and_forth(1, 3).tolist() == [0, 0, 0]


def test_still_prefix_ends_where_the_arms_start_to_move() -> None:
    xyz = np.zeros((40, 33, 3), np.float32)
    xyz[20:, 16, 0] = np.arange(1, 21) * 0.05  # the right wrist sweeps from frame 20 on
    # The 5-frame average sees the first step (frames 19 -> 20) two frames early.
    assert still_prefix(xyz) == 17
    assert still_prefix(np.zeros((30, 33, 3), np.float32)) == 30


@pytest.fixture(scope="module")
def clips() -> list:
    return load_laser_dir(resolve_dataset(None))


@pytest.fixture(scope="module")
def stances(clips) -> dict[str, dict]:
    result = still_operator(SHIPPED, clips)
    return {s["clip"]: s for s in result["stances"]}


@pytest.mark.slow
def test_the_dataset_has_still_stances_in_every_view(clips, stances) -> None:
    view = {c.name: c.view for c in clips}
    assert {view[name] for name in stances} == {"f", "l", "r"}
    assert all(s["armed_at_start"] for s in stances.values())


@pytest.mark.slow
@pytest.mark.parametrize(
    "clip", ["DJI_0146_have_command_f", "DJI_0161_move_downward_f", "DJI_0173_slow_down_f"]
)
def test_standing_with_relaxed_arms_commands_nothing(stances, clip) -> None:
    assert stances[clip]["commands"] == []


@pytest.mark.slow
@pytest.mark.parametrize(
    ("clip", "signal"),
    [("DJI_0152_land_f", "land"), ("DJI_0154_land_l", "land"), ("DJI_0149_hover_f", "hover")],
)
def test_a_static_signal_held_still_is_read_as_that_signal(stances, clip, signal) -> None:
    assert [c["command"] for c in stances[clip]["commands"]] == [signal]
