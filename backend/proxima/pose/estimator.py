"""MediaPipe Tasks PoseLandmarker in VIDEO mode, returning the project's own `Pose`.

VIDEO mode tracks people from frame to frame (cheaper and steadier than detecting in
every frame) and needs strictly increasing timestamps; one estimator serves one stream.
Nothing mediapipe-typed leaves this module: results go through `from_mediapipe`.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from proxima.pose.model import PoseModelError, resolve_pose_model
from proxima.types import NUM_LANDMARKS, Pose


def from_mediapipe(
    landmarks: Any, t: float, image_size: tuple[int, int] | None = None
) -> list[Pose]:
    """Convert MediaPipe's `pose_landmarks` (a list of people, each 33 normalised
    landmarks with x, y, z, visibility) into `Pose`s at stream time `t`.

    A person whose landmark count is not 33 is an error, not something to pad.

    Raises:
        ValueError: a person does not have 33 landmarks.
    """
    poses: list[Pose] = []
    for person in landmarks or ():
        if len(person) != NUM_LANDMARKS:
            raise ValueError(f"MediaPipe gave {len(person)} landmarks, expected 33")
        xyz = np.array([(lm.x, lm.y, lm.z) for lm in person], dtype=np.float32)
        vis = np.array(
            [lm.visibility if lm.visibility is not None else 0.0 for lm in person],
            dtype=np.float32,
        )
        poses.append(Pose(t=t, xyz=xyz, visibility=np.clip(vis, 0.0, 1.0), image_size=image_size))
    return poses


class PoseEstimator:
    """Up to `num_poses` people's landmarks per BGR image.

    Call `estimate(image, t)` with the frame's stream time; timestamps must increase
    (a repeated or earlier `t` is nudged 1 ms past the previous one, as MediaPipe
    refuses it otherwise). Close it (or use `with`): MediaPipe prints a traceback at
    exit for a landmarker left open.

    Raises:
        PoseModelError: (constructor) no model, or MediaPipe cannot load it.
    """

    def __init__(
        self,
        model_path: str | Path | None = None,
        num_poses: int = 2,
        *,
        min_detection_confidence: float = 0.5,
        min_presence_confidence: float = 0.5,
        min_tracking_confidence: float = 0.5,
    ) -> None:
        self.model_path = resolve_pose_model(model_path)
        self.num_poses = num_poses
        os.environ.setdefault("GLOG_minloglevel", "2")  # MediaPipe's C++ warnings
        from mediapipe.tasks.python.core.base_options import BaseOptions
        from mediapipe.tasks.python.vision import (
            PoseLandmarker,
            PoseLandmarkerOptions,
            RunningMode,
        )

        options = PoseLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(self.model_path)),
            running_mode=RunningMode.VIDEO,
            num_poses=num_poses,
            min_pose_detection_confidence=min_detection_confidence,
            min_pose_presence_confidence=min_presence_confidence,
            min_tracking_confidence=min_tracking_confidence,
        )
        try:
            self._landmarker: Any = PoseLandmarker.create_from_options(options)
        except (RuntimeError, ValueError) as exc:
            raise PoseModelError(
                f"MediaPipe cannot load pose model {self.model_path}: {exc}"
            ) from exc
        self._last_ms = -1

    def estimate(self, image_bgr: np.ndarray, t: float) -> list[Pose]:
        """Landmarks of every person found in `image_bgr` (HxWx3 uint8, BGR) at stream
        time `t` seconds; an empty list when nobody is found.

        Raises:
            ValueError: the image is not HxWx3 uint8, or the estimator is closed.
        """
        if self._landmarker is None:
            raise ValueError("PoseEstimator is closed")
        if image_bgr.ndim != 3 or image_bgr.shape[2] != 3 or image_bgr.dtype != np.uint8:
            raise ValueError(
                f"need an HxWx3 uint8 BGR image, got {image_bgr.shape} {image_bgr.dtype}"
            )
        import mediapipe as mp

        rgb = np.ascontiguousarray(cv2.cvtColor(image_bgr, cv2.COLOR_BGR2RGB))
        ms = max(round(t * 1000.0), self._last_ms + 1)
        self._last_ms = ms
        result = self._landmarker.detect_for_video(
            mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb), ms
        )
        height, width = image_bgr.shape[:2]
        return from_mediapipe(result.pose_landmarks, t, (width, height))

    def close(self) -> None:
        """Release the landmarker (safe to call twice)."""
        if self._landmarker is not None:
            self._landmarker.close()
            self._landmarker = None

    def __enter__(self) -> PoseEstimator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        # Last resort against MediaPipe's exit-time traceback; `close()` is the real way.
        with contextlib.suppress(Exception):
            self.close()
