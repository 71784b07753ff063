"""One clock for replayed streams and simulated vehicles.

Replays can run far faster than real time, and every decision of the engine uses stream
time, so a replay decides the same at any speed. Simulated vehicles fly at real time.
`FlightClock` joins the two without making stream time depend on the machine's speed
more than it must:

1. **Lock-step.** Before a stream's next frame goes to recognition, the engine's
   decision path must have decided that stream's previous frame, and every command it
   published must have been answered by the drone controller (mapped, checked, sent,
   acknowledged). So a command decided at stream time t reaches the vehicle before any
   frame after t is looked at.
2. **Real time while something flies.** While a vehicle executes a command (a move, a
   hold, a landing: from the controller's "sent" until its outcome "reached", "landed",
   ...), frames are paced to the wall clock, anchored where the motion began: the
   camera views see the drone where it really is at that stream time. When every
   vehicle is still, frames run flat out (a hovering simulator does not change, so
   nothing is lost by skipping its real time).
3. **The end waits.** A stream's last frame waits until no vehicle is moving, so a
   landing completes before the replay ends.

`now()` is the newest stream time let through, the scenario's time; the safety rules'
clock (rate limit, operator watchdog) runs on it too, so compressed idle stretches do
not look like a burst of commands.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from proxima.drone.events import CommandResultEvent
from proxima.events import CommandEvent, EventBus
from proxima.types import Event, Frame

if TYPE_CHECKING:
    from proxima.engine import Engine


class FlightClock:
    """Coordinates stream time with vehicles flying at real time (see the module)."""

    def __init__(self, answer_timeout_s: float = 15.0, motion_timeout_s: float = 90.0) -> None:
        self.answer_timeout_s = answer_timeout_s
        self.motion_timeout_s = motion_timeout_s
        self._cond = threading.Condition()
        self._now = 0.0
        self._anchor: tuple[float, float] | None = None  # (stream t, wall) of real-time pacing
        self._issued = 0
        self._answered = 0
        self._moving: dict[tuple[str, int | None, str], float] = {}
        self._prev_t: dict[str, float] = {}
        self._vehicles: list[Any] = []  # DroneLinks whose motion keeps real time
        self.still_speed_m_s = 0.05
        self.realtime_s = 0.0  # stream seconds that ran at real time
        self.problems: list[str] = []

    def track_vehicles(self, links: Any) -> None:
        """Also run at real time while any of these vehicles moves (a command's outcome
        "reached" comes within a tolerance, before the vehicle has settled)."""
        self._vehicles.extend(links)

    def _vehicle_moving(self) -> bool:
        for link in self._vehicles:
            tel = link.telemetry()
            if tel is None or tel.velocity is None or not tel.flying:
                continue
            if sum(v * v for v in tel.velocity) ** 0.5 > self.still_speed_m_s:
                return True
        return False

    def _busy(self) -> bool:  # call with self._cond held
        return bool(self._moving) or self._vehicle_moving()

    # --- time ---------------------------------------------------------------------------
    def now(self) -> float:
        """The scenario's time: the newest stream time let through."""
        with self._cond:
            return self._now

    def moving(self) -> bool:
        """Whether a vehicle is executing a command or still moving right now."""
        with self._cond:
            return self._busy()

    # --- what the drone controller does -------------------------------------------------
    def watch(self, bus: EventBus) -> None:
        """Follow the commands and their results on `bus`."""
        bus.add_listener(self._on_event)

    def _on_event(self, event: Event) -> None:
        if isinstance(event, CommandEvent):
            with self._cond:
                self._issued += 1
        elif isinstance(event, CommandResultEvent):
            key = (event.drone, event.log_id, event.command)
            with self._cond:
                if event.status == "done" and key in self._moving:
                    del self._moving[key]  # the outcome of a tracked command
                else:
                    self._answered += 1  # the controller's answer to a command
                    if event.status == "sent" and not event.outcome:
                        self._moving[key] = self._now  # tracked until its outcome comes
                self._cond.notify_all()

    def _wait_for(self, predicate: Callable[[], bool], timeout: float, what: str) -> bool:
        deadline = time.monotonic() + timeout
        with self._cond:
            while not predicate():  # polled too: vehicles move without notifying
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    self.problems.append(
                        f"t={self._now:.2f}s: gave up waiting {timeout:.0f} s for {what}"
                    )
                    return False
                self._cond.wait(min(remaining, 0.02))
            return True

    def settle(self, timeout: float | None = None) -> bool:
        """Wait until every command was answered and no vehicle moves (wall seconds)."""
        timeout = self.motion_timeout_s if timeout is None else timeout
        return self._wait_for(
            lambda: self._answered >= self._issued and not self._busy(),
            timeout,
            "the vehicles to answer and stop",
        )

    # --- the gate in front of each stream ------------------------------------------------
    def gate(self, stream: str, t: float, decided: Callable[[], float], last: bool) -> None:
        """Called before frame `t` of `stream` is recognised; blocks as the module says.
        `decided()` is the stream time up to which the engine has decided."""
        prev = self._prev_t.get(stream)
        if prev is not None:
            deadline = time.monotonic() + self.answer_timeout_s
            while decided() < prev:
                if time.monotonic() > deadline:
                    with self._cond:
                        self.problems.append(f"{stream} t={t:.2f}s: decisions stalled")
                    break
                time.sleep(0.0002)
        self._prev_t[stream] = t
        self._wait_for(
            lambda: self._answered >= self._issued,
            self.answer_timeout_s,
            "the drone controller to answer a command",
        )
        if last:
            self._wait_for(lambda: not self._busy(), self.motion_timeout_s, "a vehicle to stop")
        with self._cond:
            if self._busy():
                if self._anchor is None:
                    self._anchor = (max(self._now, t), time.monotonic())
                delay = self._anchor[1] + (t - self._anchor[0]) - time.monotonic()
            else:
                if self._anchor is not None:
                    self.realtime_s += max(self._now - self._anchor[0], 0.0)
                self._anchor = None
                delay = 0.0
        if delay > 0:
            time.sleep(delay)
        with self._cond:
            self._now = max(self._now, t)


def install_gate(
    engine: Engine,
    clock: FlightClock,
    last_t: Mapping[str, float],
    views: Mapping[str, Callable[[Frame], Frame]] | None = None,
) -> None:
    """Put `clock`'s gate (and the stream's camera view, if any) in front of every
    stream of `engine`, as a frame tap: each frame waits at the gate in its stream's
    thread, is seen through the view, then goes on to recognition. Call it before
    `engine.start()`, so the first frame is gated too.

    `last_t[name]` is the stream time of the stream's last frame, so the gate knows it.
    """
    views = views or {}
    controller = engine.controller

    def decided() -> float:
        return float(controller.now)

    for spec in engine.specs:
        end = last_t.get(spec.name, float("inf")) - 1e-6
        view = views.get(spec.name)

        def gate(
            frame: Frame,
            _name: str = spec.name,
            _view: Callable[[Frame], Frame] | None = view,
            _end: float = end,
        ) -> Frame | None:
            clock.gate(_name, frame.t, decided, frame.t >= _end)
            return _view(frame) if _view is not None else None

        engine.add_tap(spec.name, on_frame=gate)
