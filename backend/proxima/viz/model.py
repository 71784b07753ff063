"""What the 3D view shows, computed from bus events without any rendering library, so
it can be tested on its own: each drone's world position and trail, which drone drives,
the operator's skeleton as 3D line segments, each drone's camera (from its position,
heading and mount) and how its stream sees the operator (the newest `PoseEvent` sight,
"none" when its stream has published no pose for `SIGHT_STALE_S`).

World frame: metres, x east, y north, z up, origin at the geofence centre. A drone's
telemetry is local NED from its own origin, placed in the world by its `home`.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from proxima.drone.events import DroneStateEvent
from proxima.events import HandoverEvent, PoseEvent
from proxima.settings import Settings
from proxima.sim.mount import CameraMount
from proxima.synth.camera import Camera
from proxima.types import Event

SIGHT_STALE_S = 1.0  # wall seconds without a pose after which a stream sees nobody

# BlazePose connections drawn for the operator (body only: face and hands omitted).
BODY_CONNECTIONS: tuple[tuple[int, int], ...] = (
    (11, 12),
    (11, 13),
    (13, 15),
    (12, 14),
    (14, 16),
    (11, 23),
    (12, 24),
    (23, 24),
    (23, 25),
    (25, 27),
    (24, 26),
    (26, 28),
    (27, 31),
    (28, 32),
    (0, 11),
    (0, 12),
)
DATASET_ASPECT = 16 / 9  # x and y of the landmarks are normalised separately


@dataclass
class DroneTrack:
    name: str
    home: np.ndarray  # world position of the vehicle's local origin
    position: np.ndarray | None = None  # world, newest
    trail: deque = field(default_factory=deque)
    link: str = "connecting"
    armed: bool = False
    mode: str = ""
    attitude: tuple[float, float, float] | None = None  # roll, pitch, yaw (radians)
    mount: CameraMount = field(default_factory=lambda: CameraMount())

    def camera(self) -> Camera | None:
        """The drone's camera in the scene's NED frame (None before a position)."""
        if self.position is None:
            return None
        e, n, u = (float(v) for v in self.position)
        return self.mount.camera((n, e, -u), self.attitude or (0.0, 0.0, 0.0))


def ned_to_world(home: np.ndarray, ned: list[float] | tuple[float, float, float]) -> np.ndarray:
    """A local NED point (north, east, down) of a vehicle whose origin is `home`."""
    n, e, d = (float(v) for v in ned)
    return home + np.array([e, n, -d])


def operator_segments(
    xyz: np.ndarray, visibility: np.ndarray, base: np.ndarray, height_m: float
) -> np.ndarray | None:
    """The operator's body as (K, 2, 3) world segments standing at `base`: image
    landmarks scaled so the visible body (nose to feet) is `height_m` tall, facing -y."""
    pts = np.asarray(xyz, dtype=np.float64)
    vis = np.asarray(visibility, dtype=np.float64)
    seen = vis > 0.3
    if seen.sum() < 8:
        return None
    x = pts[:, 0] * DATASET_ASPECT
    y = pts[:, 1]
    top, bottom = y[seen].min(), y[seen].max()
    if bottom - top < 1e-3:
        return None
    scale = height_m / (bottom - top)
    cx = x[[23, 24]].mean()
    world = np.stack(
        [base[0] + (x - cx) * scale, np.full(33, base[1]), base[2] + (bottom - y) * scale],
        axis=1,
    )
    return np.array([[world[a], world[b]] for a, b in BODY_CONNECTIONS], dtype=np.float32)


class SceneModel:
    """Scene state, updated by `apply(event)` from any thread; `snapshot()` copies it."""

    def __init__(self, settings: Settings, clock: Callable[[], float] = time.monotonic) -> None:
        self.settings = settings
        self.clock = clock
        self._lock = threading.Lock()
        self.trail_points = settings.view.trail_points
        self.drones: dict[str, DroneTrack] = {}
        for d in settings.drones:
            self._add_drone(d.name, d.home).mount = d.camera
        self.stream_drone = {s.name: s.drone for s in settings.streams}
        self.stream_priority = {s.name: s.priority for s in settings.streams}
        self.driving_stream: str | None = None
        ox, oy = settings.view.operator_position
        self.operator_base = np.array([ox, oy, 0.0])
        self.operator: np.ndarray | None = None
        self.operator_visible = False
        self.sights: dict[str, tuple[str, float]] = {}  # stream -> (sight, wall time)
        self.version = 0

    def _add_drone(self, name: str, home: tuple[float, float, float]) -> DroneTrack:
        track = DroneTrack(
            name=name,
            home=np.asarray(home, dtype=np.float64),
            trail=deque(maxlen=self.trail_points),
        )
        self.drones[name] = track
        return track

    @property
    def driving_drone(self) -> str | None:
        return self.stream_drone.get(self.driving_stream or "")

    def _operator_stream(self) -> str | None:
        """Whose pose draws the operator: the driving stream, else the main one."""
        if self.driving_stream:
            return self.driving_stream
        if self.stream_priority:
            return min(self.stream_priority, key=self.stream_priority.__getitem__)
        return None

    def apply(self, event: Event) -> None:
        with self._lock:
            match event:
                case DroneStateEvent():
                    name = event.drone or event.stream
                    track = self.drones.get(name) or self._add_drone(name, (0.0, 0.0, 0.0))
                    track.link = event.link
                    track.armed = event.armed
                    track.mode = event.mode
                    if event.attitude is not None and len(event.attitude) == 3:
                        r, p, y = (float(a) for a in event.attitude)
                        track.attitude = (r, p, y)
                    if event.position is not None:
                        pos = ned_to_world(track.home, event.position)
                        if track.position is None or np.linalg.norm(pos - track.position) > 0.01:
                            track.trail.append(pos)
                        track.position = pos
                case HandoverEvent():
                    self.driving_stream = event.to_stream or None
                case PoseEvent():
                    self.sights[event.stream] = (event.sight, self.clock())
                    if event.stream != self._operator_stream():
                        self.version += 1
                        return
                    # Seen well enough to read gestures (the watchdog's rule, types.Sight).
                    self.operator_visible = event.sight != "none"
                    segs = operator_segments(
                        np.asarray(event.xyz),
                        np.asarray(event.visibility),
                        self.operator_base,
                        self.settings.view.operator_height_m,
                    )
                    if segs is not None:
                        self.operator = segs
                case _:
                    return
            self.version += 1

    def drone_sight(self, drone: str) -> str:
        """How the best of `drone`'s streams sees the operator now: full, partial or none
        (no pose for `SIGHT_STALE_S`). Call with the lock held."""
        now = self.clock()
        best = "none"
        rank = {"none": 0, "partial": 1, "full": 2}
        for stream, owner in self.stream_drone.items():
            if owner != drone or stream not in self.sights:
                continue
            sight, at = self.sights[stream]
            if now - at <= SIGHT_STALE_S and rank.get(sight, 0) > rank[best]:
                best = sight
        return best

    def snapshot(self) -> dict:
        """A consistent copy for rendering."""
        with self._lock:
            return {
                "version": self.version,
                "driving_drone": self.driving_drone,
                "drones": {
                    n: {
                        "position": None if t.position is None else t.position.copy(),
                        "trail": np.array(t.trail) if t.trail else np.zeros((0, 3)),
                        "link": t.link,
                        "armed": t.armed,
                        "mode": t.mode,
                        "home": t.home.copy(),
                        "camera": t.camera(),
                        "sight": self.drone_sight(n),
                    }
                    for n, t in self.drones.items()
                },
                "operator": None if self.operator is None else self.operator.copy(),
                "operator_visible": self.operator_visible,
            }
