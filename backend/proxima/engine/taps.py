"""Frame taps: code outside the engine that sees a stream's frames in the stream's own
thread, without replacing any part of the pipeline.

A tap has one or both of two callables:

- `on_frame(frame)` before recognition; it may return a replacement frame (a simulated
  camera view of a replay) or None to leave the frame as it is;
- `on_update(frame, update)` after recognition, with the frame's `StreamUpdate`.

Taps run in the order they were added. A tap runs in the stream thread, so a slow one
slows its stream (the scenario clock relies on this to pace replays; a thumbnail encoder
must keep to its rate). A tap that raises, or returns something that is not a `Frame`,
is skipped for that frame and recognition goes on with the frame as it was; the first
such failure is logged with its traceback, later ones every `LOG_EVERY` failures.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from proxima.control import StreamUpdate
from proxima.types import Frame

log = logging.getLogger(__name__)

FrameTap = Callable[[Frame], Frame | None]
UpdateTap = Callable[[Frame, StreamUpdate], None]

LOG_EVERY = 1000  # after its first failure, a failing tap is logged every N failures


@dataclass(eq=False)
class Tap:
    """One registered tap of `stream`; give it to `remove` to unregister it."""

    stream: str
    on_frame: FrameTap | None = None
    on_update: UpdateTap | None = None
    failures: int = 0  # failed calls, both callables (counted by the stream thread)
    _logged: set[str] = field(default_factory=set, repr=False)  # failures logged in full


class StreamTaps:
    """The taps of one stream. Added and removed from any thread; the stream thread runs
    an immutable snapshot, so a tap added mid-frame takes effect from the next frame."""

    def __init__(self, stream: str) -> None:
        self.stream = stream
        self._taps: tuple[Tap, ...] = ()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._taps)

    def add(self, on_frame: FrameTap | None = None, on_update: UpdateTap | None = None) -> Tap:
        """Register a tap; returns it (for `remove`).

        Raises:
            ValueError: neither callable given.
        """
        if on_frame is None and on_update is None:
            raise ValueError(f"a tap of stream {self.stream!r} needs on_frame or on_update")
        tap = Tap(self.stream, on_frame, on_update)
        with self._lock:
            self._taps = (*self._taps, tap)
        return tap

    def remove(self, tap: Tap) -> None:
        """Unregister `tap` (no error if it is not registered)."""
        with self._lock:
            self._taps = tuple(t for t in self._taps if t is not tap)

    def before(self, frame: Frame) -> Frame:
        """Run every `on_frame`; returns the frame recognition gets."""
        for tap in self._taps:
            if tap.on_frame is None:
                continue
            try:
                out = tap.on_frame(frame)
            except Exception:
                self._failed(tap, "on_frame raised", raised=True)
                continue
            if out is None:
                continue
            if not isinstance(out, Frame):
                self._failed(tap, f"on_frame returned {type(out).__name__}, not a Frame")
                continue
            frame = out
        return frame

    def after(self, frame: Frame, update: StreamUpdate) -> None:
        """Run every `on_update`."""
        for tap in self._taps:
            if tap.on_update is None:
                continue
            try:
                tap.on_update(frame, update)
            except Exception:
                self._failed(tap, "on_update raised", raised=True)

    def _failed(self, tap: Tap, what: str, raised: bool = False) -> None:
        tap.failures += 1
        if what not in tap._logged:  # the first failure of its kind, with the traceback
            tap._logged.add(what)
            log.error(
                "stream %s: a frame tap failed (%s); recognition goes on",
                tap.stream,
                what,
                exc_info=raised,
            )
        elif tap.failures % LOG_EVERY == 0:
            log.warning(
                "stream %s: a frame tap failed %d times (%s)", tap.stream, tap.failures, what
            )
