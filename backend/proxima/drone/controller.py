"""From a decided command to a vehicle: mapping, safety, link, log, result events.

The live engine's arbiter decides *which* drone a gesture goes to and publishes a
`CommandEvent`; `DroneController` turns it into a MAVLink action through the mapping
table, checks it against the safety rules, sends it over that drone's link, logs every
step to the command log and publishes `CommandResultEvent`s, then watches the vehicle
until the outcome is known (reached, landed, not reached). A watchdog thread hovers the
drones when the operator is lost, drops gesture control when a link is lost, and tracks
outcomes. Each drone has its own worker thread, so a slow vehicle never delays another.
"""

from __future__ import annotations

import math
import queue
import threading
import time
from collections.abc import Mapping
from concurrent.futures import Future
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

from proxima.drone.events import CommandResultEvent, DroneAlarmEvent
from proxima.drone.link import CommandResult, DroneLink, Telemetry
from proxima.drone.mapping import CommandMapping, MappedAction, MappingError, load_mapping
from proxima.drone.safety import (
    EmergencyStopRequest,
    SafetyConfig,
    SafetyGate,
    Verdict,
)
from proxima.events import ActionEvent, ArmingEvent, CommandEvent, EventBus, PoseEvent
from proxima.store.command_log import CommandLog
from proxima.types import Event, LinkState

# Modes from which a move may take the vehicle into its guided mode: the vehicle is only
# holding position. Gestures never override LAND, RTL, a mission or a pilot's manual mode.
_HOLDING = {
    "ardupilot": {"GUIDED", "LOITER", "BRAKE", "POSHOLD"},
    "px4": {"OFFBOARD", "LOITER", "POSCTL"},
}


@dataclass(frozen=True)
class ControlOutcome:
    """What the controller did with one command. `status`: "sent" (the vehicle
    accepted it), "failed" (sent, the vehicle refused or never answered), "refused"
    (safety or mapping stopped it: nothing sent), "ignored" (nothing to do), "done"
    (handled without a message, e.g. arming gesture control), "pending" (an emergency
    stop waiting for its confirmation)."""

    drone: str
    command: str
    action: str
    status: str
    reason: str = ""
    result: CommandResult | None = None
    log_id: int | None = None
    target: tuple[float, float, float] | None = None

    @property
    def sent(self) -> bool:
        return self.status in ("sent", "failed")


@dataclass
class _Tracked:
    log_id: int | None
    command: str
    action: str
    gesture_t: float
    stream: str
    target: tuple[float, float, float] | None
    deadline: float


