"""One call per frame for the engine: frame -> the operator's smoothed pose (or None).

Image frames go through a `PoseEstimator` (created on the first image, so a replayed
landmark stream never loads MediaPipe); replay frames already carry their pose. Either
way the `OperatorTracker` picks, follows and smooths the operator.
"""

from __future__ import annotations

from pathlib import Path

from proxima.pose.estimator import PoseEstimator
from proxima.pose.operator import OperatorTracker
from proxima.types import Frame, Pose


class OperatorPoser:
    """`poser(frame)` returns the operator's pose in `frame`, or None if not found.

    Call `lock_current()` when the arming gesture is recognised and `unlock()` on
    disarm (both go to the tracker); `close()` releases the estimator.
    """

    def __init__(
        self,
        model_path: str | Path | None = None,
        num_poses: int = 2,
        tracker: OperatorTracker | None = None,
    ) -> None:
        self.model_path = model_path
        self.num_poses = num_poses
        self.tracker = tracker or OperatorTracker()
        self._estimator: PoseEstimator | None = None
        self.people_last_frame = 0  # how many people the last frame had

    def poses(self, frame: Frame) -> list[Pose]:
        """Every person in the frame (the replay's one pose, or the estimator's)."""
        if frame.pose is not None:
            return [frame.pose]
        if frame.image is None:
            return []
        if self._estimator is None:
            self._estimator = PoseEstimator(self.model_path, self.num_poses)
        return self._estimator.estimate(frame.image, frame.t)

    def __call__(self, frame: Frame) -> Pose | None:
        people = self.poses(frame)
        self.people_last_frame = len(people)
        return self.tracker.update(people, frame.t)

    def lock_current(self) -> bool:
        """Lock on the current operator (see `OperatorTracker.lock_current`)."""
        return self.tracker.lock_current()

    def unlock(self) -> None:
        self.tracker.unlock()

    def close(self) -> None:
        if self._estimator is not None:
            self._estimator.close()
            self._estimator = None

    def __enter__(self) -> OperatorPoser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
