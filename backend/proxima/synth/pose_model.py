"""The synthetic operator seen by the real pose model: each frame rendered
(`render.Renderer`) and passed through MediaPipe's PoseLandmarker in video mode, as a
live camera stream is (`proxima.pose.PoseEstimator`).

What this gives over the geometric projection: MediaPipe's own guesses for limbs the body
hides, its jitter, its misses and its visibility scores, each a function of the pose
and the view. It costs about 40 ms a frame here (20 ms rendering, 20 ms MediaPipe), so a
clip can be cut to its first `max_frames` frames.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from proxima.synth.anthropometry import BodyShape
from proxima.synth.camera import Camera
from proxima.synth.projection import ImageLandmarks
from proxima.synth.render import Renderer, sample_look


class PoseModelSeer:
    """Renders a clip and returns what MediaPipe reports for it, as `ImageLandmarks`
    (the geometric projection's type; frames where MediaPipe finds nobody are not
    detected). One landmarker per clip, so tracking never carries across clips."""

    def __init__(
        self,
        model_path: str | Path | None = None,
        width: int = 640,
        max_frames: int | None = None,
        fps: float = 30.0,
    ) -> None:
        from proxima.pose.model import resolve_pose_model

        if max_frames is not None and max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {max_frames}")
        self.model_path = resolve_pose_model(model_path)
        if width < 64:
            raise ValueError(f"render width must be at least 64 pixels, got {width}")
        self.width = width
        self.max_frames = max_frames
        self.fps = fps

    def describe(self) -> str:
        return f"mediapipe:{self.model_path.name}@{self.width}px"

    def __call__(
        self, world: np.ndarray, camera: Camera, body: BodyShape, rng: np.random.Generator
    ) -> ImageLandmarks:
        from proxima.pose.estimator import PoseEstimator

        if self.max_frames is not None:
            world = world[: self.max_frames]
        ground = float(world[:, 27:33, 2].max()) + 0.02  # NED: the feet's lowest point
        height = max(round(self.width / camera.aspect), 16)  # the camera's aspect
        renderer = Renderer(camera, sample_look(rng), ground, self.width, height)
        T = len(world)
        xyz = np.zeros((T, 33, 3))
        vis = np.zeros((T, 33))
        found = np.zeros(T, bool)
        with PoseEstimator(self.model_path, num_poses=1) as estimator:
            for t in range(T):
                rgb = renderer.frame(world[t], body, rng)
                poses = estimator.estimate(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), t / self.fps)
                if poses:
                    xyz[t], vis[t], found[t] = poses[0].xyz, poses[0].visibility, True
        return ImageLandmarks(xyz, vis, found, camera.width, camera.height)
