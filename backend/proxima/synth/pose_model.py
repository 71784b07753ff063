"""The synthetic operator seen by the real pose model: each frame rendered
(`render.Renderer`) and passed through MediaPipe's PoseLandmarker in video mode, as a
live camera stream is (`proxima.pose.PoseEstimator`).

What this gives over the geometric projection: MediaPipe's own guesses for limbs the body
hides, its jitter, its misses and its visibility scores, each a function of the pose
and the view. It costs about 40 ms a frame here (20 ms rendering, 20 ms MediaPipe), so a
clip can be cut to its first `max_frames` frames.

MediaPipe reads the mannequin as facing away from the camera in 11-22 % of front-view
frames (every left landmark on the right and back; measured against the exact
projection, `python -m bench.synth_sides`), which real people's clips almost never
show (LASER's front view: 0.03 % of frames); such a `move_to_left` frame shows
`move_to_right`. `match_sides` relabels them by the exact projection (`sides="exact"`): a
frame is swapped back when the mirrored labelling lies clearly closer to the truth. Not
the default: trained with relabelled sets, unseen views scored no better (f 0.896, l
0.638, r 0.835 against 0.917, 0.648, 0.827; docs/experiments.md, "Nineteenth session").
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from proxima.gesture.skeleton import MIRROR
from proxima.synth.anthropometry import BodyShape
from proxima.synth.camera import Camera
from proxima.synth.projection import ImageLandmarks, project_landmarks
from proxima.synth.render import Renderer, sample_look

# The mirrored labelling must lie this much closer (ratio of mean distances) to be taken:
# front-view swaps sit far under it (most below 0.5), side views near 1, where left and
# right project close together and either labelling fits.
SIDE_MARGIN = 0.7
_PAIRED = [i for i in range(33) if MIRROR[i] != i]


def match_sides(
    seen: ImageLandmarks, exact: ImageLandmarks, margin: float = SIDE_MARGIN
) -> tuple[ImageLandmarks, np.ndarray]:
    """`seen` with the frames whose left and right are swapped against `exact` (the same
    frames' exact projection) relabelled; also returns which frames were (T,)."""
    if seen.xyz.shape != exact.xyz.shape:
        raise ValueError(f"seen {seen.xyz.shape} and exact {exact.xyz.shape} differ in shape")

    def distance(xyz: np.ndarray) -> np.ndarray:
        gap = xyz[:, _PAIRED, :2] - exact.xyz[:, _PAIRED, :2]
        return np.linalg.norm(gap, axis=-1).mean(axis=1)

    mirrored = seen.xyz[:, MIRROR]
    swap = seen.detected & (distance(mirrored) < margin * distance(seen.xyz))
    xyz = np.where(swap[:, None, None], mirrored, seen.xyz)
    vis = np.where(swap[:, None], seen.visibility[:, MIRROR], seen.visibility)
    return ImageLandmarks(xyz, vis, seen.detected, seen.width, seen.height), swap


class PoseModelSeer:
    """Renders a clip and returns what MediaPipe reports for it, as `ImageLandmarks`
    (the geometric projection's type; frames where MediaPipe finds nobody are not
    detected). One landmarker per clip, so tracking never carries across clips. `sides`
    "mediapipe" (the default) keeps MediaPipe's labelling; "exact" relabels the frames it
    reads as facing away (`match_sides`)."""

    def __init__(
        self,
        model_path: str | Path | None = None,
        width: int = 640,
        max_frames: int | None = None,
        fps: float = 30.0,
        sides: str = "mediapipe",
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
        if sides not in ("exact", "mediapipe"):
            raise ValueError(f"sides {sides!r}: expected 'exact' or 'mediapipe'")
        self.sides = sides
        self.swapped_frames = 0  # relabelled by match_sides, over every clip seen

    def describe(self) -> str:
        tail = ",sides=exact" if self.sides == "exact" else ""
        return f"mediapipe:{self.model_path.name}@{self.width}px{tail}"

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
        seen = ImageLandmarks(xyz, vis, found, camera.width, camera.height)
        if self.sides == "mediapipe":
            return seen
        seen, swapped = match_sides(seen, project_landmarks(world, camera, body))
        self.swapped_frames += int(swapped.sum())
        return seen
