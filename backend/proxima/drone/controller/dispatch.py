"""`DroneController`: the drone side of the live engine's events.

The engine's arbiter decides *which* drone a gesture goes to and publishes a
`CommandEvent`; the controller hands it to that drone's worker thread (so a slow vehicle
never delays another), where `execute.CommandExecutor` maps, checks and sends it and
`outcomes.OutcomeTracker` follows it to its outcome. It also follows the engine's arming
(gesture control of every drone), poses (the operator watchdog, `watchdog.Watchdog`) and
actions (the confidence logged with a command), and offers the two-step emergency stop
(`estop`).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from typing import Any

from proxima.drone.controller.estop import EmergencyStops
from proxima.drone.controller.execute import CommandExecutor
from proxima.drone.controller.outcomes import OutcomeTracker
from proxima.drone.controller.record import CommandContext, CommandRecorder, ControlOutcome
from proxima.drone.controller.watchdog import Watchdog
from proxima.drone.heading import HeadingPolicy
from proxima.drone.link import DroneLink
from proxima.drone.mapping import CommandMapping, load_mapping
from proxima.drone.safety import EmergencyStopRequest, SafetyConfig, SafetyGate
from proxima.events import ActionEvent, ArmingEvent, CommandEvent, EventBus, PoseEvent
from proxima.store.command_log import CommandLog
from proxima.types import Event

# A worker's queue holds commands (event, confidence, future), arming changes, or None
# (stop).
_WorkItem = tuple[CommandEvent, float | None, Future] | tuple[str, bool] | None


class DroneController:
    """Routes commands for a set of named drones. Call `attach(bus)` to follow the
    engine's events, or `handle(event)` directly (blocking). `clock` (monotonic seconds)
    times the outcome deadlines; the safety rules keep their own clock. `heading` says
    which way each drone points while it flies a move (`proxima.drone.heading`; default:
    no yaw sent)."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        *,
        mapping: CommandMapping | None = None,
        safety: SafetyGate | SafetyConfig | None = None,
        log: CommandLog | None = None,
        bus: EventBus | None = None,
        arrive_tolerance_m: float = 0.25,
        clock: Callable[[], float] = time.monotonic,
        heading: HeadingPolicy | None = None,
    ) -> None:
        self.links = dict(links)
        self.mapping = mapping or load_mapping()
        self.safety = safety if isinstance(safety, SafetyGate) else SafetyGate(safety)
        self.log = log
        self.bus = bus
        speeds = dict.fromkeys(self.links, self.mapping.cruise_speed_m_s)
        self.recorder = CommandRecorder(log, self._publish)
        self.tracker = OutcomeTracker(self.links, self.recorder, speeds, arrive_tolerance_m, clock)
        self.executor = CommandExecutor(
            self.links, self.mapping, self.safety, self.recorder, self.tracker, speeds, heading
        )
        self.estops = EmergencyStops(self.links, self.safety, self.executor, self.recorder)
        self._confidence: dict[tuple[str, str], float] = {}
        self._queues: dict[str, queue.SimpleQueue[_WorkItem]] = {}
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self._subscription: Any = None
        self.watchdog = Watchdog(
            self.links, self.safety, self.executor, self.tracker, self.recorder
        )

    @property
    def arrive_tolerance_m(self) -> float:
        """How close to its target a move counts as reached."""
        return self.tracker.arrive_tolerance_m

    # --- wiring -----------------------------------------------------------------------
    def attach(self, bus: EventBus) -> None:
        """Follow `bus`: commands, arming, poses (operator watchdog), actions (confidence)."""
        self.bus = self.bus or bus
        self._subscription = bus.subscribe(types=("command", "arming", "pose", "action"))
        for name in self.links:
            self._queues[name] = queue.SimpleQueue()
            t = threading.Thread(target=self._work, args=(name,), name=f"drone-{name}", daemon=True)
            t.start()
            self._threads.append(t)
        t = threading.Thread(target=self._dispatch, name="drone-dispatch", daemon=True)
        t.start()
        self._threads.append(t)

    def close(self) -> None:
        """Stop the controller's threads (the links stay open: their owner closes them)."""
        self._stop.set()
        if self._subscription is not None:
            self._subscription.close()
        for q in self._queues.values():
            q.put(None)
        for t in self._threads:
            t.join(timeout=3.0)
        self.watchdog.stop()

    def submit(self, event: CommandEvent, confidence: float | None = None) -> Future:
        """Queue a command on its drone's worker; the future gives the ControlOutcome."""
        fut: Future = Future()
        q = self._queues.get(event.drone)
        if q is None:
            fut.set_result(self.handle(event, confidence=confidence))
        else:
            q.put((event, confidence, fut))
        return fut

    def on_event(self, event: Event) -> None:
        """Feed one engine event (what `attach` does for every event on the bus)."""
        if isinstance(event, PoseEvent):
            # The arbiter's rule: a stream that sees the operator, feet or not, keeps
            # them present; only NONE everywhere for operator_lost_s means hover.
            seen = event.sight != "none"
            self.safety.note_operator(event.stream, seen)
            if seen:
                self.watchdog.operator_seen()
        elif isinstance(event, ActionEvent):
            if event.action:
                self._confidence[(event.stream, event.action)] = event.confidence
        elif isinstance(event, ArmingEvent):
            # The engine arms the operator, i.e. every drone. Its disarm follows the
            # command that caused it (wave_off, the hover on losing the operator): apply
            # it in order on each drone's worker so that command still goes out first.
            for name in self.links:
                q = self._queues.get(name)
                if q is None:
                    self.executor.set_control(name, event.armed)
                else:
                    q.put(("arming", event.armed))
        elif isinstance(event, CommandEvent):
            self.submit(event)

    def _publish(self, event: Event) -> None:
        if self.bus is not None:
            self.bus.publish(event)

    def _dispatch(self) -> None:
        sub = self._subscription
        while not self._stop.is_set():
            event = sub.get(timeout=0.2)
            if event is not None:
                self.on_event(event)

    def _work(self, name: str) -> None:
        q = self._queues[name]
        while True:
            item = q.get()
            if item is None:
                return
            if isinstance(item[0], str):
                self.executor.set_control(name, bool(item[1]))
                continue
            event, confidence, fut = item
            try:
                fut.set_result(self.handle(event, confidence=confidence))
            except Exception as exc:  # keep the worker alive; the future reports it
                fut.set_exception(exc)

    # --- commands -----------------------------------------------------------------------
    def gesture_control_armed(self, drone: str) -> bool:
        return self.safety.is_armed(drone)

    def handle(
        self,
        event: CommandEvent,
        *,
        confidence: float | None = None,
        source: str = "gesture",
    ) -> ControlOutcome:
        """Map, check, send, log one command; blocks until the vehicle answered."""
        if confidence is None:
            confidence = self._confidence.get((event.stream, event.command))
        ctx = CommandContext(event.drone, source, event.command, event.stream, event.t, confidence)
        return self.executor.handle(event, ctx)

    def request_emergency_stop(self, drone: str, kind: str = "land") -> EmergencyStopRequest:
        """Step one of two: nothing is sent; confirm with the returned token.

        Raises:
            KeyError: unknown drone.  ValueError: unknown kind.
        """
        return self.estops.request(drone, kind)

    def confirm_emergency_stop(self, token: str, drone: str | None = None) -> ControlOutcome:
        """Step two: land (or kill the motors of) the drone the token was issued for.

        Raises:
            EmergencyStopError: unknown, used or expired token, or a token issued for
                another drone than `drone` (nothing is sent).
        """
        return self.estops.confirm(token, drone)
