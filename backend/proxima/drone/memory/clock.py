"""Clocks for the in-memory link: the wall clock, or one that moves only when told."""

from __future__ import annotations

import threading
import time
from typing import Protocol


class Clock(Protocol):
    """Monotonic seconds, and a way to let time pass."""

    def now(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class WallClock:
    """Real time: `time.monotonic` and `time.sleep`."""

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        time.sleep(seconds)


class ManualClock:
    """Time that passes only through `advance` (or `sleep`, which is the same), so a test
    decides exactly how far a vehicle flies. Thread-safe; also callable, as the
    `clock` of `SafetyGate` and `DroneController`."""

    def __init__(self, start: float = 1000.0) -> None:
        self._t = start
        self._lock = threading.Lock()

    def now(self) -> float:
        with self._lock:
            return self._t

    def __call__(self) -> float:
        return self.now()

    def advance(self, seconds: float) -> float:
        """Move time forward by `seconds`; the new time.

        Raises:
            ValueError: negative `seconds` (time does not run backwards).
        """
        if seconds < 0:
            raise ValueError(f"cannot advance a clock by {seconds} s")
        with self._lock:
            self._t += seconds
            return self._t

    def sleep(self, seconds: float) -> None:
        self.advance(max(seconds, 0.0))
