"""`Setpoint`: one SET_POSITION_TARGET_LOCAL_NED position target, as the link sends it."""

from __future__ import annotations

from dataclasses import dataclass

from proxima.drone.mavlink.protocol import IGNORE_YAW, POSITION_ONLY


@dataclass
class Setpoint:
    """An absolute local NED position target (MAV_FRAME_LOCAL_NED), with a yaw or not."""

    position: tuple[float, float, float]
    yaw: float | None = None
    sent_at: float = 0.0  # when it last went out (monotonic)

    @property
    def type_mask(self) -> int:
        """Position only; the yaw too when one is given."""
        return POSITION_ONLY | (IGNORE_YAW if self.yaw is None else 0)
