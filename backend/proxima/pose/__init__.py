"""Pose estimation (MediaPipe PoseLandmarker -> `proxima.types.Pose`) and operator
selection. No MediaPipe type leaves this package; MediaPipe itself is imported only
when a `PoseEstimator` is made. See docs/ingest-and-pose.md."""

from __future__ import annotations

from proxima.pose.estimator import PoseEstimator, from_mediapipe
from proxima.pose.model import PoseModelError, resolve_pose_model
from proxima.pose.one_euro import (
    LIVE_ONE_EURO,
    OneEuroFilter,
    OneEuroParams,
    PoseSmoother,
    one_euro_windows,
)
from proxima.pose.operator import (
    FEET,
    OperatorTracker,
    body_area,
    body_centre,
    operator_sight,
    operator_visible,
    selection_score,
)
from proxima.pose.operator_pose import OperatorPoser

__all__ = [
    "FEET",
    "LIVE_ONE_EURO",
    "OneEuroFilter",
    "OneEuroParams",
    "OperatorPoser",
    "OperatorTracker",
    "PoseEstimator",
    "PoseModelError",
    "PoseSmoother",
    "body_area",
    "body_centre",
    "from_mediapipe",
    "one_euro_windows",
    "operator_sight",
    "operator_visible",
    "resolve_pose_model",
    "selection_score",
]
