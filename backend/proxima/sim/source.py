"""`SimSource`: a simulated camera as a `FrameSource` (`sim:` URIs, `proxima.sim.uri`).

Each frame carries no image and no single pose but `poses`: every person the camera
would detect, as MediaPipe would report them (`Scene.view`), so the engine picks the
operator among them with the same `OperatorTracker` as for a real camera, without
MediaPipe. A camera carried by a drone is placed, frame by frame, from the drone's newest
telemetry through its mount: the frame shows the vehicle where it was when the frame was
made (with a link, up to one telemetry period old; with the scenario's clock, up to one
frame before the frame's stream time, as a camera's latency).

Time: frame k is at k / fps of stream time; `realtime` paces frames to the scene's
shared wall-clock anchor (all streams of a scene in step), else they come as fast as
they are taken. A looping scene never ends; otherwise the stream ends with the script.
"""

from __future__ import annotations

import itertools
import math
import threading
import time
import zlib
from collections.abc import Callable, Iterator

import numpy as np

from proxima.ingest.base import FrameSource, SourceError, StateListener
from proxima.sim.noise import CaptureNoise
from proxima.sim.registry import scene_for, vehicle
from proxima.sim.scene import Scene
from proxima.sim.uri import SimUri, parse_sim_uri
from proxima.synth.camera import Camera
from proxima.types import Frame, StreamState

CHEST = 0.55  # a fixed camera aims at this share of the operator's stature by default
DEFAULT_DISTANCE_M = 5.0
DEFAULT_HEIGHT_M = 1.8


def fixed_camera(uri: SimUri, scene: Scene) -> Camera:
    """The still camera a URI without `#DRONE` describes (see `proxima.sim.uri`)."""
    op = scene.operator
    chest = op.world[0][[11, 12, 23, 24]].mean(axis=0)
    w, h = uri.size
    if uri.at is not None:
        pos = np.array([uri.at[0], uri.at[1], -uri.at[2]])
    else:
        feet = op.world[0][[27, 28]].mean(axis=0)
        facing = op.world[0][0] - (op.world[0][7] + op.world[0][8]) / 2  # nose ahead of ears
        facing[2] = 0.0
        facing /= max(float(np.linalg.norm(facing)), 1e-9)
        pos = feet + DEFAULT_DISTANCE_M * facing
        pos[2] = -DEFAULT_HEIGHT_M
    if uri.yaw_deg is not None or uri.pitch_deg is not None:
        return Camera(
            (float(pos[0]), float(pos[1]), float(pos[2])),
            uri.yaw_deg or 0.0,
            uri.pitch_deg or 0.0,
            uri.roll_deg,
            uri.hfov_deg,
            w,
            h,
        )
    target = chest if uri.look is None else np.array([uri.look[0], uri.look[1], -uri.look[2]])
    try:
        return Camera.looking_at(pos, target, uri.roll_deg, uri.hfov_deg, w, h)
    except ValueError:
        raise SourceError(f"{uri.uri}: the camera stands where it looks") from None


class SimSource(FrameSource):
    """Frames of one simulated camera (see the module).

    Raises:
        SourceError: (constructor) a bad URI, an unknown scene, or `#DRONE` with no
            vehicle of that name registered in this process.
    """

    def __init__(
        self, uri: str, *, realtime: bool = True, on_state: StateListener | None = None
    ) -> None:
        super().__init__(uri, on_state)
        parsed = parse_sim_uri(uri)
        self.parsed = parsed
        self.scene = scene_for(parsed)
        self.realtime = realtime
        self._stop = threading.Event()
        self.camera_name = parsed.drone or uri
        self._camera: Callable[[], Camera | None]
        if parsed.drone is not None:
            v = vehicle(parsed.drone)
            if v is None:
                raise SourceError(
                    f"{uri}: the camera of drone {parsed.drone!r}, but no vehicle of that name "
                    "is registered in this process (the console and the demo register their "
                    "drones; elsewhere give a fixed camera: drop #DRONE, add at=N,E,HEIGHT)"
                )
            self._camera = v.camera
        else:
            still = fixed_camera(parsed, self.scene)
            self._camera = lambda: still
        base = self.scene.noise
        self.noise = CaptureNoise(
            base.jitter if parsed.jitter is None else parsed.jitter,
            base.visibility_noise if parsed.visibility_noise is None else parsed.visibility_noise,
            base.depth_jitter if parsed.depth_jitter is None else parsed.depth_jitter,
        )
        self.rng = np.random.default_rng([self.scene.seed, zlib.crc32(self.camera_name.encode())])

    def camera(self) -> Camera | None:
        """Where the camera is now (None: its drone has reported no position yet)."""
        return self._camera()

    def _frames(self) -> Iterator[Frame]:
        scene = self.scene
        fps = scene.fps
        start = 0
        anchor = 0.0
        if self.realtime:
            anchor = scene.anchor()
            start = max(0, math.ceil((time.monotonic() - anchor) * fps - 1e-9))
        for k in itertools.count(start):
            if not scene.loop and k >= scene.frames:
                break
            t = k / fps
            if self.realtime:
                delay = anchor + t - time.monotonic()
                if delay > 0 and self._stop.wait(delay):
                    break
            if self._stop.is_set() or self.state == StreamState.ENDED:
                break
            if self.state == StreamState.CONNECTING:
                self._advance(StreamState.LIVE)
            view = scene.view(self.camera(), k, self.rng, self.camera_name, self.noise)
            yield Frame(t=t, index=k, image=None, poses=view.poses)
        self._end()

    def close(self) -> None:
        self._stop.set()
        super().close()
