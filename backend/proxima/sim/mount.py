"""A camera mounted on a vehicle: where it sits on the airframe, where it points, and the
pinhole camera it makes from the vehicle's pose.

The vehicle's pose is what its telemetry reports (`Telemetry.position`, local NED from
the vehicle's origin, and `Telemetry.attitude`, roll / pitch / yaw in radians), placed in
the scene by the vehicle's home (the scene's NED coordinates of that origin). So the
mount follows whatever flies the vehicle: `proxima sim-drone` over MAVLink, the
in-process `MemoryLink`, SITL or a real drone.

A gimballed mount (`gimbal = True`, the default, like most camera drones) keeps its
pitch and roll against the horizon and turns with the vehicle's yaw only; a fixed mount
also tilts with the airframe's roll and pitch (the accelerations the simulated vehicle
reports as attitude). Angles compose in MAVLink's Z-Y-X order, as `synth.Camera` does.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from proxima.drone.link import Telemetry
from proxima.synth.camera import Camera, rotation_zyx

Vec3 = tuple[float, float, float]


class CameraMount(BaseModel):
    """A drone's camera: its place on the airframe and its optics (a `[drones.camera]`
    table in the console's settings)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    offset_m: Vec3 = Field(
        (0.1, 0.0, 0.0), description="lens from the vehicle's centre: forward, right, down (m)"
    )
    yaw_deg: float = Field(0.0, ge=-180.0, le=180.0, description="from the vehicle's heading")
    pitch_deg: float = Field(-8.0, ge=-90.0, le=30.0, description="up positive; down negative")
    roll_deg: float = Field(0.0, ge=-45.0, le=45.0)
    gimbal: bool = Field(True, description="stabilised: only the vehicle's yaw turns it")
    hfov_deg: float = Field(70.0, ge=10.0, le=150.0, description="horizontal field of view")
    width: int = Field(1280, ge=16, le=8192)
    height: int = Field(720, ge=16, le=8192)

    def camera(self, position_ned: Sequence[float], attitude: Sequence[float]) -> Camera:
        """The camera of a vehicle at scene position `position_ned` (m) with `attitude`
        (roll, pitch, yaw in radians)."""
        roll, pitch, yaw = (float(a) for a in attitude)
        if self.gimbal:
            roll = pitch = 0.0
        body = rotation_zyx(yaw, pitch, roll)
        lens = np.asarray(position_ned, np.float64) + body @ np.asarray(self.offset_m)
        mount = rotation_zyx(*np.deg2rad([self.yaw_deg, self.pitch_deg, self.roll_deg]))
        y, p, r = _zyx_angles(body @ mount)
        return Camera(
            (float(lens[0]), float(lens[1]), float(lens[2])),
            math.degrees(y),
            math.degrees(p),
            math.degrees(r),
            self.hfov_deg,
            self.width,
            self.height,
        )

    def camera_for(self, tel: Telemetry, home_ned: Sequence[float]) -> Camera | None:
        """The camera of the vehicle whose telemetry is `tel` and whose local origin sits
        at `home_ned` in the scene; None while the vehicle reports no position."""
        if tel.position is None:
            return None
        pos = np.asarray(home_ned, np.float64) + np.asarray(tel.position, np.float64)
        attitude = tel.attitude if tel.attitude is not None else (0.0, 0.0, tel.yaw)
        return self.camera(pos.tolist(), attitude)


def _zyx_angles(r: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) in radians of a body-to-world rotation (Z-Y-X)."""
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    if abs(math.cos(pitch)) < 1e-9:  # looking straight up or down: roll folds into yaw
        return math.atan2(-float(r[0, 1]), float(r[1, 1])), pitch, 0.0
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    roll = math.atan2(float(r[2, 1]), float(r[2, 2]))
    return yaw, pitch, roll
