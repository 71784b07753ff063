"""Stitched streams through the engine's own code, in two ways that decide identically
(a test on real clips checks it, and the latency benchmark reports it):

- `engine_run`: the real `Engine` (replay source, stream thread, time-ordered merge,
  controller, event bus) on the stream written as a landmark CSV.
- The fast offline replay, for trying many decision settings on the same streams:
  `recognize` runs the engine's `StreamPipeline` once over the stream's frames, as the
  engine's replay source delivers them, and keeps what no decision setting changes:
  each frame's update (the operator's sight) and, at each classified window, the
  classifier's probabilities, the gestures the hand evidence withheld and whether the
  window had restarted. `decide` then runs the engine's own decision rule
  (`decision_filter`, `decide_window` with the withheld gestures) and `CommandController`
  over them for one setting, in the order `StreamPipeline.process` calls them, and gives
  the controller every frame's update, as the engine's merge does for one stream. The
  window's own settings (stride, gap) and the hand evidence's are fixed by `recognize`.
"""

from __future__ import annotations

import hashlib
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from proxima.control import (
    CommandController,
    ControlSettings,
    Sight,
    StreamUpdate,
    decide_window,
    decision_filter,
)
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.stream import DATASET_ASPECT, Classifier, StreamPipeline
from proxima.evaluation.scoring import Score, score_commands
from proxima.evaluation.stitch import StitchedStream
from proxima.events import ArmingEvent, CommandEvent, EventBus, GestureEvent
from proxima.ingest.landmark_csv import LandmarkTrack
from proxima.ingest.replay import ReplaySource
from proxima.types import Event

STREAM = "main"  # the name every replayed stream runs under


class Run:
    """The commands and arming changes of one run, as the scorer wants them."""

    def __init__(self) -> None:
        self.commands: list[dict[str, Any]] = []
        self.arming: list[tuple[float, bool]] = []
        self.events = 0
        self._armed = False  # the controller's arming when the next command was decided
        # offline replays only: (t, the classifier's top label, what the filter passed,
        # whether a new window stretch began)
        self.recognitions: list[tuple[float, str, str, bool]] = []

    def add(self, e: Event) -> None:
        """Take one event of the run (every event counts; commands and arming are kept)."""
        self.events += 1
        if isinstance(e, CommandEvent):
            # The controller reports a command before the arming change it causes, so
            # `armed` is the state the command was sent in.
            self.commands.append(
                {"t": e.t, "command": e.command, "stream": e.stream, "armed": self._armed}
            )
        elif isinstance(e, ArmingEvent):
            self.arming.append((e.t, e.armed))
            self._armed = e.armed

    def score(self, stream: StitchedStream, by_script: bool = False) -> Score:
        """The run's commands against `stream`'s ground truth: expecting what the run's own
        arming allowed, or with `by_script` every command the script asks for once armed
        (`scoring.expected_commands` with no arming events)."""
        arming = None if by_script else self.arming
        return score_commands(truth_segments(stream), self.commands, stream.duration_s, arming)


def truth_segments(stream: StitchedStream) -> list[dict[str, Any]]:
    """The stream's script as the scorer reads it (gesture, onset)."""
    return [{"gesture": s.gesture, "onset_t": s.onset_t} for s in stream.segments]


# -- the real engine ------------------------------------------------------------------
def engine_run(
    stream: StitchedStream,
    control: ControlSettings,
    settings: EngineSettings,
    classifier: Classifier,
) -> Run:
    """Run `stream` through the real engine (threads, merge, bus): written as a landmark
    CSV to a temporary folder and replayed at its frame rate, as fast as possible.

    Raises:
        RuntimeError: the stream failed in the engine (the message is its error).
    """
    from proxima.engine.runner import Engine

    with tempfile.TemporaryDirectory(prefix="proxima-replay-") as tmp:
        path = Path(tmp) / "stream.csv"
        stream.write(path)
        bus = EventBus()
        run = Run()
        bus.add_listener(run.add)
        spec = StreamSpec(name=STREAM, uri=f"replay:{path}@{stream.fps:g}")
        engine = Engine(
            [spec], bus, control=control, settings=settings, realtime=False, classifier=classifier
        )
        engine.run()
    if engine.stats[STREAM].error:
        raise RuntimeError(engine.stats[STREAM].error)
    return run


