"""The controller's watchdog thread (every 50 ms): a lost link disarms gesture control of
its drone; an operator no stream has seen for `operator_lost_s` makes every flying drone
under gesture control hold (once per loss, logged with source "watchdog"); tracked
commands get their outcomes.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping

from proxima.drone.controller.execute import CommandExecutor
from proxima.drone.controller.outcomes import OutcomeTracker
from proxima.drone.controller.record import CommandContext, CommandRecorder
from proxima.drone.link import DroneLink
from proxima.drone.safety import SafetyGate
from proxima.events import CommandEvent
from proxima.types import LinkState

PERIOD_S = 0.05


class Watchdog:
    """Runs its checks on its own thread from construction until `stop()`."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        safety: SafetyGate,
        executor: CommandExecutor,
        tracker: OutcomeTracker,
        recorder: CommandRecorder,
    ) -> None:
        self.links = links
        self.safety = safety
        self.executor = executor
        self.tracker = tracker
        self.recorder = recorder
        self._link_states = {name: link.state for name, link in links.items()}
        self._operator_lost_handled = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="drone-watchdog", daemon=True)
        self._thread.start()

    def operator_seen(self) -> None:
        """The operator is in view again: a later loss holds the drones again."""
        self._operator_lost_handled = False

    def stop(self, timeout: float = 3.0) -> None:
        self._stop.set()
        self._thread.join(timeout=timeout)

    def _run(self) -> None:
        while not self._stop.wait(PERIOD_S):
            try:
                self._check_links()
                self._check_operator()
                self.tracker.check()
            except Exception as exc:  # never let the watchdog die silently
                self.recorder.alarm("", "controller_error", f"{type(exc).__name__}: {exc}")

    def _check_links(self) -> None:
        for name, link in self.links.items():
            state, was = link.state, self._link_states[name]
            self._link_states[name] = state
            if state == LinkState.LOST and was != LinkState.LOST:
                armed = self.safety.is_armed(name)
                self.executor.set_control(name, False)
                self.tracker.drop(name, "link_lost")
                note = "; gesture control disarmed: have_command again" if armed else ""
                self.recorder.alarm(name, "link_lost", f"{name}: link lost, nothing is sent{note}")

    def _check_operator(self) -> None:
        if self._operator_lost_handled or not self.safety.operator_lost():
            return
        self._operator_lost_handled = True
        after = self.safety.cfg.operator_lost_s
        for name, link in self.links.items():
            tel = link.telemetry()
            if not self.safety.is_armed(name) or tel is None or not tel.flying:
                continue
            self.recorder.alarm(
                name, "operator_lost", f"operator not seen for {after:.0f} s: {name} hovers"
            )
            event = CommandEvent(t=time.time(), stream="", command="hover", drone=name)
            ctx = CommandContext(name, "watchdog", "operator_lost", "", event.t)
            # Off this thread: a hold waits for the vehicle, the other drones must not.
            threading.Thread(target=self.executor.hold, args=(event, ctx), daemon=True).start()
