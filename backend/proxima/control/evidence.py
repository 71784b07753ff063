"""Gestures a window cannot tell apart without the operator's hand.

`all_clear` and `not_clear` differ only in the thumb (up or down). Where the camera does
not see the hand that gives them (a side view with the hand behind the body), the
classifier can only guess between the two from the arm, and a guess must not become a
command: while the newest window does not see the hand, neither may be the filtered action
(the action is then none, never the next-best gesture).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from proxima.control.config import ControlSettings

THUMB_GESTURES = ("all_clear", "not_clear")
# MediaPipe's pinky, index and thumb points of each hand (the wrist is seen far more
# often than the fingers, so it does not count).
FINGERS = {"left": (17, 19, 21), "right": (18, 20, 22)}


def hands_seen(visibility: np.ndarray, hand: str, min_visibility: float) -> np.ndarray:
    """Per window (`visibility` (..., W, 33)), whether at least half its frames see
    `hand`: the median visibility of its finger points reaches `min_visibility`."""
    per_frame = np.median(visibility[..., list(FINGERS[hand])], axis=-1)
    return np.mean(per_frame >= min_visibility, axis=-1) >= 0.5


def hand_seen(visibility: np.ndarray, hand: str, min_visibility: float) -> bool:
    """`hands_seen` of one window (`visibility` (W, 33))."""
    return bool(hands_seen(visibility, hand, min_visibility))


class HandEvidence:
    """Withholds the thumb gestures while the window does not see `hand` ("off": never)."""

    def __init__(self, hand: str, min_visibility: float = 0.5) -> None:
        if hand != "off" and hand not in FINGERS:
            raise ValueError(f"hand must be one of {', '.join(FINGERS)} or off, got {hand!r}")
        self.hand = hand
        self.min_visibility = min_visibility

    @classmethod
    def from_settings(cls, control: ControlSettings) -> HandEvidence:
        return cls(control.thumb_hand, control.hand_visibility)

    def withheld(self, visibility: np.ndarray) -> list[str]:
        """The gestures that may not be the filtered action while this window
        (`visibility` (W, 33)) is the newest: the thumb gestures if it does not see the
        hand, else none."""
        if self.hand == "off" or hand_seen(visibility, self.hand, self.min_visibility):
            return []
        return list(THUMB_GESTURES)

    @staticmethod
    def action(action: str, withheld: Sequence[str]) -> str:
        """The filtered `action` as it may go on: none instead of a withheld gesture."""
        return "" if action in withheld else action
