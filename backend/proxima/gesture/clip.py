"""The one in-memory form of a recorded gesture, whatever data set it came from."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class DataError(ValueError):
    """Bad input data; the message names the file, the line and the problem."""


@dataclass(frozen=True, eq=False)
class Clip:
    """One recording of one gesture.

    `xyz` is (T, 33, 3) in MediaPipe's landmark layout and normalised image coordinates
    (x, y in 0..1 of the image, z depth in x's scale). Landmarks a data set does not have
    (UAV-Gesture has 17 of the 33, and no z) carry visibility 0. `frames` holds each row's
    frame number, so gaps (frames with no person detected) are visible. `aspect` is the
    image's width / height: x * aspect and y share one metric scale.
    """

    name: str
    gesture: str
    view: str  # "f", "l", "r" for LASER; "f" for UAV-Gesture (frontal)
    subject: str
    source: str  # "laser" or "uav-gesture"
    frames: np.ndarray  # (T,) int
    xyz: np.ndarray  # (T, 33, 3) float32
    visibility: np.ndarray  # (T, 33) float32
    aspect: float = 16 / 9
    has_z: bool = True

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def scene(self) -> str:
        """The recording it belongs to: one person before one camera."""
        return f"{self.source}/{self.subject}/{self.view}"

    def slice(self, start: int, stop: int) -> Clip:
        """Rows start:stop as a new clip (same metadata)."""
        return Clip(
            name=self.name,
            gesture=self.gesture,
            view=self.view,
            subject=self.subject,
            source=self.source,
            frames=self.frames[start:stop],
            xyz=self.xyz[start:stop],
            visibility=self.visibility[start:stop],
            aspect=self.aspect,
            has_z=self.has_z,
        )
