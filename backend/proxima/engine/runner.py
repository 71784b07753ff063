"""The multi-stream engine: one thread per stream, one decision path, one event bus.

    engine = Engine([StreamSpec(name="main", uri="replay:a.csv"),
                     StreamSpec(name="side", uri="replay:b.csv")], bus)
    engine.run()   # or start() ... stop()

Each stream thread runs source -> pose -> window -> classifier -> filter and publishes
pose, gesture, action and stream events itself; its updates go through the
`TimeOrderedMerge` to one `CommandController` (arbiter, debounce, arming), which decides
the handover, arming and command events for the controlled drone (by default the first
stream's drone). A stream that fails (unreadable file, dropped camera) shows as a
`stream` event in state `ended` with the reason; the other streams go on.

Hooks for the rest of the system (the console's thumbnails, the scenario clock, model
promotion): `add_tap` registers a frame tap on a stream (`proxima.engine.taps`), before
or after `start`; `swap_classifier` changes a running stream's model from any thread,
applied by the stream thread before its next frame (`proxima.engine.stream`).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from proxima.control import CommandController, ControlSettings, Sight, StreamUpdate
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.fusion import FusedDecisions
from proxima.engine.merge import Decider, TimeOrderedMerge
from proxima.engine.stream import Classifier, ClassifierSwap, StreamPipeline
from proxima.engine.taps import FrameTap, StreamTaps, Tap, UpdateTap
from proxima.events import ArmingEvent, EventBus, StreamEvent
from proxima.ingest import FrameSource, SourceError, StateChange, open_source
from proxima.types import Event, StreamState

log = logging.getLogger(__name__)


@dataclass
class StreamStats:
    """What one stream did in a run."""

    frames: int = 0
    classifications: int = 0
    last_t: float = 0.0
    error: str | None = None
    total_frames: int | None = None  # known for replays, for progress bars
    done: bool = False


def load_classifier(path: str | Path | None) -> Classifier:
    """The gesture classifier at `path` (default: the shipped checkpoint); comma-joined
    paths (`a.pt,b.pt,c.pt`) are an ensemble, the mean of their probabilities
    (`proxima.gesture.ensemble`).

    Raises:
        FileNotFoundError: no such checkpoint.
        ValueError: the file is not a Proxima gesture checkpoint, or ensemble members
            disagree on window or labels.
    """
    from proxima.gesture.ensemble import load_checkpoint

    return load_checkpoint(path)


class Engine:
    """Runs several ranked streams into one decision path on an `EventBus`.

    Streams are ranked by `StreamSpec.priority`, ties by their order in `streams`.
    `realtime=False` lets file and replay sources run as fast as possible (decisions use
    stream time, so they come out the same). `classifier` is shared by streams that name
    no checkpoint of their own; without it `settings.checkpoint` (default: the shipped
    model) is loaded.

    Raises:
        ValueError: (constructor) no streams, or duplicate stream names.
    """

    def __init__(
        self,
        streams: Sequence[StreamSpec],
        bus: EventBus,
        *,
        control: ControlSettings | None = None,
        settings: EngineSettings | None = None,
        drone: str | None = None,
        realtime: bool = True,
        classifier: Classifier | None = None,
    ) -> None:
        if not streams:
            raise ValueError("the engine needs at least one stream")
        self.specs = sorted(streams, key=lambda s: s.priority)  # stable: ties keep order
        names = [s.name for s in self.specs]
        if len(set(names)) != len(names):
            raise ValueError(f"stream names must be unique: {names}")
        self.bus = bus
        self.control = control or ControlSettings()
        self.settings = settings or EngineSettings()
        self.drone = drone or self.specs[0].drone
        self.realtime = realtime
        self._default_classifier = classifier
        self._taps = {name: StreamTaps(name) for name in names}
        self.controller = CommandController(names, self.drone, self.control)
        # With fusion on, every stream's window is fused with the others' before the
        # controller sees its action (`proxima.engine.fusion`); the arbiter is unchanged.
        self.fusion: FusedDecisions | None = None
        decider: Decider = self.controller
        if self.settings.fusion == "on":
            decider = self.fusion = FusedDecisions(self.controller, self.control, self.settings)
        self.merge = TimeOrderedMerge(
            decider, self._publish_decision, names, self.settings.stale_after_s
        )
        self.stats = {name: StreamStats() for name in names}
        self.pipelines: dict[str, StreamPipeline] = {}
        self._sources: dict[str, FrameSource] = {}
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self._started = False

    # -- set-up -------------------------------------------------------------------------
    def _classifiers(self) -> dict[str, Classifier]:
        cache: dict[str, Classifier] = {}
        out: dict[str, Classifier] = {}
        for spec in self.specs:
            if spec.checkpoint is None and self._default_classifier is not None:
                out[spec.name] = self._default_classifier
                continue
            path = spec.checkpoint or self.settings.checkpoint
            key = str(path)
            if key not in cache:
                cache[key] = load_classifier(path)
            out[spec.name] = cache[key]
        return out

    def start(self) -> Engine:
        """Load the models and start one thread per stream (once).

        Raises:
            FileNotFoundError, ValueError: a checkpoint is missing or not a checkpoint.
        """
        if self._started:
            return self
        import torch

        torch.set_num_threads(self.settings.torch_threads)
        classifiers = self._classifiers()
        for spec in self.specs:
            self.pipelines[spec.name] = StreamPipeline(
                spec,
                classifiers[spec.name],
                self.bus.publish,
                self.control,
                self.settings,
                self._taps[spec.name],
            )
        self._started = True
        for spec in self.specs:
            thread = threading.Thread(
                target=self._run_stream, args=(spec,), name=f"stream {spec.name}", daemon=True
            )
            self._threads.append(thread)
            thread.start()
        return self

    # -- hooks ----------------------------------------------------------------------------
    def add_tap(
        self, stream: str, on_frame: FrameTap | None = None, on_update: UpdateTap | None = None
    ) -> Tap:
        """Register a frame tap on `stream` (before or after `start`); see
        `proxima.engine.taps` for when each callable runs and what a failure does.

        Raises:
            KeyError: no such stream.
            ValueError: neither callable given.
        """
        return self._taps[stream].add(on_frame, on_update)

    def remove_tap(self, tap: Tap) -> None:
        """Unregister a tap `add_tap` returned."""
        self._taps[tap.stream].remove(tap)

    def classifier(self, stream: str) -> Classifier:
        """The classifier `stream` classifies with now.

        Raises:
            RuntimeError: the engine was not started (no model is loaded yet).
            KeyError: no such stream.
        """
        if not self._started:
            raise RuntimeError("the engine is not started: no classifier is loaded yet")
        return self.pipelines[stream].classifier

    def swap_classifier(
        self, classifier: Classifier, streams: Sequence[str] | None = None
    ) -> list[ClassifierSwap]:
        """Ask `streams` (default: all) to classify with `classifier` from their next frame
        on; thread-safe, returns at once. Each `ClassifierSwap` is set when its stream
        thread has applied it (`wait(timeout)`).

        Raises:
            RuntimeError: the engine was not started.
            KeyError: no such stream.
        """
        if not self._started:
            raise RuntimeError("the engine is not started: start it before swapping models")
        names = list(streams) if streams is not None else [s.name for s in self.specs]
        pipelines = [self.pipelines[name] for name in names]
        return [p.swap_classifier(classifier) for p in pipelines]

    # -- decisions ------------------------------------------------------------------------
    def _publish_decision(self, event: Event) -> None:
        if isinstance(event, ArmingEvent):
            # The person who armed is the operator every camera follows until disarm.
            for pipeline in self.pipelines.values():
                pipeline.request_operator_lock(event.armed)
        self.bus.publish(event)

    # -- stream threads -------------------------------------------------------------------
    def _on_state(self, name: str, change: StateChange) -> None:
        self.bus.publish(
            StreamEvent(t=change.t, stream=name, state=str(change.state), detail=change.detail)
        )

    def _run_stream(self, spec: StreamSpec) -> None:
        name = spec.name
        stats = self.stats[name]
        pipeline = self.pipelines[name]
        source: FrameSource | None = None
        try:
            self.bus.publish(StreamEvent(t=0.0, stream=name, state=str(StreamState.CONNECTING)))
            source = open_source(
                spec.uri, realtime=self.realtime, on_state=lambda c: self._on_state(name, c)
            )
            self._sources[name] = source
            track = getattr(source, "track", None)
            stats.total_frames = len(track) if track is not None else None
            from proxima.ingest.live import LiveSource

            self.merge.set_live(name, isinstance(source, LiveSource))
            for frame in source:
                if self._stop.is_set():
                    break
                update = pipeline.process(frame)
                stats.frames += 1
                stats.classifications = pipeline.classifications
                stats.last_t = frame.t
                self.merge.submit(update)
        except SourceError as exc:
            stats.error = str(exc)
            if source is None:  # never opened: no state listener told anyone
                self.bus.publish(
                    StreamEvent(t=0.0, stream=name, state=str(StreamState.ENDED), detail=str(exc))
                )
        except Exception as exc:  # a bug in one stream must not take the others down
            log.exception("stream %s failed", name)
            stats.error = f"{type(exc).__name__}: {exc}"
            self.bus.publish(
                StreamEvent(
                    t=stats.last_t, stream=name, state=str(StreamState.ENDED), detail=stats.error
                )
            )
        finally:
            if source is not None:
                source.close()
            pipeline.close()
            self.merge.submit(StreamUpdate(name, stats.last_t, Sight.NONE, ended=True))
            stats.done = True

    # -- lifetime -------------------------------------------------------------------------
    def wait(self, timeout: float | None = None) -> bool:
        """Wait until every stream has ended; return whether they all did."""
        deadline = None if timeout is None else time.monotonic() + timeout
        for thread in self._threads:
            remaining = None if deadline is None else max(deadline - time.monotonic(), 0.0)
            thread.join(remaining)
            if thread.is_alive():
                return False
        self.merge.flush()
        return True

    def stop(self, timeout: float = 5.0) -> None:
        """Stop every stream (closing its source) and wait for the threads."""
        self._stop.set()
        for source in list(self._sources.values()):
            source.close()
        self.wait(timeout)

    def run(self) -> None:
        """Start, run every stream to its end, and stop cleanly on Ctrl-C."""
        self.start()
        try:
            while not self.wait(0.2):
                pass
        except KeyboardInterrupt:
            self.stop()
            raise