# -- the offline replay ---------------------------------------------------------------
class MemoClassifier:
    """A classifier that answers a window it has seen before from memory.

    Replaying one stream again (another stride, the offline replay after the engine run)
    asks for many of the same windows, and a window's probabilities depend on its content
    alone, so each is computed once. The key is a digest of the window's landmarks and
    the aspect ratio (the classifier does not read visibility).
    """

    def __init__(self, classifier: Classifier) -> None:
        self.classifier = classifier
        self.window = classifier.window
        self.window_clock = classifier.window_clock
        self.labels = classifier.labels
        self._memo: dict[bytes, np.ndarray] = {}

    def __len__(self) -> int:
        return len(self._memo)

    def predict(self, xyz: np.ndarray, aspect: float = DATASET_ASPECT) -> np.ndarray:
        """The classifier's probabilities for windows `xyz`, from memory if seen."""
        digest = hashlib.blake2b(digest_size=16)
        digest.update(repr(np.shape(xyz)).encode())
        digest.update(np.ascontiguousarray(xyz).tobytes())
        digest.update(np.asarray(aspect, dtype=np.float64).tobytes())
        key = digest.digest()
        probs = self._memo.get(key)
        if probs is None:
            probs = np.asarray(self.classifier.predict(xyz, aspect=aspect))
            self._memo[key] = probs
        return probs


class _Recorder:
    """Passes windows on to `classifier` and keeps each answer, in order."""

    def __init__(self, classifier: Classifier) -> None:
        self.classifier = classifier
        self.window = classifier.window
        self.window_clock = classifier.window_clock
        self.labels = classifier.labels
        self.outputs: list[np.ndarray] = []

    def predict(self, xyz: np.ndarray, aspect: float = DATASET_ASPECT) -> np.ndarray:
        probs = np.asarray(self.classifier.predict(xyz, aspect=aspect))
        self.outputs.append(probs[0])
        return probs


def replay_source(stream: StitchedStream) -> ReplaySource:
    """The engine's replay source over `stream`'s frames, without writing the CSV: the
    CSV keeps float32 landmarks exactly (9 significant digits), so the frames are the
    ones the engine reads back from it."""
    track = LandmarkTrack(
        path=f"stitched:{stream.view}:{stream.seed}",
        frames=np.asarray(stream.frames, dtype=np.int64),
        xyz=np.asarray(stream.xyz, dtype=np.float32),
        visibility=np.clip(stream.visibility, 0.0, 1.0).astype(np.float32),
    )
    return ReplaySource(f"replay:{track.path}", track, stream.fps, realtime=False)


@dataclass(frozen=True)
class Recognitions:
    """What the engine's stream pipeline made of one replayed stream (see the module).

    `updates` holds each frame's `StreamUpdate` (its sight; `decide` replaces the actions
    in it). For the frames in `classified` (indices into `updates`): `probs` the
    classifier's probabilities, `withheld` the gestures the hand evidence withheld, and
    `new_window` whether the window began a new stretch there (the stream's first, or the
    first after a gap restarted the window, when the pipeline restarted its filter), and
    `bridged` whether the window held a bridged pause (None: none did; recognitions made
    before the engine bridged pauses).
    """

    labels: tuple[str, ...]
    settings: EngineSettings
    # (thumb_hand, hand_visibility, thumb_raise) the withheld were judged with
    hand: tuple[str, float, float | None]
    updates: list[StreamUpdate]
    classified: np.ndarray  # (N,) int
    probs: np.ndarray  # (N, len(labels))
    withheld: list[list[str]]
    new_window: np.ndarray  # (N,) bool
    last_t: float = 0.0
    stream: str = STREAM
    bridged: np.ndarray | None = None  # (N,) bool


