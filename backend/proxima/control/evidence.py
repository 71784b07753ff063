"""Gestures a window cannot tell apart without the operator's hand.

`all_clear` and `not_clear` differ only in the thumb (up or down). Where the camera does
not see the hand that gives them (a side view with the hand behind the body), the
classifier can only guess between the two from the arm, and a guess must not become a
command: both are withheld from the filter for that window.
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


def hand_seen(visibility: np.ndarray, hand: str, min_visibility: float) -> bool:
    """Whether at least half the frames of a window (`visibility` (W, 33)) see `hand`: the
    median visibility of its finger points reaches `min_visibility`."""
    per_frame = np.median(visibility[:, FINGERS[hand]], axis=1)
    return bool(np.mean(per_frame >= min_visibility) >= 0.5)


class HandEvidence:
    """Zeroes the thumb gestures' probabilities for windows that do not see `hand`
    ("off": never)."""

    def __init__(self, labels: Sequence[str], hand: str, min_visibility: float = 0.5) -> None:
        if hand != "off" and hand not in FINGERS:
            raise ValueError(f"hand must be one of {', '.join(FINGERS)} or off, got {hand!r}")
        self.hand = hand
        self.min_visibility = min_visibility
        self._thumb = [i for i, g in enumerate(labels) if g in THUMB_GESTURES]

    @classmethod
    def from_settings(cls, control: ControlSettings, labels: Sequence[str]) -> HandEvidence:
        return cls(labels, control.thumb_hand, control.hand_visibility)

    def apply(self, probs: np.ndarray, visibility: np.ndarray) -> tuple[np.ndarray, bool]:
        """(`probs` as the filter may use them, whether the thumb gestures were withheld):
        a copy with the thumb gestures at 0 when the window (`visibility` (W, 33)) does
        not see the hand, else `probs` itself."""
        if self.hand == "off" or hand_seen(visibility, self.hand, self.min_visibility):
            return probs, False
        out = np.array(probs, dtype=float)
        out[self._thumb] = 0.0
        return out, True
