"""Small value types shared by every stage of the frame -> drone-command path.

Everything that crosses a module boundary is one of these; library types (MediaPipe,
pymavlink, torch) are converted where they enter and never leave their module.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum, StrEnum

import numpy as np

# The 13 UAV marshalling gestures, in the order the classifier's outputs use.
GESTURES: tuple[str, ...] = (
    "all_clear",
    "have_command",
    "hover",
    "land",
    "land_direction",
    "move_ahead",
    "move_downward",
    "move_to_left",
    "move_to_right",
    "move_upward",
    "not_clear",
    "slow_down",
    "wave_off",
)

NUM_LANDMARKS = 33  # MediaPipe BlazePose topology


@dataclass(frozen=True, eq=False)
class Pose:
    """One person's 33 MediaPipe landmarks in one frame.

    `xyz` is (33, 3): x, y normalised to the image (0..1, may leave it), z depth relative
    to the hips in roughly the same scale as x. `visibility` is (33,) in [0, 1].
    `t` is stream time in seconds (from the frames, not the wall clock).
    """

    t: float
    xyz: np.ndarray
    visibility: np.ndarray
    image_size: tuple[int, int] | None = None  # (width, height) when it came from pixels

    def __post_init__(self) -> None:
        if self.xyz.shape != (NUM_LANDMARKS, 3):
            raise ValueError(f"Pose.xyz must be (33, 3), got {self.xyz.shape}")
        if self.visibility.shape != (NUM_LANDMARKS,):
            raise ValueError(f"Pose.visibility must be (33,), got {self.visibility.shape}")


@dataclass(frozen=True, eq=False)
class Frame:
    """One frame from a source: an image (BGR, HxWx3 uint8); or, for replayed landmark
    streams, the operator's ready pose and no image; or, for simulated cameras, `poses`:
    every person the camera sees (possibly none) and no image, among which the engine
    picks the operator as it does among MediaPipe's people. `index` counts frames from 0
    in the stream."""

    t: float
    index: int
    image: np.ndarray | None = None
    pose: Pose | None = None
    poses: tuple[Pose, ...] | None = None


class StreamState(StrEnum):
    CONNECTING = "connecting"
    LIVE = "live"
    STALLED = "stalled"
    RECONNECTING = "reconnecting"
    ENDED = "ended"


class Sight(IntEnum):
    """How well one stream sees the operator in one frame (`proxima.pose.operator_sight`).

    One rule for everything that asks "is the operator there?": the arbiter lets a stream
    drive at PARTIAL or better and prefers FULL; the drone watchdog hovers when no stream
    has had PARTIAL or better for a while."""

    NONE = 0  # nobody, not the operator, or too few landmarks to read a gesture
    PARTIAL = 1  # enough landmarks to read gestures, but the feet are out of view
    FULL = 2  # `operator_visible`: enough landmarks, feet included


class LinkState(StrEnum):
    CONNECTING = "connecting"
    OK = "ok"
    LOST = "lost"


@dataclass(frozen=True, kw_only=True)
class Event:
    """Base of every event on the bus. `t` is stream time in seconds; `stream` names the
    camera stream (or drone) it concerns, if any."""

    t: float
    stream: str = ""

    type: str = field(default="event", init=False)

    def to_dict(self) -> dict:
        """Plain JSON-serialisable dict, `type` included."""
        out: dict = {"type": self.type}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if isinstance(value, np.ndarray):
                value = value.round(5).tolist()
            elif isinstance(value, StrEnum):
                value = str(value)
            out[name] = value
        return out
