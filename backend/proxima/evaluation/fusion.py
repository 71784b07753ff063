"""Several cameras at once on stitched streams: the same script seen by views f, l and r
(`stitch_views`), optionally through a capture condition (`proxima.gesture.capture`),
run through the real engine with fusion off or on, and scored by commands and windows.

    streams = stitch_views(clips, plan, ("f", "l", "r"), part="test", seed=3)
    run = engine_run_views([streams["f"], streams["l"]], control, settings, classifier)
    run.score(streams["f"]), run.window_accuracy(streams)
"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from proxima.control import ControlSettings
from proxima.engine.config import EngineSettings, StreamSpec
from proxima.engine.fusion import Fused
from proxima.engine.stream import Classifier
from proxima.evaluation.replay import Run
from proxima.evaluation.stitch import StitchedStream
from proxima.events import EventBus, GestureEvent, HandoverEvent
from proxima.gesture.capture.model import CaptureModel
from proxima.types import Event


class ViewsRun(Run):
    """A multi-camera engine run: the commands and arming (as `Run`), each stream's
    classifier outputs (t, probs) and, with fusion, its fused windows (t, probs)."""

    def __init__(self, labels: Sequence[str]) -> None:
        super().__init__()
        self.labels = tuple(labels)
        self.own: dict[str, list[tuple[float, np.ndarray]]] = {}
        self.fused: dict[str, list[tuple[float, np.ndarray]]] = {}
        self.handovers = 0  # between two streams, before the end

    def add(self, e: Event) -> None:
        super().add(e)
        if isinstance(e, GestureEvent):
            self.own.setdefault(e.stream, []).append((e.t, np.asarray(e.probs)))
        elif (
            isinstance(e, HandoverEvent)
            and e.from_stream
            and e.to_stream
            and e.reason != "stream_ended"  # the replays' end, not a change of view
        ):
            self.handovers += 1

    def on_fused(self, stream: str, t: float, fused: Fused) -> None:
        self.fused.setdefault(stream, []).append((t, fused.probs))

    def window_accuracy(
        self, streams: Mapping[str, StitchedStream], window: int = 60
    ) -> dict[str, float | int | None]:
        """Share of windows whose top label is the gesture performed, over every stream's
        windows that lie wholly inside one gesture's own rows (transitions excluded): the
        classifier's own windows (`own`) and, with fusion, the fused ones (`fused`)."""
        out: dict[str, float | int | None] = {}
        for kind, per_stream in (("own", self.own), ("fused", self.fused)):
            right = total = 0
            for name, rows in per_stream.items():
                stream = streams[name]
                span = (window - 1) / stream.fps
                for t, probs in rows:
                    seg = next(
                        (s for s in stream.segments if s.onset_t <= t - span and t <= s.end_t),
                        None,
                    )
                    if seg is None:
                        continue
                    total += 1
                    right += self.labels[int(np.argmax(probs))] == seg.gesture
            out[kind] = round(right / total, 4) if total else None
            out[f"{kind}_windows"] = total
        return out


def engine_run_views(
    streams: Sequence[StitchedStream],
    control: ControlSettings,
    settings: EngineSettings,
    classifier: Classifier,
) -> ViewsRun:
    """Run `streams` (one per camera, main first; named by their view) together through
    the real engine, as fast as possible; the commands go to the first stream's drone.

    Raises:
        RuntimeError: a stream failed in the engine (the message is its error).
    """
    from proxima.engine.runner import Engine

    run = ViewsRun(classifier.labels)
    with tempfile.TemporaryDirectory(prefix="proxima-views-") as tmp:
        specs = []
        for rank, stream in enumerate(streams):
            path = Path(tmp) / f"{stream.view}.csv"
            stream.write(path)
            uri = f"replay:{path}@{stream.fps:.9g}"
            specs.append(StreamSpec(name=stream.view, uri=uri, priority=rank, drone="main"))
        bus = EventBus()
        bus.add_listener(run.add)
        engine = Engine(
            specs, bus, control=control, settings=settings, realtime=False, classifier=classifier
        )
        if engine.fusion is not None:
            engine.fusion.listener = run.on_fused
        engine.run()
    errors = [f"{n}: {s.error}" for n, s in engine.stats.items() if s.error]
    if errors:
        raise RuntimeError("; ".join(errors))
    return run


def captured(
    stream: StitchedStream, model: CaptureModel, rng: np.random.Generator
) -> StitchedStream:
    """`stream` as the capture model's camera and pose path would deliver it (its own
    frame rate, lost frames, jitter); the script's times are kept."""
    t = (np.asarray(stream.frames, np.float64) - 1.0) / stream.fps
    cap = model.apply_sequence(t, stream.xyz, stream.visibility, rng)
    return replace(
        stream,
        fps=cap.fps,
        frames=np.asarray(cap.frames, np.int64),
        xyz=cap.xyz,
        visibility=np.clip(cap.visibility, 0.0, 1.0),
    )
