"""One stream's recognition: frame -> operator pose -> sight -> window -> classifier ->
moving-average filter -> hand evidence, publishing pose, gesture and action events on the way.

Replayed frames carry their pose, so pose estimation and operator tracking are skipped
for them; their landmarks pass the same One Euro filter as the tracker's
(`EngineSettings.smooth_replays`, `proxima.pose.PoseSmoother`); camera frames go through
MediaPipe and the operator tracker, created on the first image so a replay never loads
MediaPipe; a simulated camera's frames list the people it sees (`Frame.poses`) and go
through the operator tracker only. The result of every frame is a `StreamUpdate` for the
decision path.

Two hooks let other parts join without touching the pipeline's state from their own
threads: frame taps (`proxima.engine.taps`) and the classifier swap. A swap is requested
from any thread (`swap_classifier`) and applied by the stream thread before its next
frame, so before its next window. The rules on applying it:

- the moving-average filter is emptied: two models' probabilities are never averaged,
  so the first command after a swap needs `filter_size` recognitions of the new model;
- the pose window is kept when the new model's window has the same length (poses do not
  depend on the model: the next due classification already uses the new one); a model
  with another window length starts from an empty window.

The returned `ClassifierSwap` is set once applied, with the stream time of the first frame
the new model was there for; a stream that has ended applies a swap at once (`t` None).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from proxima.control import (
    ControlSettings,
    HandEvidence,
    Sight,
    StreamUpdate,
    decide_window,
    decision_filter,
)
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.fusion import window_evidence
from proxima.engine.taps import StreamTaps
from proxima.engine.window import PoseWindow, WindowClock, engine_clock
from proxima.events import ActionEvent, GestureEvent, PoseEvent
from proxima.pose import PoseSmoother, operator_sight
from proxima.types import Event, Frame, Pose

log = logging.getLogger(__name__)

DATASET_ASPECT = 16 / 9  # the LASER videos; replayed poses carry no image size


class Classifier(Protocol):
    """What the engine needs of `proxima.gesture.classifier.GestureClassifier`."""

    window: int
    labels: tuple[str, ...]

    @property
    def window_clock(self) -> str:
        """ "poses" or "time": how the model's training windows were timed."""
        ...

    def predict(self, xyz: np.ndarray, aspect: float = ...) -> np.ndarray: ...


@dataclass(eq=False)
class ClassifierSwap:
    """A requested classifier change of one stream. `applied` is set by the stream thread
    once the new classifier is in place (or at once for an ended stream), and also when a
    newer request replaced this one before it was applied (`replaced` True)."""

    stream: str
    classifier: Classifier
    applied: threading.Event = field(default_factory=threading.Event)
    t: float | None = None  # stream time of the first frame the new classifier was there for
    replaced: bool = False

    def wait(self, timeout: float | None = None) -> bool:
        """Block until applied (or replaced); return whether it was within `timeout`."""
        return self.applied.wait(timeout)


class PoseStage:
    """The people in a frame -> the operator. Camera images go through MediaPipe (the
    estimator made on the first image); a simulated camera's frames list their people
    (`Frame.poses`), so no estimator is made for them. Either way the operator tracker
    picks and follows the operator among them."""

    def __init__(self, model_path: object = None, num_poses: int = 2) -> None:
        from proxima.pose import OperatorTracker

        self.model_path = model_path
        self.num_poses = num_poses
        self.estimator: Any = None
        self.tracker = OperatorTracker()

    def people(self, frame: Frame) -> list[Pose]:
        if frame.poses is not None:
            return list(frame.poses)
        assert frame.image is not None
        if self.estimator is None:
            from proxima.pose import PoseEstimator

            self.estimator = PoseEstimator(self.model_path, num_poses=self.num_poses)  # type: ignore[arg-type]
        return self.estimator.estimate(frame.image, frame.t)

    def __call__(self, frame: Frame) -> Pose | None:
        return self.tracker.update(self.people(frame), frame.t)

    @property
    def track_id(self) -> int:
        return self.tracker.track_id

    def close(self) -> None:
        if self.estimator is not None:
            self.estimator.close()


