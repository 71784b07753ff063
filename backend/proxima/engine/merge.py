"""Feeds every stream's updates to the decision path in stream-time order.

Each stream runs in its own thread at its own pace; a replay may run far ahead of
another. The arbiter compares streams at the same instant, so updates are buffered and
released in order of stream time: an update at `t` is decided only once every other
stream has either passed `t`, has an update waiting, or has ended. That makes
multi-stream replays decide the same at any speed. A live stream that has been silent
for `stale_after_s` of wall clock (reconnecting, frozen) stops holding the others back,
and its late updates are decided at the current time.

Submitting never blocks on the decisions' consumers: events go to the bus, which never
blocks either.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Protocol

from proxima.control import StreamUpdate
from proxima.types import Event


class Decider(Protocol):
    """The decision path the merge feeds: `CommandController`, or fusion in front of it
    (`proxima.engine.fusion.FusedDecisions`)."""

    def process(self, update: StreamUpdate) -> list[Event]: ...


class TimeOrderedMerge:
    """Orders updates from several threads by stream time and runs the controller."""

    def __init__(
        self,
        controller: Decider,
        publish: Callable[[Event], None],
        streams: Sequence[str],
        stale_after_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.controller = controller
        self.publish = publish
        self.streams = tuple(streams)
        self.stale_after_s = stale_after_s
        self._clock = clock
        self._lock = threading.Lock()
        self._pending: dict[str, deque[StreamUpdate]] = {s: deque() for s in self.streams}
        self._last_t: dict[str, float | None] = dict.fromkeys(self.streams)
        self._last_wall: dict[str, float] = dict.fromkeys(self.streams, clock())
        self._live: set[str] = set()
        self._ended: set[str] = set()
        self.decided = 0

    def set_live(self, stream: str, live: bool = True) -> None:
        """Mark a stream as live (camera): it may go stale instead of blocking others."""
        with self._lock:
            (self._live.add if live else self._live.discard)(stream)
            self._last_wall[stream] = self._clock()

    def submit(self, update: StreamUpdate) -> None:
        """Queue one update from a stream's thread and decide what has become decidable.

        Raises:
            ValueError: the update's stream is unknown.
        """
        if update.stream not in self._pending:
            raise ValueError(f"unknown stream {update.stream!r}; known: {self.streams}")
        with self._lock:
            self._pending[update.stream].append(update)
            self._last_t[update.stream] = update.t
            self._last_wall[update.stream] = self._clock()
            if update.ended:
                self._ended.add(update.stream)
            self._drain(force=False)

    def flush(self) -> None:
        """Decide everything still waiting, in time order (at the end of a run)."""
        with self._lock:
            self._drain(force=True)

    def _blocks(self, stream: str, t: float, rank: int, now: float) -> bool:
        """Whether `stream` may still submit an update that goes before (t, rank)."""
        if self._pending[stream] or stream in self._ended:
            return False
        if stream in self._live and now - self._last_wall[stream] > self.stale_after_s:
            return False
        last = self._last_t[stream]
        return last is None or last < t or (last == t and self.streams.index(stream) < rank)

    def _drain(self, force: bool) -> None:
        now = self._clock()
        while True:
            best: tuple[float, int] | None = None
            best_stream = ""
            for rank, stream in enumerate(self.streams):
                queue = self._pending[stream]
                if queue and (best is None or (queue[0].t, rank) < best):
                    best, best_stream = (queue[0].t, rank), stream
            if best is None:
                return
            if not force and any(
                self._blocks(s, best[0], best[1], now) for s in self.streams if s != best_stream
            ):
                return
            update = self._pending[best_stream].popleft()
            self.decided += 1
            for event in self.controller.process(update):
                self.publish(event)
