"""A simulated scene: the operator and bystanders in one world, one clock, and what any
camera in it sees.

World: local NED metres (x north, y east, z down; the ground at z = 0), the frame of
`synth` and of the drones' local positions; a drone's local origin sits at its `home`
in it (the console's `home` is ENU, x east, y north, z up: `enu_to_ned`).

Clock: frame k of the scene is at `k / fps` seconds of stream time for every stream, so
all cameras of a run see the same instant of everyone at the same stream time. Streams
paced to the wall clock (`realtime`) share one anchor, the first such stream's start
(`wall_anchor`); a stream opened later starts at the scene's current frame. A looping
scene repeats its `frames` frames (every person's motion has that period).

`view(camera, k)` is what a camera sees at frame k: one `Pose` per person MediaPipe would
detect (geometry: in front of the camera, torso inside the image and large enough), with
the capture noise applied, plus each person's sight; `last_views` keeps the newest per
camera for the 3D view and the scenario's timeline.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from proxima.pose import operator_sight
from proxima.sim.noise import CaptureNoise
from proxima.sim.people import Person
from proxima.synth.camera import Camera
from proxima.synth.projection import project_landmarks
from proxima.types import Pose, Sight

MAX_BLOCK = 16  # frames a still camera is projected for at once


def _same_camera(a: Camera, b: Camera) -> bool:
    """Whether two cameras see alike: within 1 mm and 0.01 degree, same optics."""
    close = max(abs(x - y) for x, y in zip(a.position, b.position, strict=True)) < 1e-3
    angles = (a.yaw_deg - b.yaw_deg, a.pitch_deg - b.pitch_deg, a.roll_deg - b.roll_deg)
    turned = max(abs((d + 180.0) % 360.0 - 180.0) for d in angles) < 1e-2
    optics = (a.hfov_deg, a.width, a.height) == (b.hfov_deg, b.width, b.height)
    return close and turned and optics


@dataclass
class _Block:
    """Frames k0 .. k0 + n - 1 as one camera saw them: per person, landmarks (n, 33, 3),
    visibility (n, 33) (noise applied if `noisy`) and detection (n,)."""

    camera: Camera
    k0: int
    n: int
    noise: CaptureNoise
    noisy: bool
    xyz: list[np.ndarray]
    vis: list[np.ndarray]
    detected: list[np.ndarray]

    def holds(self, k: int, camera: Camera, noise: CaptureNoise, noisy: bool) -> bool:
        return (
            self.k0 <= k < self.k0 + self.n
            and noise == self.noise
            and noisy == self.noisy
            and _same_camera(self.camera, camera)
        )


def enu_to_ned(p: Sequence[float]) -> tuple[float, float, float]:
    """A world point in the console's frame (x east, y north, z up) in the scene's NED."""
    return (float(p[1]), float(p[0]), -float(p[2]))


def ned_to_enu(p: Sequence[float]) -> tuple[float, float, float]:
    return (float(p[1]), float(p[0]), -float(p[2]))


@dataclass(frozen=True)
class PersonView:
    """One person as one camera saw them in one frame: their pose (None: not detected)
    and the sight the engine's rule gives that pose."""

    person: str
    operator: bool
    pose: Pose | None
    sight: Sight


@dataclass(frozen=True)
class View:
    """What camera `camera_name` saw at frame `k` (stream time `t`)."""

    camera_name: str
    k: int
    t: float
    camera: Camera | None
    people: tuple[PersonView, ...]

    @property
    def poses(self) -> tuple[Pose, ...]:
        """Every detected person's pose (what a sim frame carries)."""
        return tuple(p.pose for p in self.people if p.pose is not None)

    @property
    def operator_sight(self) -> Sight:
        return next((p.sight for p in self.people if p.operator), Sight.NONE)


@dataclass(frozen=True)
class SightChange:
    """The operator's sight in camera `camera_name` became `sight` at stream time `t`
    (the camera then at `position`, scene NED)."""

    t: float
    camera_name: str
    sight: Sight
    position: tuple[float, ...] | None


