"""Where the virtual camera stands: view ranges relative to the operator, and cameras
drawn from them.

A view is `NAME:AZIMUTH:ELEVATION[:DISTANCE]`, each a value or a range `LO..HI`:
- azimuth (degrees): the camera's bearing from the operator, measured from the way the
  operator faces, clockwise seen from above like a heading: 0 in front, 90 at the
  operator's right, -90 at the left, 180 behind;
- elevation (degrees): how far above the horizontal the camera looks down at the
  operator (0 = eye level);
- distance (metres, optional): camera to the operator's torso. Without it the camera
  frames the operator: the stature spans 45-80 % of the image height.

The LASER recordings' views sit at about 0 (front) and 70 degrees to either side
(data-notes.md), seen from a drone a little above eye level: MediaPipe's depth puts the
shoulders nearer the camera than the hips and the ankles farther, by what a camera
10-15 degrees above the horizontal gives (docs/synth.md). `DEFAULT_VIEWS` spreads
around those three.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from proxima.synth.anthropometry import BodyShape
from proxima.synth.body import Placement
from proxima.synth.camera import Camera

LASER_VIEW_AZIMUTH = {"f": 0.0, "r": 70.0, "l": -70.0}
FRAMING = (0.45, 0.8)  # share of the image height the stature spans, when no distance
HFOV_DEG = (60.0, 78.0)


@dataclass(frozen=True)
class ViewRange:
    """A range of camera placements around the operator (see the module docstring)."""

    name: str
    azimuth: tuple[float, float]
    elevation: tuple[float, float]
    distance: tuple[float, float] | None = None

    def spec(self) -> str:
        def r(lo: float, hi: float) -> str:
            return f"{lo:g}" if lo == hi else f"{lo:g}..{hi:g}"

        text = f"{self.name}:{r(*self.azimuth)}:{r(*self.elevation)}"
        return text + (f":{r(*self.distance)}" if self.distance else "")


def _range(text: str, what: str, spec: str) -> tuple[float, float]:
    parts = text.split("..")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"view {spec!r}: {what} {text!r} is not a number or LO..HI") from None
    if len(values) == 1:
        return values[0], values[0]
    if len(values) != 2 or values[0] > values[1]:
        raise ValueError(f"view {spec!r}: {what} {text!r} must be LO..HI with LO <= HI")
    return values[0], values[1]


def parse_view(spec: str) -> ViewRange:
    """`NAME:AZIMUTH:ELEVATION[:DISTANCE]` -> ViewRange.

    Raises:
        ValueError: the text does not follow the syntax, or a value is out of range
            (azimuth -360..360, elevation -30..89, distance above 0.3 m).
    """
    fields = spec.split(":")
    if len(fields) not in (3, 4) or not fields[0]:
        raise ValueError(
            f"view {spec!r}: expected NAME:AZIMUTH:ELEVATION[:DISTANCE], "
            "e.g. front:-20..20:0..10 or above:0..360:30..60:6..12"
        )
    az = _range(fields[1], "azimuth", spec)
    el = _range(fields[2], "elevation", spec)
    dist = _range(fields[3], "distance", spec) if len(fields) == 4 else None
    if not (az[0] >= -360 and az[1] <= 360):
        raise ValueError(f"view {spec!r}: azimuth must lie in -360..360 degrees")
    if not (el[0] >= -30 and el[1] <= 89):
        raise ValueError(f"view {spec!r}: elevation must lie in -30..89 degrees")
    if dist is not None and dist[0] < 0.3:
        raise ValueError(f"view {spec!r}: distance must be at least 0.3 m")
    return ViewRange(fields[0], az, el, dist)


DEFAULT_VIEWS = (
    parse_view("front:-20..20:5..20"),
    parse_view("right:55..85:5..20"),
    parse_view("left:-85..-55:5..20"),
)


def laser_view(azimuth_deg: float) -> str:
    """The LASER view ("f", "r", "l") nearest to a camera azimuth."""

    def gap(a: float, b: float) -> float:
        return abs((a - b + 180) % 360 - 180)

    return min(LASER_VIEW_AZIMUTH, key=lambda v: gap(azimuth_deg, LASER_VIEW_AZIMUTH[v]))


@dataclass(frozen=True)
class CameraDraw:
    """A camera drawn from a view range, with the draws that placed it."""

    view: str
    azimuth_deg: float
    elevation_deg: float
    distance_m: float
    camera: Camera

    @property
    def laser_view(self) -> str:
        return laser_view(self.azimuth_deg)

    def to_dict(self) -> dict[str, object]:
        return {
            "view": self.view,
            "azimuth_deg": round(self.azimuth_deg, 3),
            "elevation_deg": round(self.elevation_deg, 3),
            "distance_m": round(self.distance_m, 3),
            "laser_view": self.laser_view,
            "camera": self.camera.to_dict(),
        }


def orbit_camera(
    placement: Placement,
    target_height: float,
    azimuth_deg: float,
    elevation_deg: float,
    distance_m: float,
    hfov_deg: float = 70.0,
    width: int = 1920,
    height: int = 1080,
) -> Camera:
    """A camera `distance_m` from the operator's point at `target_height` metres above
    the ground, at a bearing `azimuth_deg` from the operator's facing (clockwise) and
    `elevation_deg` above the horizontal, looking at that point."""
    target = np.array([placement.north, placement.east, placement.down - target_height])
    bearing = np.deg2rad(placement.heading_deg + azimuth_deg)
    el = np.deg2rad(elevation_deg)
    offset = distance_m * np.array(
        [np.cos(el) * np.cos(bearing), np.cos(el) * np.sin(bearing), -np.sin(el)]
    )
    return Camera.looking_at(target + offset, target, hfov_deg=hfov_deg, width=width, height=height)


def sample_camera(
    view: ViewRange,
    rng: np.random.Generator,
    body: BodyShape,
    placement: Placement,
    width: int = 1920,
    height: int = 1080,
) -> CameraDraw:
    """A camera drawn from a view range: azimuth, elevation, field of view, distance (or
    framing), a small roll, and an aim off the operator's centre that keeps the body in
    the picture."""
    az = float(rng.uniform(*view.azimuth))
    el = float(rng.uniform(*view.elevation))
    hfov = float(rng.uniform(*HFOV_DEG))
    probe = Camera(hfov_deg=hfov, width=width, height=height)
    half_v = np.deg2rad(probe.vfov_deg) / 2
    framing = float(rng.uniform(*FRAMING))
    if view.distance is not None:
        dist = float(rng.uniform(*view.distance))
        framing = min(body.stature / (2 * dist * np.tan(half_v)), 1.0)
    else:
        dist = body.stature / framing / (2 * np.tan(half_v))
    target_h = float(rng.uniform(0.5, 0.62)) * body.stature
    base = orbit_camera(
        placement, target_h, az, el, dist, hfov_deg=hfov, width=width, height=height
    )
    slack = max(1.0 - framing, 0.0)  # aim off centre only as far as the framing allows
    yaw_off = float(rng.uniform(-0.35, 0.35)) * slack * hfov / 2
    pitch_off = float(rng.uniform(-0.3, 0.3)) * slack * probe.vfov_deg / 2
    cam = Camera(
        base.position,
        base.yaw_deg + yaw_off,
        base.pitch_deg + pitch_off,
        float(rng.normal(0.0, 2.0)),
        hfov,
        width,
        height,
    )
    return CameraDraw(view.name, az, el, dist, cam)
