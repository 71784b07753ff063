"""One stream's recognition: frame -> operator pose -> sight -> window -> classifier ->
moving-average filter -> hand evidence, publishing pose, gesture and action events on the way.

Replayed frames carry their pose, so pose estimation and operator tracking are skipped
for them (the replayed landmarks are used exactly as recorded); camera frames go through
MediaPipe and the operator tracker, created on the first image so a replay never loads
MediaPipe. The result of every frame is a `StreamUpdate` for the decision path.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Protocol

import numpy as np

from proxima.control import (
    ControlSettings,
    HandEvidence,
    MovingAverageFilter,
    Sight,
    StreamUpdate,
)
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.window import PoseWindow
from proxima.events import ActionEvent, GestureEvent, PoseEvent
from proxima.pose import operator_sight
from proxima.types import Event, Frame, Pose

DATASET_ASPECT = 16 / 9  # the LASER videos; replayed poses carry no image size


class Classifier(Protocol):
    """What the engine needs of `proxima.gesture.classifier.GestureClassifier`."""

    window: int
    labels: tuple[str, ...]

    def predict(
        self, xyz: np.ndarray, visibility: np.ndarray | None = None, aspect: float = ...
    ) -> np.ndarray: ...


class ImagePoseStage:
    """MediaPipe pose estimation plus operator selection for camera frames."""

    def __init__(self, model_path: object = None, num_poses: int = 2) -> None:
        from proxima.pose import OperatorTracker, PoseEstimator

        self.estimator = PoseEstimator(model_path, num_poses=num_poses)  # type: ignore[arg-type]
        self.tracker = OperatorTracker()

    def __call__(self, frame: Frame) -> Pose | None:
        assert frame.image is not None
        return self.tracker.update(self.estimator.estimate(frame.image, frame.t), frame.t)

    @property
    def track_id(self) -> int:
        return self.tracker.track_id

    def close(self) -> None:
        self.estimator.close()


class StreamPipeline:
    """Per-stream state and processing; `process(frame)` runs in the stream's thread."""

    def __init__(
        self,
        spec: StreamSpec,
        classifier: Classifier,
        publish: Callable[[Event], None],
        control: ControlSettings | None = None,
        settings: EngineSettings | None = None,
    ) -> None:
        control = control or ControlSettings()
        self.settings = settings or EngineSettings()
        self.spec = spec
        self.name = spec.name
        self.classifier = classifier
        self.publish = publish
        self.window = PoseWindow(classifier.window, self.settings.stride, self.settings.max_gap_s)
        self.filter = MovingAverageFilter.from_settings(control, classifier.labels)
        self.evidence = HandEvidence.from_settings(control)
        self.frames = 0
        self.classifications = 0
        self._pose_stage: ImagePoseStage | None = None
        self._track_id = 0
        self._lock_request: bool | None = None  # set by the decision path, any thread
        self._lock_guard = threading.Lock()

    def request_operator_lock(self, locked: bool) -> None:
        """Follow only the current operator (armed) or anyone again (disarmed); applied
        by the stream's own thread before its next frame."""
        with self._lock_guard:
            self._lock_request = locked

    def _apply_lock_request(self) -> None:
        with self._lock_guard:
            request, self._lock_request = self._lock_request, None
        if request is None or self._pose_stage is None:
            return
        if request:
            self._pose_stage.tracker.lock_current()
        else:
            self._pose_stage.tracker.unlock()

    def _operator_pose(self, frame: Frame) -> Pose | None:
        if frame.pose is not None:
            return frame.pose
        if frame.image is None:
            return None
        if self._pose_stage is None:
            self._pose_stage = ImagePoseStage(self.settings.pose_model, self.settings.num_poses)
        self._apply_lock_request()
        pose = self._pose_stage(frame)
        if self._pose_stage.track_id != self._track_id:  # another person is the operator
            self._track_id = self._pose_stage.track_id
            self.window.clear()
            self.filter.reset()
        return pose

    def process(self, frame: Frame) -> StreamUpdate:
        """Run one frame through the stream's stages; return its update."""
        self.frames += 1
        t = frame.t
        pose = self._operator_pose(frame)
        if pose is None:
            return StreamUpdate(self.name, t, Sight.NONE)
        sight = operator_sight(pose)
        if (self.frames - 1) % self.settings.pose_every == 0:
            self.publish(
                PoseEvent(
                    t=t,
                    stream=self.name,
                    xyz=pose.xyz.round(4).tolist(),
                    visibility=pose.visibility.round(3).tolist(),
                    sight=sight.name.lower(),
                )
            )
        if self.window.push(pose):
            self.filter.reset()
        if not self.window.due():
            return StreamUpdate(self.name, t, sight)
        xyz, vis = self.window.take()
        size = pose.image_size
        aspect = size[0] / size[1] if size else DATASET_ASPECT
        probs = np.asarray(self.classifier.predict(xyz, vis, aspect=aspect))[0]
        self.classifications += 1
        best = int(np.argmax(probs))
        withheld = self.evidence.withheld(vis[0])
        self.publish(
            GestureEvent(
                t=t,
                stream=self.name,
                gesture=self.classifier.labels[best],
                confidence=round(float(probs[best]), 4),
                probs=[round(float(p), 4) for p in probs],
                withheld=withheld,
            )
        )
        decision = self.filter.update(t, probs)
        action = self.evidence.action(decision.action, withheld)
        self.publish(
            ActionEvent(
                t=t,
                stream=self.name,
                action=action,
                confidence=round(decision.confidence, 4),
            )
        )
        return StreamUpdate(self.name, t, sight, action, decision.confidence)

    def close(self) -> None:
        """Release the pose estimator, if one was made."""
        if self._pose_stage is not None:
            self._pose_stage.close()
            self._pose_stage = None