@dataclass
class Scene:
    """People in a world with a clock (see the module). `people[0]` is the operator."""

    name: str
    people: list[Person]
    fps: float = 30.0
    loop: bool = False
    noise: CaptureNoise = field(default_factory=CaptureNoise)
    seed: int = 0
    wall_anchor: float | None = None
    last_views: dict[str, View] = field(default_factory=dict)
    sight_log: list[SightChange] = field(default_factory=list)
    _blocks: dict[str, _Block] = field(default_factory=dict, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def __post_init__(self) -> None:
        if not self.people or not self.people[0].operator:
            raise ValueError(f"scene {self.name}: the first person must be the operator")
        lengths = {len(p.world) for p in self.people}
        if len(lengths) != 1:
            raise ValueError(f"scene {self.name}: people with different frame counts {lengths}")
        if not self.fps > 0:
            raise ValueError(f"scene {self.name}: fps must be > 0, got {self.fps}")

    @property
    def frames(self) -> int:
        """Frames of one pass of the scene."""
        return len(self.people[0].world)

    @property
    def duration_s(self) -> float:
        return self.frames / self.fps

    @property
    def operator(self) -> Person:
        return self.people[0]

    def index(self, k: int) -> int:
        """The row of frame k in every person's motion (wrapping when looping).

        Raises:
            IndexError: k past the end of a scene that does not loop.
        """
        if k < 0 or (not self.loop and k >= self.frames):
            raise IndexError(f"scene {self.name}: frame {k} outside 0..{self.frames - 1}")
        return k % self.frames

    def anchor(self) -> float:
        """The wall-clock time (`time.monotonic`) of stream time 0 for realtime streams,
        set by the first one to ask."""
        with self._lock:
            if self.wall_anchor is None:
                self.wall_anchor = time.monotonic()
            return self.wall_anchor

    def world(self, k: int) -> list[tuple[Person, np.ndarray]]:
        """Everyone's landmarks (33, 3) in the world at frame k."""
        i = self.index(k)
        return [(p, p.world[i]) for p in self.people]

    def truth(self) -> list[dict[str, object]]:
        """The operator's script as segments in stream time (as the stitched streams'
        ground truth: gesture, transition_t, onset_t, end_t), idle stances left out."""
        out: list[dict[str, object]] = []
        for label, start, onset, end in self.operator.segments:
            if label:
                out.append(
                    {
                        "gesture": label,
                        "transition_t": round(start / self.fps, 3),
                        "onset_t": round(onset / self.fps, 3),
                        "end_t": round(end / self.fps, 3),
                    }
                )
        return out

    def view(
        self,
        camera: Camera | None,
        k: int,
        rng: np.random.Generator | None = None,
        camera_name: str = "",
        noise: CaptureNoise | None = None,
    ) -> View:
        """What `camera` sees at frame k (nobody when there is no camera), with the
        capture noise (`noise`, default the scene's) drawn from `rng` (none without
        one). Named views are kept as the camera's newest, and every change of the
        operator's sight in that camera is logged (`sight_log`).

        A named camera that stays put is projected for several frames at once (up to
        `MAX_BLOCK`; "put" is within 1 mm and 0.01 degree), which makes a still camera
        about ten times cheaper per frame; one that moves is projected frame by frame."""
        t = k / self.fps
        noise = noise or self.noise
        people: list[PersonView] = []
        if camera is not None:
            block = self._block(camera, k, rng, camera_name, noise)
            i = k - block.k0
            size = (camera.width, camera.height)
            for p, person in enumerate(self.people):
                pose = None
                if bool(block.detected[p][i]):
                    pose = Pose(
                        t=t, xyz=block.xyz[p][i], visibility=block.vis[p][i], image_size=size
                    )
                sight = operator_sight(pose) if person.operator else Sight.NONE
                people.append(PersonView(person.name, person.operator, pose, sight))
        v = View(camera_name, k, t, camera, tuple(people))
        if camera_name:
            with self._lock:
                before = self.last_views.get(camera_name)
                self.last_views[camera_name] = v
                if before is None or before.operator_sight != v.operator_sight:
                    where = None if camera is None else tuple(round(c, 3) for c in camera.position)
                    self.sight_log.append(SightChange(t, camera_name, v.operator_sight, where))
        return v

    def _block(
        self,
        camera: Camera,
        k: int,
        rng: np.random.Generator | None,
        name: str,
        noise: CaptureNoise,
    ) -> _Block:
        """The projected frames holding frame k for this camera (cached per name)."""
        old = self._blocks.get(name) if name else None
        if old is not None and old.holds(k, camera, noise, rng is not None):
            return old
        length = 1
        if old is not None:
            moved = not _same_camera(old.camera, camera)
            early = old.k0 <= k < old.k0 + old.n
            length = max(1, old.n // 4) if (moved and early) else min(MAX_BLOCK, 2 * old.n)
        self.index(k)  # raises past the end
        n = length if self.loop else min(length, self.frames - k)
        rows = (k + np.arange(n)) % self.frames
        xyz, vis, det = [], [], []
        for person in self.people:
            seen = project_landmarks(person.world[rows], camera, person.body)
            x, v = seen.xyz, seen.visibility
            if rng is not None:
                x, v = noise.apply(x, v, seen.aspect, rng)
            xyz.append(x)
            vis.append(v)
            det.append(seen.detected)
        block = _Block(camera, k, n, noise, rng is not None, xyz, vis, det)
        if name:
            self._blocks[name] = block
        return block

    def views(self) -> dict[str, View]:
        """The newest view of every camera that looked (a copy)."""
        with self._lock:
            return dict(self.last_views)
