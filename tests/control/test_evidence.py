"""The thumb gestures need the operator's hand in view: checked on the LASER clips, where
the left camera sees the operator's left side and the right hand is behind the body."""

import numpy as np
import pytest
from pydantic import ValidationError

from proxima.control import ControlSettings, HandEvidence
from proxima.control.evidence import hand_seen, hands_seen
from proxima.types import GESTURES


def windows_seen(clip, hand: str) -> float:
    """Share of a clip's 60-frame windows (step 30) that see `hand`."""
    starts = range(0, len(clip) - 60, 30)
    return float(np.mean([hand_seen(clip.visibility[s : s + 60], hand, 0.5) for s in starts]))


def test_the_side_cameras_see_the_hand_on_their_side_only(laser_clips) -> None:
    clips = {c.name.split("_", 2)[2]: c for c in laser_clips}
    for gesture in ("all_clear", "not_clear"):
        assert windows_seen(clips[f"{gesture}_f"], "right") == 1.0
        assert windows_seen(clips[f"{gesture}_r"], "right") == 1.0
        assert windows_seen(clips[f"{gesture}_l"], "right") == 0.0
        assert windows_seen(clips[f"{gesture}_l"], "left") > 0.8
    # the batch form (training's mask) judges every window as the engine does
    clip = clips["all_clear_l"]
    batch = np.stack([clip.visibility[s : s + 60] for s in range(0, len(clip) - 60, 7)])
    for hand in ("left", "right"):
        assert hands_seen(batch, hand, 0.5).tolist() == [hand_seen(v, hand, 0.5) for v in batch]


def test_a_hidden_hand_withholds_only_the_thumb_gestures(laser_clips) -> None:
    hidden = next(c for c in laser_clips if c.name.endswith("all_clear_l")).visibility[:60]
    seen = next(c for c in laser_clips if c.name.endswith("all_clear_f")).visibility[:60]
    evidence = HandEvidence.from_settings(ControlSettings())
    withheld = evidence.withheld(hidden)
    assert withheld == ["all_clear", "not_clear"] and evidence.withheld(seen) == []
    # a withheld gesture becomes no action at all, never the next-best gesture
    assert [evidence.action(g, withheld) for g in GESTURES] == [
        "" if g in ("all_clear", "not_clear") else g for g in GESTURES
    ]
    assert [evidence.action(g, []) for g in GESTURES] == list(GESTURES)
    assert HandEvidence.from_settings(ControlSettings(thumb_hand="off")).withheld(hidden) == []
    assert HandEvidence("left").withheld(hidden) == []  # the left hand faces that camera


def test_a_bad_hand_setting_is_refused() -> None:
    with pytest.raises(ValidationError, match="thumb_hand"):
        ControlSettings(thumb_hand="middle")
    with pytest.raises(ValueError, match="hand must be one of left, right or off"):
        HandEvidence("middle")
