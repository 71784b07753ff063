"""The in-memory backend: `MemoryLink`, the MAVLink commands to a simulated vehicle in this
process (no sockets, no threads), on the wall clock or a `ManualClock`."""

from proxima.drone.memory.clock import Clock, ManualClock, WallClock
from proxima.drone.memory.link import MemoryLink

__all__ = ["Clock", "ManualClock", "MemoryLink", "WallClock"]
