"""A bus subscriber that writes every event as one JSON line.

The bus calls `_enqueue` synchronously, which only puts the event on an unbounded queue;
a writer thread serialises and writes. Recognition never waits for the disk, and no event
is dropped (a `Subscription` would drop the oldest when full).
"""

from __future__ import annotations

import json
import queue
import threading
from pathlib import Path

from proxima.events import EventBus
from proxima.types import Event

_STOP = object()


class JsonlWriter:
    """Appends every event published on `bus` to `path` as JSON lines until `close()`."""

    def __init__(self, path: str | Path, bus: EventBus) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = self.path.open("w", encoding="utf-8")
        self._queue: queue.SimpleQueue[object] = queue.SimpleQueue()
        self._closed = False
        self.written = 0
        self._thread = threading.Thread(target=self._run, name=f"jsonl {self.path}", daemon=True)
        self._thread.start()
        bus.add_listener(self._enqueue)

    def _enqueue(self, event: Event) -> None:
        if not self._closed:
            self._queue.put(event)

    def _run(self) -> None:
        while True:
            item = self._queue.get()
            if item is _STOP:
                break
            assert isinstance(item, Event)
            self._file.write(json.dumps(item.to_dict(), separators=(",", ":")) + "\n")
            self.written += 1
        self._file.flush()

    def close(self) -> None:
        """Write what is queued, then close the file (safe to call twice)."""
        if self._closed:
            return
        self._closed = True
        self._queue.put(_STOP)
        self._thread.join()
        self._file.close()

    def __enter__(self) -> JsonlWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