def recognize(
    stream: StitchedStream,
    classifier: Classifier,
    settings: EngineSettings | None = None,
    control: ControlSettings | None = None,
) -> Recognitions:
    """Run the engine's `StreamPipeline` (with `settings`, and `control`'s hand evidence)
    once over `stream`'s frames, and keep what `decide` needs for any decision setting.

    Raises:
        ValueError: the classifier's answers and the pipeline's classifications disagree
            in number (a classifier that does not answer one row per window).
    """
    settings = settings or EngineSettings()
    control = control or ControlSettings()
    recorder = _Recorder(classifier)
    withheld: list[list[str]] = []

    def publish(event: Event) -> None:
        if isinstance(event, GestureEvent):
            withheld.append(list(event.withheld))

    spec = StreamSpec(name=STREAM, uri=f"replay:stitched:{stream.view}:{stream.seed}")
    pipeline = StreamPipeline(spec, recorder, publish, control=control, settings=settings)
    updates: list[StreamUpdate] = []
    classified: list[int] = []
    new_window: list[bool] = []
    bridged: list[bool] = []
    restarts: int | None = None  # the window's restarts at the previous classification
    with replay_source(stream) as source:
        for frame in source:
            before = pipeline.classifications
            updates.append(pipeline.process(frame))
            if pipeline.classifications > before:
                classified.append(len(updates) - 1)
                bridged.append(pipeline.last_bridged)
                new_window.append(restarts is None or pipeline.window.restarts != restarts)
                restarts = pipeline.window.restarts
    pipeline.close()
    if not len(recorder.outputs) == len(withheld) == len(classified):
        raise ValueError(
            f"{len(classified)} classifications, {len(recorder.outputs)} answers and "
            f"{len(withheld)} gesture events: the classifier must answer each window once"
        )
    probs = (
        np.stack(recorder.outputs)
        if recorder.outputs
        else np.zeros((0, len(classifier.labels)), dtype=np.float32)
    )
    return Recognitions(
        labels=tuple(classifier.labels),
        settings=settings,
        hand=(control.thumb_hand, control.hand_visibility, control.thumb_raise),
        updates=updates,
        classified=np.asarray(classified, dtype=np.int64),
        probs=probs,
        withheld=withheld,
        new_window=np.asarray(new_window, dtype=bool),
        last_t=updates[-1].t if updates else 0.0,
        bridged=np.asarray(bridged, dtype=bool),
    )


def decide(rec: Recognitions, control: ControlSettings) -> Run:
    """What the engine decides on `rec`'s stream with the decision settings `control`:
    its filter, hand evidence and controller, as the module describes.

    Raises:
        ValueError: `control`'s hand evidence is not the one `rec` was recognised with.
    """
    hand = (control.thumb_hand, control.hand_visibility, control.thumb_raise)
    if hand != rec.hand:
        raise ValueError(
            f"the recognitions judged the hand with {rec.hand}, these settings with {hand}: "
            "recognize the stream again with them"
        )
    filt = decision_filter(control, rec.labels)
    controller = CommandController([rec.stream], rec.stream, control)
    run = Run()
    updates = rec.updates
    done = 0
    for n, i in enumerate(rec.classified.tolist()):
        for update in updates[done:i]:
            for event in controller.process(update):
                run.add(event)
        frame = updates[i]
        probs = rec.probs[n]
        if rec.new_window[n]:
            filt.reset()
        bridged = rec.bridged is not None and bool(rec.bridged[n])
        decision, action = decide_window(filt, frame.t, probs, rec.withheld[n], bridged)
        top = rec.labels[int(np.argmax(probs))]
        run.recognitions.append((frame.t, top, action, bool(rec.new_window[n])))
        update = StreamUpdate(frame.stream, frame.t, frame.sight, action, decision.confidence)
        for event in controller.process(update):
            run.add(event)
        done = i + 1
    for update in updates[done:]:
        for event in controller.process(update):
            run.add(event)
    # The end of the replay, as the engine reports it: an armed drone gets the safety hover.
    for event in controller.process(StreamUpdate(rec.stream, rec.last_t, Sight.NONE, ended=True)):
        run.add(event)
    return run