class DroneController:
    """Routes commands for a set of named drones. Call `attach(bus)` to follow the
    engine's events, or `handle(event)` directly (blocking)."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        *,
        mapping: CommandMapping | None = None,
        safety: SafetyGate | SafetyConfig | None = None,
        log: CommandLog | None = None,
        bus: EventBus | None = None,
        arrive_tolerance_m: float = 0.25,
    ) -> None:
        self.links = dict(links)
        self.mapping = mapping or load_mapping()
        self.safety = safety if isinstance(safety, SafetyGate) else SafetyGate(safety)
        self.log = log
        self.bus = bus
        self.arrive_tolerance_m = arrive_tolerance_m
        self._speed = dict.fromkeys(self.links, self.mapping.cruise_speed_m_s)
        self._locks = {name: threading.Lock() for name in self.links}
        self._tracked: dict[str, _Tracked] = {}
        self._track_lock = threading.Lock()
        self._confidence: dict[tuple[str, str], float] = {}
        self._link_states = {name: link.state for name, link in self.links.items()}
        self._operator_lost_handled = False
        self._queues: dict[str, queue.SimpleQueue] = {}
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self._subscription: Any = None
        self._watchdog = threading.Thread(target=self._watch, name="drone-watchdog", daemon=True)
        self._watchdog.start()

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
        for t in [*self._threads, self._watchdog]:
            t.join(timeout=3.0)

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
                self._operator_lost_handled = False
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
                    self._set_control(name, event.armed)
                else:
                    q.put(("arming", event.armed))
        elif isinstance(event, CommandEvent):
            self.submit(event)

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
            if item[0] == "arming":
                self._set_control(name, item[1])
                continue
            event, confidence, fut = item
            try:
                fut.set_result(self.handle(event, confidence=confidence))
            except Exception as exc:  # keep the worker alive; the future reports it
                fut.set_exception(exc)

    # --- gesture control ------------------------------------------------------------------
    def gesture_control_armed(self, drone: str) -> bool:
        return self.safety.is_armed(drone)

    def _set_control(self, drone: str, armed: bool) -> None:
        if armed:
            self.safety.arm_control(drone)
        else:
            self.safety.disarm_control(drone)
        link = self.links.get(drone)
        if link is not None and hasattr(link, "gesture_control"):
            link.gesture_control = armed

    # --- the command path ---------------------------------------------------------------
    def handle(
        self,
        event: CommandEvent,
        *,
        confidence: float | None = None,
        source: str = "gesture",
    ) -> ControlOutcome:
        """Map, check, send, log one command; blocks until the vehicle answered."""
        drone, gesture = event.drone, event.command
        if confidence is None:
            confidence = self._confidence.get((event.stream, gesture))
        base = {
            "drone": drone,
            "source": source,
            "command": gesture,
            "stream": event.stream,
            "gesture_t": event.t,
            "confidence": confidence,
        }
        try:
            mapped = self.mapping.lookup(gesture)
        except MappingError as exc:
            return self._finish(event, base, "", "refused", str(exc))
        link = self.links.get(drone)
        if link is None:
            return self._finish(event, base, mapped.action, "refused", f"unknown drone {drone!r}")
        with self._locks[drone]:
            self._begin(base, mapped.action)
            return self._handle_locked(event, base, mapped, link)

    def _begin(self, base: dict, action: str) -> None:
        """Write the command's row (status "pending") before anything is sent."""
        if self.log is not None:
            base["log_id"] = self.log.add(**base, action=action, status="pending")
        base["_started"] = datetime.now(UTC)

    def _handle_locked(
        self, event: CommandEvent, base: dict, mapped: MappedAction, link: DroneLink
    ) -> ControlOutcome:
        drone, action = event.drone, mapped.action
        if action == "arm_control":
            self._set_control(drone, True)
            return self._finish(
                event, base, action, "done", "gesture control armed", outcome="control_armed"
            )
        if not self.safety.is_armed(drone):
            return self._finish(
                event,
                base,
                action,
                "refused",
                "gesture control not armed (have_command first): nothing sent",
            )
        if action == "none":
            return self._finish(event, base, action, "ignored", "mapped to no action")
        if action == "abort":  # disarm first: whatever happens to the hold, control is off
            self._set_control(drone, False)
        if link.state != LinkState.OK:
            return self._finish(event, base, action, "refused", f"link {link.state}: nothing sent")
        tel = link.telemetry()
        if tel is None:
            return self._finish(event, base, action, "refused", "no telemetry yet")
        verdict = self.safety.check_rate(drone, action)
        if not verdict.ok:
            return self._finish(event, base, action, "refused", verdict.reason)
        if action in ("hold", "abort"):
            if not tel.flying:
                reason = "on the ground: nothing to hold"
                outcome = "control_disarmed" if action == "abort" else None
                return self._finish(event, base, action, "ignored", reason, outcome=outcome)
            result = link.hold()
            return self._sent(event, base, action, result, link, track="hold")
        if action == "land":
            if not tel.flying:
                return self._finish(event, base, action, "ignored", "already on the ground")
            return self._sent(event, base, action, link.land(), link, track="land")
        if action in ("change_speed", "resume_speed"):
            if action == "change_speed":
                factor = mapped.factor or 0.5
                speed = max(self.mapping.min_speed_m_s, self._speed[drone] * factor)
            else:
                speed = self.mapping.cruise_speed_m_s
            result = link.change_speed(speed)
            if result.ok:
                self._speed[drone] = speed
            return self._sent(event, base, action, result, link)
        if action == "move":
            return self._move(event, base, mapped, link, tel)
        return self._finish(event, base, action, "refused", f"unhandled action {action!r}")

    def _move(
        self,
        event: CommandEvent,
        base: dict,
        mapped: MappedAction,
        link: DroneLink,
        tel: Telemetry,
    ) -> ControlOutcome:
        action = mapped.action
        if not tel.flying or tel.position is None:
            why = "not flying" if tel.position is not None else "no local position"
            return self._finish(event, base, action, "refused", f"{why}: nothing sent")
        holding = _HOLDING.get(tel.autopilot, _HOLDING["ardupilot"])
        if tel.mode not in holding:
            return self._finish(
                event,
                base,
                action,
                "refused",
                f"vehicle in {tel.mode}: gestures do not override it",
            )
        step_len = mapped.step_m or self.mapping.step_m
        f, r, d = (c * step_len for c in mapped.direction or (0.0, 0.0, 0.0))
        yaw = tel.yaw
        step = (f * math.cos(yaw) - r * math.sin(yaw), f * math.sin(yaw) + r * math.cos(yaw), d)
        guided = "OFFBOARD" if tel.autopilot == "px4" else "GUIDED"
        origin = tel.position
        settling = tel.position_target
        if tel.mode == guided and settling is not None and tel.distance_to(settling) < 0.5:
            origin = settling  # step from where the vehicle is settling, not from noise
        target = (origin[0] + step[0], origin[1] + step[1], origin[2] + step[2])
        verdict: Verdict = self.safety.check_move(step, target)
        if not verdict.ok:
            return self._finish(event, base, action, "refused", verdict.reason, target=target)
        if tel.mode != guided:
            result = link.enter_guided()
            if not result.ok:
                return self._sent(event, base, action, result, link, target=target)
        result = link.goto_local(*target)
        return self._sent(event, base, action, result, link, track="move", target=target)

    # --- results, log, events -----------------------------------------------------------
    def _sent(
        self,
        event: CommandEvent,
        base: dict,
        action: str,
        result: CommandResult,
        link: DroneLink,
        *,
        track: str | None = None,
        target: tuple[float, float, float] | None = None,
    ) -> ControlOutcome:
        nothing_sent = result.ack in (
            "link_lost",
            "not_connected",
            "wrong_mode",
            "no_position",
            "unknown_mode",
        )
        if nothing_sent:
            status = "refused"
        else:
            status = "sent" if result.ok else "failed"
            self.safety.note_sent(event.drone)
        reason = result.detail or ("" if result.ok else f"vehicle answered {result.ack}")
        outcome = None
        if status == "sent" and track is None:
            outcome = "done"
        elif status != "sent":
            outcome = status
        out = self._finish(
            event, base, action, status, reason, result=result, outcome=outcome, target=target
        )
        if status == "sent" and track is not None:
            self._track(event, out, track, target, link)
        return out

    def _track(
        self,
        event: CommandEvent,
        out: ControlOutcome,
        kind: str,
        target: tuple[float, float, float] | None,
        link: DroneLink,
    ) -> None:
        tel = link.telemetry()
        sent = out.result.sent if out.result is not None else {}
        if kind == "hold" and target is None and "x" in sent:
            target = (sent["x"], sent["y"], sent["z"])  # the hold point that was sent
        if kind == "land":
            alt = (tel.altitude or 0.0) if tel else 0.0
            timeout = 30.0 + alt / 0.3
        else:
            dist = tel.distance_to(target) if tel and target else 0.0
            timeout = 5.0 + 3.0 * dist / max(self._speed[event.drone], 0.1)
        item = _Tracked(
            out.log_id,
            event.command,
            kind,
            event.t,
            event.stream,
            target,
            time.monotonic() + timeout,
        )
        with self._track_lock:
            old = self._tracked.get(event.drone)
            self._tracked[event.drone] = item
        if old is not None:
            self._outcome(event.drone, old, "superseded")

    def _finish(
        self,
        event: CommandEvent,
        base: dict,
        action: str,
        status: str,
        reason: str,
        *,
        result: CommandResult | None = None,
        outcome: str | None = None,
        target: tuple[float, float, float] | None = None,
    ) -> ControlOutcome:
        if outcome is None and status in ("refused", "ignored", "failed"):
            outcome = status
        fields: dict[str, Any] = dict(base)
        log_id: int | None = fields.pop("log_id", None)
        started: datetime | None = fields.pop("_started", None)
        if self.log is not None:
            now = datetime.now(UTC)
            fields.update(
                {
                    "action": action,
                    "status": status,
                    "reason": reason,
                    "outcome": outcome,
                }
            )
            if result is not None:
                sent_at = started or now
                if result.latency_s is not None:
                    sent_at = now - timedelta(seconds=result.latency_s)
                fields.update(
                    sent=result.sent or None,
                    ack=result.ack,
                    attempts=result.attempts,
                    sent_at=sent_at if status in ("sent", "failed") else None,
                    acked_at=now if result.confirmed else None,
                )
                if result.latency_s is not None:
                    fields["ack_latency_ms"] = result.latency_s * 1000.0
            if outcome is not None and outcome not in ("refused", "ignored", "failed"):
                fields["completed_at"] = now
            if log_id is None:
                log_id = self.log.add(**fields)
            else:
                self.log.update(log_id, **fields)
        out = ControlOutcome(
            event.drone, event.command, action, status, reason, result, log_id, target
        )
        self._publish(
            CommandResultEvent(
                t=event.t,
                stream=event.stream,
                drone=event.drone,
                command=event.command,
                action=action,
                status=status,
                ack=result.ack if result else "",
                outcome=outcome or "",
                reason=reason,
                gesture_t=event.t,
                latency_s=result.latency_s if result else None,
                log_id=log_id,
            )
        )
        return out

    def _outcome(self, drone: str, item: _Tracked, outcome: str) -> None:
        if self.log is not None and item.log_id is not None:
            self.log.update(item.log_id, outcome=outcome, completed_at=datetime.now(UTC))
        self._publish(
            CommandResultEvent(
                t=item.gesture_t,
                stream=item.stream,
                drone=drone,
                command=item.command,
                action=item.action,
                status="done",
                outcome=outcome,
                gesture_t=item.gesture_t,
                log_id=item.log_id,
            )
        )

    def _publish(self, event: Event) -> None:
        if self.bus is not None:
            self.bus.publish(event)

    def _alarm(self, drone: str, kind: str, message: str) -> None:
        # A drone's alarm is also its stream's (the console shows it on that tile);
        # drone "" is the controller itself.
        self._publish(
            DroneAlarmEvent(t=time.time(), stream=drone, drone=drone, kind=kind, message=message)
        )

    # --- watchdog -----------------------------------------------------------------------
    def _watch(self) -> None:
        while not self._stop.wait(0.05):
            try:
                self._check_links()
                self._check_operator()
                self._check_outcomes()
            except Exception as exc:  # never let the watchdog die silently
                self._alarm("", "controller_error", f"{type(exc).__name__}: {exc}")

    def _check_links(self) -> None:
        for name, link in self.links.items():
            state, was = link.state, self._link_states[name]
            self._link_states[name] = state
            if state == LinkState.LOST and was != LinkState.LOST:
                armed = self.safety.is_armed(name)
                self._set_control(name, False)
                with self._track_lock:
                    item = self._tracked.pop(name, None)
                if item is not None:
                    self._outcome(name, item, "link_lost")
                note = "; gesture control disarmed: have_command again" if armed else ""
                self._alarm(name, "link_lost", f"{name}: link lost, nothing is sent{note}")

    def _check_operator(self) -> None:
        if self._operator_lost_handled or not self.safety.operator_lost():
            return
        self._operator_lost_handled = True
        after = self.safety.cfg.operator_lost_s
        for name, link in self.links.items():
            tel = link.telemetry()
            if not self.safety.is_armed(name) or tel is None or not tel.flying:
                continue
            message = f"operator not seen for {after:.0f} s: {name} hovers"
            self._alarm(name, "operator_lost", message)
            event = CommandEvent(t=time.time(), stream="", command="hover", drone=name)
            threading.Thread(target=self._watchdog_hold, args=(event,), daemon=True).start()

    def _watchdog_hold(self, event: CommandEvent) -> None:
        base = {
            "drone": event.drone,
            "source": "watchdog",
            "command": "operator_lost",
            "stream": "",
            "gesture_t": event.t,
            "confidence": None,
        }
        link = self.links[event.drone]
        with self._locks[event.drone]:
            self._begin(base, "hold")
            if link.state != LinkState.OK:
                self._finish(event, base, "hold", "refused", f"link {link.state}")
                return
            self._sent(event, base, "hold", link.hold(), link, track="hold")

    def _check_outcomes(self) -> None:
        now = time.monotonic()
        done: list[tuple[str, _Tracked, str]] = []
        with self._track_lock:
            for name, item in list(self._tracked.items()):
                tel = self.links[name].telemetry()
                outcome = None
                if tel is not None:
                    if item.action == "land":
                        if tel.landed == "on_ground" and not tel.armed:
                            outcome = "landed"
                    elif item.target is not None:
                        if tel.distance_to(item.target) < self.arrive_tolerance_m:
                            outcome = "reached"
                    else:
                        outcome = "done"
                if outcome is None and now > item.deadline:
                    outcome = "not_landed" if item.action == "land" else "not_reached"
                if outcome is not None:
                    del self._tracked[name]
                    done.append((name, item, outcome))
        for name, item, outcome in done:
            self._outcome(name, item, outcome)

    # --- emergency stop -----------------------------------------------------------------
    def request_emergency_stop(self, drone: str, kind: str = "land") -> EmergencyStopRequest:
        """Step one of two: nothing is sent; confirm with the returned token.

        Raises:
            KeyError: unknown drone.  ValueError: unknown kind.
        """
        if drone not in self.links:
            raise KeyError(f"unknown drone {drone!r}")
        req = self.safety.request_emergency_stop(drone, kind)
        event = CommandEvent(t=time.time(), stream="", command="emergency_stop", drone=drone)
        base = {
            "drone": drone,
            "source": "api",
            "command": "emergency_stop",
            "stream": "",
            "gesture_t": None,
            "confidence": None,
        }
        self._finish(
            event,
            base,
            f"request_{kind}",
            "pending",
            f"awaiting confirmation within {req.confirm_within_s:.0f} s",
            outcome="awaiting_confirmation",
        )
        return req

    def confirm_emergency_stop(self, token: str, drone: str | None = None) -> ControlOutcome:
        """Step two: land (or kill the motors of) the drone the token was issued for.
        Gesture control of that drone is disarmed first.

        Raises:
            EmergencyStopError: unknown, used or expired token, or a token issued for
                another drone than `drone` (nothing is sent).
        """
        req = self.safety.confirm_emergency_stop(token, drone)
        drone = req.drone
        self._set_control(drone, False)
        link = self.links[drone]
        self._alarm(drone, "emergency_stop", f"emergency stop ({req.kind}) confirmed")
        event = CommandEvent(t=time.time(), stream="", command="emergency_stop", drone=drone)
        base = {
            "drone": drone,
            "source": "api",
            "command": "emergency_stop",
            "stream": "",
            "gesture_t": None,
            "confidence": None,
        }
        self._begin(base, req.kind)
        result = link.land() if req.kind == "land" else link.disarm(force=True)
        track = "land" if req.kind == "land" else None
        return self._sent(event, base, req.kind, result, link, track=track)


class EmergencyStopService:
    """The console's two-step emergency stop (`proxima.api.interfaces.EmergencyStop`)
    on top of a controller: `request` sends nothing, `confirm` lands the drone."""

    def __init__(self, controller: DroneController, kind: str = "land") -> None:
        self.controller = controller
        self.kind = kind

    def request(self, drone: str, user: str) -> dict[str, Any]:
        """Raises: KeyError: unknown drone."""
        req = self.controller.request_emergency_stop(drone, self.kind)
        return {
            "confirmation_id": req.token,
            "expires_in_s": req.confirm_within_s,
            "kind": req.kind,
            "requested_by": user,
        }

    def confirm(self, drone: str, confirmation_id: str, user: str) -> dict[str, Any]:
        """Raises: KeyError: unknown drone.  PermissionError: bad, used or late id."""
        if drone not in self.controller.links:
            raise KeyError(drone)
        out = self.controller.confirm_emergency_stop(confirmation_id, drone=drone)
        detail = out.reason or (out.result.ack if out.result else out.status)
        return {
            "ok": out.status == "sent",
            "detail": detail,
            "log_id": out.log_id,
            "confirmed_by": user,
        }
