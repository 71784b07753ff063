"""Pace a stream to its own timestamps (real time) or let it run as fast as possible."""

from __future__ import annotations

import threading
import time


class Pacer:
    """Sleeps so that frame time `t` is reached `t - t0` seconds of wall clock after the
    first frame. With `realtime=False` it never sleeps. `wait` returns False when the
    `stop` event is set while sleeping, so closing a source interrupts it at once."""

    def __init__(self, realtime: bool, stop: threading.Event) -> None:
        self.realtime = realtime
        self._stop = stop
        self._origin: tuple[float, float] | None = None  # (stream t0, wall clock t0)

    def wait(self, t: float) -> bool:
        if self._stop.is_set():
            return False
        if not self.realtime:
            return True
        now = time.monotonic()
        if self._origin is None:
            self._origin = (t, now)
            return True
        delay = self._origin[1] + (t - self._origin[0]) - now
        if delay > 0:
            return not self._stop.wait(delay)
        return True