class StreamPipeline:
    """Per-stream state and processing; `process(frame)` runs in the stream's thread
    (taps, then the stages, then the update taps)."""

    def __init__(
        self,
        spec: StreamSpec,
        classifier: Classifier,
        publish: Callable[[Event], None],
        control: ControlSettings | None = None,
        settings: EngineSettings | None = None,
        taps: StreamTaps | None = None,
    ) -> None:
        self.control = control or ControlSettings()
        self.settings = settings or EngineSettings()
        self.spec = spec
        self.name = spec.name
        self.publish = publish
        self.taps = taps if taps is not None else StreamTaps(spec.name)
        self._classifier = classifier
        self.window = self._new_window(classifier)
        self.filter = decision_filter(self.control, classifier.labels)
        self.evidence = HandEvidence.from_settings(self.control)
        self._restarted = True  # the filter was emptied since the last window (fusion)
        self.frames = 0
        self.classifications = 0
        self.last_bridged = False  # the latest classified window held a bridged pause
        self.last_pose: Pose | None = None  # the operator's pose in the latest frame (taps)
        self._pose_stage: PoseStage | None = None
        self._smoother: PoseSmoother | None = (
            PoseSmoother() if self.settings.smooth_replays else None
        )
        self._track_id = 0
        self._lock_request: bool | None = None  # set by the decision path, any thread
        self._lock_guard = threading.Lock()
        self._swap: ClassifierSwap | None = None  # requested from any thread
        self._swap_guard = threading.Lock()
        self._closed = False

    def _clock(self, classifier: Classifier) -> WindowClock:
        return engine_clock(self.settings.window_clock, classifier.window_clock)

    def _new_window(self, classifier: Classifier) -> PoseWindow:
        s = self.settings
        return PoseWindow(classifier.window, s.stride, s.max_gap_s, clock=self._clock(classifier))

    @property
    def classifier(self) -> Classifier:
        """The classifier this stream's windows go to (a requested swap once applied)."""
        return self._classifier

    def swap_classifier(self, classifier: Classifier) -> ClassifierSwap:
        """Classify with `classifier` from the stream's next frame on (see the module for
        what is reset). Thread-safe; returns at once. A request not yet applied is
        replaced by a newer one."""
        swap = ClassifierSwap(self.name, classifier)
        with self._swap_guard:
            older, self._swap = self._swap, swap
            if self._closed:  # no stream thread any more: nothing classifies meanwhile
                self._swap = None
                self._install(swap, None)
        if older is not None:
            older.replaced = True
            older.applied.set()
        return swap

    def _apply_swap(self, t: float | None) -> None:
        with self._swap_guard:
            swap, self._swap = self._swap, None
        if swap is not None:
            self._install(swap, t)

    def _install(self, swap: ClassifierSwap, t: float | None) -> None:
        clf = swap.classifier
        if (clf.window, self._clock(clf)) != (self.window.size, self.window.clock):
            self.window = self._new_window(clf)
        self.filter = decision_filter(self.control, clf.labels)
        self._classifier = clf
        self._restarted = True
        swap.t = t
        swap.applied.set()
        log.info("stream %s: classifier swapped (window %d) at t=%s", self.name, clf.window, t)

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
            if self._smoother is None:
                return frame.pose
            p = frame.pose
            xyz = self._smoother(p.xyz, frame.t)
            return Pose(t=p.t, xyz=xyz, visibility=p.visibility, image_size=p.image_size)
        if frame.image is None and frame.poses is None:
            return None
        if self._pose_stage is None:
            self._pose_stage = PoseStage(self.settings.pose_model, self.settings.num_poses)
        self._apply_lock_request()
        pose = self._pose_stage(frame)
        if self._pose_stage.track_id != self._track_id:  # another person is the operator
            self._track_id = self._pose_stage.track_id
            self.window.clear()
            self.filter.reset()
            self._restarted = True
        return pose

    def process(self, frame: Frame) -> StreamUpdate:
        """Run one frame through the taps and the stream's stages; return its update."""
        self._apply_swap(frame.t)
        frame = self.taps.before(frame)
        update = self._recognise(frame)
        self.taps.after(frame, update)
        return update

    def _recognise(self, frame: Frame) -> StreamUpdate:
        self.frames += 1
        t = frame.t
        pose = self._operator_pose(frame)
        # a replayed pose as received, so a recording replays through the same filter
        self.last_pose = frame.pose if frame.pose is not None else pose
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
            self._restarted = True
        if not self.window.due():
            return StreamUpdate(self.name, t, sight)
        bridged = self.window.bridged()
        xyz, vis = self.window.take()
        size = pose.image_size
        aspect = size[0] / size[1] if size else DATASET_ASPECT
        classifier = self._classifier
        probs = np.asarray(classifier.predict(xyz, aspect=aspect))[0]
        self.classifications += 1
        self.last_bridged = bridged
        best = int(np.argmax(probs))
        withheld = self.evidence.withheld(vis[0], xyz[0], aspect)
        self.publish(
            GestureEvent(
                t=t,
                stream=self.name,
                gesture=classifier.labels[best],
                confidence=round(float(probs[best]), 4),
                probs=[round(float(p), 4) for p in probs],
                withheld=withheld,
            )
        )
        decision, action = decide_window(self.filter, t, probs, withheld, bridged)
        self.publish(
            ActionEvent(
                t=t,
                stream=self.name,
                action=action,
                confidence=round(decision.confidence, 4),
            )
        )
        fused = None
        if self.settings.fusion == "on":
            fused = window_evidence(
                probs, vis[0], withheld, classifier.labels,
                self.settings.fusion_min_visibility, self._restarted,
            )  # fmt: skip
        self._restarted = False
        return StreamUpdate(self.name, t, sight, action, decision.confidence, evidence=fused)

    def close(self) -> None:
        """Release the pose estimator, if one was made; later swaps apply at once."""
        with self._swap_guard:  # installs after the stream thread are all under the guard
            self._closed = True
            swap, self._swap = self._swap, None
            if swap is not None:
                self._install(swap, None)
        if self._pose_stage is not None:
            self._pose_stage.close()
            self._pose_stage = None
