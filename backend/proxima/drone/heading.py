"""Which way a vehicle points while it flies a gesture's move: the heading policy.

A move is an absolute `SET_POSITION_TARGET_LOCAL_NED`; its yaw field is used only when
the type mask lets it through (`Setpoint.type_mask`: the ignore-yaw bit is cleared when
a yaw is given). Per drone, one of:

- `free`: no yaw is sent (ignore-yaw set), the autopilot's own yaw behaviour applies (on
  ArduCopter `WP_YAW_BEHAVIOR`, whose default turns the nose toward the target); what
  the project did before it could send a yaw;
- `keep`: the heading the vehicle has when the move starts is sent with the target, so a
  sideways step stays sideways and the camera keeps its direction;
- `face_operator`: the heading from the move's target toward the operator's place, so a
  drone stepping sideways turns to keep its camera on the operator (within 0.5 m of
  that place it keeps its heading: a bearing there means nothing).

The operator's place is the console's `view.operator_position` (world frame, x east,
y north), taken into each drone's local NED through the drone's `home`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from proxima.drone.link import Telemetry

HeadingMode = Literal["free", "keep", "face_operator"]
HEADING_MODES: tuple[str, ...] = ("free", "keep", "face_operator")
NEAR_M = 0.5


def bearing(frm: Sequence[float], to: Sequence[float]) -> float:
    """Yaw (radians, clockwise from north) from local NED point `frm` toward `to`."""
    return math.atan2(float(to[1]) - float(frm[1]), float(to[0]) - float(frm[0]))


@dataclass(frozen=True)
class HeadingPolicy:
    """Per drone: its mode (`HeadingMode`; missing drones are `free`) and, for
    `face_operator`, the operator's (north, east) in that drone's local NED."""

    modes: Mapping[str, str] = field(default_factory=dict)
    operator_ne: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for drone, mode in self.modes.items():
            if mode not in HEADING_MODES:
                raise ValueError(f"drone {drone}: heading {mode!r}; choose one of {HEADING_MODES}")
            if mode == "face_operator" and drone not in self.operator_ne:
                raise ValueError(f"drone {drone}: face_operator needs the operator's place")

    def yaw_for(self, drone: str, tel: Telemetry, target: Sequence[float]) -> float | None:
        """The yaw (radians) to send with a move of `drone` to local NED `target`, or
        None to send none."""
        mode = self.modes.get(drone, "free")
        if mode == "free":
            return None
        if mode == "keep":
            return tel.yaw
        op = self.operator_ne[drone]
        if math.hypot(op[0] - target[0], op[1] - target[1]) < NEAR_M:
            return tel.yaw
        return bearing(target, op)

    @classmethod
    def from_drones(cls, drones: Sequence[Any], operator_enu: Sequence[float]) -> HeadingPolicy:
        """From the console's drones (`DroneSettings`: name, `home` (x east, y north, z
        up), `heading`) and the operator's place (x east, y north)."""
        modes = {d.name: d.heading for d in drones}
        ops = {
            d.name: (float(operator_enu[1]) - d.home[1], float(operator_enu[0]) - d.home[0])
            for d in drones
        }
        return cls(modes, ops)
