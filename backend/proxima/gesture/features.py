"""Feature pipelines: metric landmarks (N, W, 33, 3) -> model input (N, W, F).

- `paper`: the paper's input, all 33 x 3 coordinates with MinMax scaling fitted on the
  training windows only.
- `body` (default): view-robust and scale-free, so it needs no fitted statistics (which
  also keeps federated clients from scaling with statistics only they have). Per window:
  centred on the hips, scaled by the torso length, turned about the vertical axis to
  face the camera (from the shoulder and hip lines, using MediaPipe's z), then the 17
  joints of the skeleton both data sets share, as 2D positions plus their velocities,
  and the hand points' offsets from their wrist (thumb up or down is all that tells
  all_clear from not_clear; zero where a data set has no hands).
- `body-image`: `body` without the turn: the body as the camera shows it. MediaPipe's z
  is rough in the side views (near profile), and the turn mixes it into x; for a camera
  position seen in training the unturned picture is the cleaner one (temporal split
  0.920 -> 0.950, unseen left view 0.551 -> 0.657; docs/gesture.md).
- `body-smooth-z`: `body` with the depth averaged over a few frames before the turn; the
  shipped model's pipeline since 2026-12-07 (docs/experiments.md "Thirty-fourth session").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from proxima.gesture.geometry import facing_yaw, hip_centre, torso_length
from proxima.gesture.skeleton import COMMON, HAND_WRIST, HANDS


class PaperPipeline:
    name = "paper"

    def __init__(self, lo: np.ndarray | None = None, hi: np.ndarray | None = None) -> None:
        self.lo, self.hi = lo, hi

    @property
    def num_features(self) -> int:
        return 99

    def fit(self, metric: np.ndarray) -> PaperPipeline:
        flat = metric.reshape(-1, 99)
        self.lo, self.hi = flat.min(axis=0), flat.max(axis=0)
        return self

    def transform(self, metric: np.ndarray, has_z: np.ndarray | None = None) -> np.ndarray:
        if self.lo is None or self.hi is None:
            raise RuntimeError("PaperPipeline.transform before fit")
        flat = metric.reshape(*metric.shape[:-2], 99)
        return ((flat - self.lo) / np.maximum(self.hi - self.lo, 1e-6)).astype(np.float32)

    def state(self) -> dict[str, Any]:
        return {"lo": np.asarray(self.lo).tolist(), "hi": np.asarray(self.hi).tolist()}

    @classmethod
    def from_state(cls, state: dict[str, Any]) -> PaperPipeline:
        return cls(np.asarray(state["lo"], np.float32), np.asarray(state["hi"], np.float32))


class BodyPipeline:
    name = "body"
    joints = COMMON

    hand_gain = 5.0  # hand offsets are ~0.1 torso lengths; bring them to the joints' scale

    @property
    def num_features(self) -> int:
        return len(self.joints) * 4 + len(HANDS) * 2

    def fit(self, metric: np.ndarray) -> BodyPipeline:
        return self  # scale-free: nothing to fit

    def canonical(self, metric: np.ndarray, has_z: np.ndarray | None = None) -> np.ndarray:
        """(N, W, 33, 3) -> (N, W, 33, 3): hip-centred, torso-scaled, facing the camera.
        Windows without depth (`has_z` False, e.g. UAV-Gesture) are not turned."""
        x = metric - hip_centre(metric)
        x = x / torso_length(x)
        yaw = facing_yaw(x)  # (N,)
        if has_z is not None:
            yaw = np.where(has_z, yaw, 0.0)
        c, s = np.cos(yaw)[:, None, None], np.sin(yaw)[:, None, None]
        out = x.copy()
        out[..., 0] = c * x[..., 0] + s * x[..., 2]
        out[..., 2] = -s * x[..., 0] + c * x[..., 2]
        return out

    def transform(self, metric: np.ndarray, has_z: np.ndarray | None = None) -> np.ndarray:
        can = self.canonical(metric, has_z)
        pos = can[:, :, list(self.joints), :2]  # (N, W, 17, 2)
        vel = np.diff(pos, axis=1, prepend=pos[:, :1])
        hands = can[:, :, list(HANDS), :2] - can[:, :, list(HAND_WRIST), :2]  # (N, W, 6, 2)
        n, w = pos.shape[:2]
        parts = [pos.reshape(n, w, -1), 10 * vel.reshape(n, w, -1),
                 self.hand_gain * hands.reshape(n, w, -1)]  # fmt: skip
        return np.concatenate(parts, -1).astype(np.float32)

    def state(self) -> dict[str, Any]:
        return {}

    @classmethod
    def from_state(cls, state: dict[str, Any]) -> BodyPipeline:
        return cls()


class BodyImagePipeline(BodyPipeline):
    name = "body-image"

    def canonical(self, metric: np.ndarray, has_z: np.ndarray | None = None) -> np.ndarray:
        """Hip-centred and torso-scaled, never turned (as `body` treats windows without
        depth)."""
        return super().canonical(metric, np.zeros(len(metric), dtype=bool))


class BodySmoothZPipeline(BodyPipeline):
    name = "body-smooth-z"
    z_frames = 9  # the centred moving average over the window's frames (0.3 s at 30 fps)

    def canonical(self, metric: np.ndarray, has_z: np.ndarray | None = None) -> np.ndarray:
        """`body` with each landmark's depth averaged over `z_frames` frames before the
        turn: the live path's z jitters 23 times x and y (docs/capture.md), and the turn
        mixes z into x by the sine of the facing angle, so a side view's every joint
        inherits it; the average cuts that noise by about 3 and keeps slower depth motion."""
        from scipy.ndimage import uniform_filter1d

        steady = np.array(metric, dtype=np.float64, copy=True)
        steady[..., 2] = uniform_filter1d(steady[..., 2], self.z_frames, axis=-2, mode="nearest")
        return super().canonical(steady, has_z)


Pipeline = PaperPipeline | BodyPipeline | BodyImagePipeline | BodySmoothZPipeline
PIPELINES: dict[str, type[PaperPipeline] | type[BodyPipeline]] = {
    "paper": PaperPipeline,
    "body": BodyPipeline,
    "body-image": BodyImagePipeline,
    "body-smooth-z": BodySmoothZPipeline,
}


def make_pipeline(name: str, state: dict[str, Any] | None = None) -> Pipeline:
    if name not in PIPELINES:
        raise ValueError(f"unknown feature pipeline {name!r}; choose from {sorted(PIPELINES)}")
    cls = PIPELINES[name]
    return cls.from_state(state) if state is not None else cls()
