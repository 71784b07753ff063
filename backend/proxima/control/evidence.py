"""Gestures a window cannot tell apart without the operator's hand.

`all_clear` and `not_clear` differ only in the thumb (up or down). Where the camera does
not see the hand that gives them (a side view with the hand behind the body), the
classifier can only guess between the two from the arm, and a guess must not become a
command: while the newest window does not see the hand, neither may be the filtered action
(the action is then none, never the next-best gesture).

Both also raise the arm: from hanging to shoulder height and back, so the classifier,
which has no "rest" class, reads an operator standing with the arms hanging as the pair
(0.8-0.95 of the probability for the front view's rest stances with the shipped model).
A window in which the thumb hand's wrist never rises `raise_share` of the way from the hip
to the shoulder (along the body's own axis, so camera roll does not matter) is not the
pair: a hanging arm reaches 0.16 of the way at most, while in LASER's front and right views
98-100 % of the pair's 30-frame windows reach a quarter, 73-100 % seen from 45 degrees
above (docs/experiments.md, "Thirty-fifth session").
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
# Each hand's (wrist, shoulder, hip) on its own side.
ARM = {"left": (15, 11, 23), "right": (16, 12, 24)}


def hands_seen(visibility: np.ndarray, hand: str, min_visibility: float) -> np.ndarray:
    """Per window (`visibility` (..., W, 33)), whether at least half its frames see
    `hand`: the median visibility of its finger points reaches `min_visibility`."""
    per_frame = np.median(visibility[..., list(FINGERS[hand])], axis=-1)
    return np.mean(per_frame >= min_visibility, axis=-1) >= 0.5


def hand_seen(visibility: np.ndarray, hand: str, min_visibility: float) -> bool:
    """`hands_seen` of one window (`visibility` (W, 33))."""
    return bool(hands_seen(visibility, hand, min_visibility))


def arm_raised(
    xyz: np.ndarray,
    visibility: np.ndarray,
    hand: str,
    share: float,
    min_visibility: float,
    aspect: float = 1.0,
) -> bool:
    """Whether `hand`'s wrist rises `share` of the way from its hip to its shoulder in
    some frame of the window (`xyz` (W, 33, 3) in image units, `visibility` (W, 33);
    `aspect` the image's width / height). True when the window does not see that
    shoulder and hip (median visibility under `min_visibility`): nothing to judge by."""
    wrist, shoulder, hip = ARM[hand]
    if np.median(visibility[:, [shoulder, hip]]) < min_visibility:
        return True
    xy = xyz[..., :2] * np.array([aspect, 1.0])
    axis = xy[:, shoulder] - xy[:, hip]
    rise = np.sum((xy[:, wrist] - xy[:, hip]) * axis, axis=-1)
    return bool(np.max(rise / np.maximum(np.sum(axis * axis, axis=-1), 1e-9)) >= share)


class HandEvidence:
    """Withholds the thumb gestures while the window does not see `hand` or, with
    `raise_share` set, while that arm stays down ("off": never)."""

    def __init__(
        self, hand: str, min_visibility: float = 0.5, raise_share: float | None = None
    ) -> None:
        if hand != "off" and hand not in FINGERS:
            raise ValueError(f"hand must be one of {', '.join(FINGERS)} or off, got {hand!r}")
        self.hand = hand
        self.min_visibility = min_visibility
        self.raise_share = raise_share

    @classmethod
    def from_settings(cls, control: ControlSettings) -> HandEvidence:
        return cls(control.thumb_hand, control.hand_visibility, control.thumb_raise)

    def withheld(
        self, visibility: np.ndarray, xyz: np.ndarray | None = None, aspect: float = 1.0
    ) -> list[str]:
        """The gestures that may not be the filtered action while this window
        (`visibility` (W, 33), `xyz` (W, 33, 3) or None: no arm check) is the newest:
        the thumb gestures if it does not see the hand or its arm stays down, else none."""
        if self.hand == "off":
            return []
        if not hand_seen(visibility, self.hand, self.min_visibility):
            return list(THUMB_GESTURES)
        if xyz is None or self.raise_share is None:
            return []
        raised = arm_raised(
            xyz, visibility, self.hand, self.raise_share, self.min_visibility, aspect
        )
        return [] if raised else list(THUMB_GESTURES)

    @staticmethod
    def action(action: str, withheld: Sequence[str]) -> str:
        """The filtered `action` as it may go on: none instead of a withheld gesture."""
        return "" if action in withheld else action
