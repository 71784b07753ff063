"""A pose-only feed: replayed landmark streams published as PoseEvents on a bus.

It exercises the console (tiles, labelling, the benchmark) with real recorded landmarks
through the project's replay source, without running recognition; the live engine
publishes the same PoseEvents (plus gestures, actions, ...) when it runs.
"""

from __future__ import annotations

import threading

from proxima.events import EventBus, PoseEvent
from proxima.ingest import open_source
from proxima.pose import operator_sight


class ReplayPoseFeed:
    """One thread per stream replaying `replay:PATH@FPS` in real time, looping at the end
    (stream time keeps increasing across loops)."""

    def __init__(self, bus: EventBus, streams: dict[str, str], loop: bool = True) -> None:
        self.bus = bus
        self.streams = streams  # name -> replay URI
        self.loop = loop
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self.published = dict.fromkeys(streams, 0)
        self.errors: dict[str, str] = {}

    def _run(self, name: str, uri: str) -> None:
        offset = 0.0
        while not self._stop.is_set():
            last = 0.0
            try:
                with open_source(uri, realtime=True) as source:
                    for frame in source:
                        if self._stop.is_set():
                            return
                        pose = frame.pose
                        if pose is None:
                            continue
                        last = frame.t
                        self.bus.publish(
                            PoseEvent(
                                t=offset + frame.t,
                                stream=name,
                                xyz=pose.xyz.round(4).tolist(),
                                visibility=pose.visibility.round(3).tolist(),
                                sight=operator_sight(pose).name.lower(),
                            )
                        )
                        self.published[name] += 1
            except Exception as exc:  # shown to the caller, never silent
                self.errors[name] = f"{type(exc).__name__}: {exc}"
                return
            if not self.loop:
                return
            offset += last + 1.0 / 30

    def start(self) -> ReplayPoseFeed:
        for name, uri in self.streams.items():
            t = threading.Thread(
                target=self._run, args=(name, uri), daemon=True, name=f"feed-{name}"
            )
            self._threads.append(t)
            t.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(timeout)

    def __enter__(self) -> ReplayPoseFeed:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
