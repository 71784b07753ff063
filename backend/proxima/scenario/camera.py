"""What a drone's camera sees of the operator, given where the drone is.

A replayed landmark stream is what one camera recorded from one place. In a scenario
the drone carrying that camera moves, so the replayed pose is passed through a
`CameraView` before recognition: the camera frames the whole operator only from its
*framing spot* (where the drone hovered when the stream was set up, within
`tolerance_m`); anywhere else the frame cuts the operator's feet, as the paper reports
for its main drone after a move. Cut landmarks keep their position (MediaPipe still
guesses one) but get the low visibility MediaPipe gives landmarks outside the image,
so `proxima.pose.operator_visible` fails on the feet and the stream sees the operator
only PARTIAL.

This is a declared model of framing, not optics: a pinhole camera that moves sideways
keeps the feet in the image; a real drone loses them through its pitch, yaw drift and
gimbal. The model only needs to be a function of the drone's real position, so the
handover happens because the drone moved, not because a script said so.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

import numpy as np

from proxima.drone.link import DroneLink, Telemetry
from proxima.pose import FEET
from proxima.types import Frame, Pose

CUT_VISIBILITY = 0.02  # what MediaPipe reports for a landmark well outside the image


@dataclass
class ViewChange:
    """The camera's framing changed at stream time `t` (`framed`: feet in view)."""

    t: float
    stream: str
    drone: str
    framed: bool
    offset_m: float


@dataclass
class CameraView:
    """The camera of drone `drone` (on `link`), framed from `framing` (local NED)."""

    stream: str
    drone: str
    link: DroneLink
    framing: tuple[float, float, float] | None = None
    tolerance_m: float = 0.5
    changes: list[ViewChange] = field(default_factory=list)
    _framed: bool | None = field(default=None, init=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, init=False)

    def set_framing(self, tel: Telemetry | None = None) -> tuple[float, float, float]:
        """Frame the operator from where the drone is now (after take-off).

        Raises:
            RuntimeError: the vehicle reports no local position.
        """
        tel = tel or self.link.telemetry()
        if tel is None or tel.position is None:
            raise RuntimeError(f"{self.drone}: no local position to frame the operator from")
        self.framing = tel.position
        return self.framing

    def offset(self, tel: Telemetry | None) -> float:
        """How far the drone is from its framing spot (inf when unknown)."""
        if tel is None or tel.position is None or self.framing is None:
            return math.inf
        return math.dist(tel.position, self.framing)

    def framed(self, tel: Telemetry | None) -> bool:
        """Whether the whole operator, feet included, is in the image from here."""
        return self.offset(tel) <= self.tolerance_m

    def apply(self, frame: Frame) -> Frame:
        """The frame as this camera sees it from the drone's current position."""
        tel = self.link.telemetry()
        framed = self.framed(tel)
        with self._lock:
            if framed != self._framed:
                self._framed = framed
                self.changes.append(
                    ViewChange(frame.t, self.stream, self.drone, framed, round(self.offset(tel), 3))
                )
        pose = frame.pose
        if framed or pose is None:
            return frame
        vis = np.array(pose.visibility, dtype=np.float32, copy=True)
        vis[list(FEET)] = np.minimum(vis[list(FEET)], CUT_VISIBILITY)
        cut = Pose(t=pose.t, xyz=pose.xyz, visibility=vis, image_size=pose.image_size)
        return Frame(t=frame.t, index=frame.index, image=frame.image, pose=cut)
