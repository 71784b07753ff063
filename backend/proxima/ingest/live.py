"""Live sources (webcam, RTSP): one reader thread per device keeps only the newest frame.

The reader thread owns the `cv2.VideoCapture`: it reads as fast as the device delivers,
overwrites a single slot with the newest timestamped frame and never waits for the
consumer, so a slow consumer drops frames instead of building latency. A small watchdog
thread marks the stream stalled when frames stop. The consumer
(`for frame in source`) takes each new frame once and refuses frames older than
`max_age_s` (a frame left over from before a stall). When the device drops, the reader
reconnects with exponential backoff, and the state shows it:

    connecting -> live <-> stalled;  live/stalled -> reconnecting -> live;  * -> ended

`stalled` means no new frame for `stall_after_s` while still connected; `reconnecting`
means the capture failed and a new one is being opened.
"""

from __future__ import annotations

import threading
import time
from abc import abstractmethod
from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np

from proxima.ingest.base import FrameSource, SourceError, StateListener
from proxima.types import Frame, StreamState


@dataclass(frozen=True)
class ReconnectPolicy:
    """How a live source retries. Waits grow `backoff_s * 2**k` up to `backoff_max_s`.

    `connect_attempts`: tries before the first frame ever arrives; after that many
    failures the source ends with an error (an unreachable URL is reported, not retried
    forever). `give_up_after_s`: once a stream has been live, how long to keep trying to
    get it back before ending with an error (None: forever).
    """

    backoff_s: float = 0.5
    backoff_max_s: float = 8.0
    connect_attempts: int = 3
    give_up_after_s: float | None = 60.0

    def delay(self, failures: int) -> float:
        return min(self.backoff_s * 2 ** max(failures - 1, 0), self.backoff_max_s)


@dataclass(frozen=True)
class _Slot:
    seq: int
    image: np.ndarray
    index: int
    t: float
    wall: float


class LiveSource(FrameSource):
    """Base of webcam and RTSP sources; subclasses say how to open the capture."""

    def __init__(
        self,
        uri: str,
        *,
        policy: ReconnectPolicy | None = None,
        stall_after_s: float = 1.0,
        max_age_s: float = 1.0,
        on_state: StateListener | None = None,
    ) -> None:
        super().__init__(uri, on_state)
        self.policy = policy or ReconnectPolicy()
        self.stall_after_s = stall_after_s
        self.max_age_s = max_age_s
        self.frames_read = 0  # frames the reader got from the device
        self.frames_dropped = 0  # frames overwritten before the consumer took them
        self.reconnects = 0
        self._slot: _Slot | None = None
        self._taken_seq = -1  # seq of the last frame the consumer took
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._watchdog: threading.Thread | None = None

    # -- subclass hooks -----------------------------------------------------------------
    @abstractmethod
    def _open_capture(self) -> cv2.VideoCapture:
        """Open the device. Raises SourceError with a reason when it cannot."""

    def start(self) -> LiveSource:
        """Start the reader thread (once); `open_source` calls this."""
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._run, name=f"reader {self.uri}", daemon=True
            )
            self._thread.start()
            self._watchdog = threading.Thread(
                target=self._watch, name=f"stall watchdog {self.uri}", daemon=True
            )
            self._watchdog.start()
        return self

    def _watch(self) -> None:
        """Mark the stream stalled when frames stop while connected; the reader cannot,
        as it is blocked in `read()` then. Runs whether or not anyone consumes frames."""
        while not self._stop.wait(0.1) and self._state != StreamState.ENDED:
            self._mark_stalled_if_quiet()

    # -- reader thread ------------------------------------------------------------------
    def _try_open(self) -> tuple[cv2.VideoCapture | None, str]:
        try:
            cap = self._open_capture()
        except SourceError as exc:
            return None, str(exc)
        except cv2.error as exc:
            return None, f"{self.uri}: OpenCV error: {exc}"
        return cap, ""

    def _give_up_reason(
        self, why: str, failures: int, ever_live: bool, lost_since: float | None
    ) -> str | None:
        """Why to stop retrying now, or None to go on (see `ReconnectPolicy`)."""
        if not ever_live and failures >= self.policy.connect_attempts:
            return f"{why} (gave up after {failures} attempts)"
        limit = self.policy.give_up_after_s
        if lost_since is not None and limit is not None and time.monotonic() - lost_since > limit:
            return f"{why} (gave up after {limit:g} s)"
        return None

    def _run(self) -> None:
        first_wall: float | None = None
        lost_since: float | None = None  # wall time the stream was last lost
        failures = 0
        index = 0
        try:
            while not self._stop.is_set():
                cap, why = self._try_open()
                if cap is not None:
                    try:
                        while not self._stop.is_set():
                            ok, image = cap.read()
                            if not ok or image is None:
                                break
                            now = time.monotonic()
                            if first_wall is None:
                                first_wall = now
                            self._publish(image, index, now - first_wall, now)
                            index += 1
                            failures = 0
                            lost_since = None
                            if self._state != StreamState.LIVE:
                                self._advance(StreamState.LIVE)
                    finally:
                        cap.release()
                    if self._stop.is_set():
                        break
                    # The server dropped, the camera went away, or no frame came within
                    # the read timeout.
                    self.reconnects += 1
                    why = f"{self.uri}: stream dropped" if first_wall else f"{self.uri}: no frame"
                failures += 1
                lost_since = lost_since or time.monotonic()
                reason = self._give_up_reason(why, failures, first_wall is not None, lost_since)
                if reason is not None:
                    self._end(reason)
                    return
                self._advance(StreamState.RECONNECTING, why)
                self._stop.wait(self.policy.delay(failures))
        except Exception as exc:  # a bug here must end this stream visibly, not silently
            self._end(f"{self.uri}: reader failed: {exc!r}")
        finally:
            self._end()
            with self._cond:
                self._cond.notify_all()

    def _publish(self, image: np.ndarray, index: int, t: float, wall: float) -> None:
        with self._cond:
            old = self._slot
            if old is not None and old.seq > self._taken_seq:
                self.frames_dropped += 1
            self._slot = _Slot((old.seq + 1) if old else 0, image, index, t, wall)
            self.frames_read += 1
            self._cond.notify_all()

    # -- consumer -----------------------------------------------------------------------
    def _mark_stalled_if_quiet(self) -> None:
        slot = self._slot
        if slot is None or time.monotonic() - slot.wall <= self.stall_after_s:
            return
        with self._state_lock:
            if self._state == StreamState.LIVE:
                quiet = time.monotonic() - slot.wall
                self._advance(StreamState.STALLED, f"no frame for {quiet:.1f} s")

    def _frames(self) -> Iterator[Frame]:
        self.start()
        while True:
            with self._cond:
                slot = self._slot
                if slot is None or slot.seq <= self._taken_seq:
                    if self._state == StreamState.ENDED:
                        return
                    self._cond.wait(0.1)
                    slot = self._slot
                if slot is not None and slot.seq > self._taken_seq:
                    self._taken_seq = slot.seq
                else:
                    slot = None
            if slot is None:
                continue
            if time.monotonic() - slot.wall > self.max_age_s:
                continue  # stale: left over from before a stall
            yield Frame(t=slot.t, index=slot.index, image=slot.image)

    def close(self) -> None:
        """Stop the reader thread (waits for a blocked read to time out) and end."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=self.join_timeout_s())
        if self._watchdog is not None:
            self._watchdog.join(timeout=1.0)
        super().close()
        with self._cond:
            self._cond.notify_all()

    def join_timeout_s(self) -> float:
        """How long `close` waits for the reader thread (a blocked read must time out)."""
        return 2.0
