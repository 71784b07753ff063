"""From a decided command to vehicle actions, under the safety rules.

`CommandExecutor.handle` maps the gesture (`mapping`), checks gesture control, the
link, the rate limit, the vehicle's mode and, for a move, the step and the geofence
(`safety`); only then does it call the drone's link, and it records every step
(`record`) and hands what was sent to the outcome tracker (`outcomes`). Commands to one
drone run one at a time (a lock per drone); different drones never wait for each other.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping

from proxima.drone.controller.outcomes import OutcomeTracker
from proxima.drone.controller.record import CommandContext, CommandRecorder, ControlOutcome
from proxima.drone.heading import HeadingPolicy
from proxima.drone.link import CommandResult, DroneLink, Telemetry
from proxima.drone.mapping import CommandMapping, MappedAction, MappingError
from proxima.drone.safety import SafetyGate
from proxima.events import CommandEvent
from proxima.types import LinkState

# Link answers that mean the command never left (the link refused it itself).
_NOTHING_SENT = frozenset(
    {"link_lost", "not_connected", "wrong_mode", "no_position", "unknown_mode"}
)


class CommandExecutor:
    """Executes commands for the drones on `links` (see the module)."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        mapping: CommandMapping,
        safety: SafetyGate,
        recorder: CommandRecorder,
        tracker: OutcomeTracker,
        speeds: dict[str, float],
        heading: HeadingPolicy | None = None,
    ) -> None:
        self.links = links
        self.heading = heading or HeadingPolicy()
        self.mapping = mapping
        self.safety = safety
        self.recorder = recorder
        self.tracker = tracker
        self.speeds = speeds  # each drone's commanded horizontal speed
        self.locks = {name: threading.Lock() for name in links}

    # --- gesture control ------------------------------------------------------------------
    def set_control(self, drone: str, armed: bool) -> None:
        """Arm or disarm gesture control of `drone` (never its motors)."""
        if armed:
            armed = self.safety.arm_control(drone)  # refused for a stopped drone
        else:
            self.safety.disarm_control(drone)
        link = self.links.get(drone)
        if link is not None:
            link.gesture_control = armed

    # --- the command path ---------------------------------------------------------------
    def handle(self, event: CommandEvent, ctx: CommandContext) -> ControlOutcome:
        """Map, check, send, log one command; blocks until the vehicle answered."""
        try:
            mapped = self.mapping.lookup(event.command)
        except MappingError as exc:
            return self.recorder.finish(event, ctx, "", "refused", str(exc))
        link = self.links.get(event.drone)
        if link is None:
            reason = f"unknown drone {event.drone!r}"
            return self.recorder.finish(event, ctx, mapped.action, "refused", reason)
        with self.locks[event.drone]:
            self.recorder.begin(ctx, mapped.action)
            return self._execute(event, ctx, mapped, link)

    def _execute(
        self, event: CommandEvent, ctx: CommandContext, mapped: MappedAction, link: DroneLink
    ) -> ControlOutcome:
        drone, action, finish = event.drone, mapped.action, self.recorder.finish
        if action == "arm_control" and self.safety.is_stopped(drone):
            reason = "emergency-stopped: a supervisor must resume it before have_command"
            return finish(event, ctx, action, "refused", reason)
        if action == "arm_control":
            self.set_control(drone, True)
            return finish(
                event, ctx, action, "done", "gesture control armed", outcome="control_armed"
            )
        if not self.safety.is_armed(drone):
            reason = "gesture control not armed (have_command first): nothing sent"
            return finish(event, ctx, action, "refused", reason)
        if action == "none":
            return finish(event, ctx, action, "ignored", "mapped to no action")
        if action == "abort":  # disarm first: whatever happens to the hold, control is off
            self.set_control(drone, False)
        if link.state != LinkState.OK:
            return finish(event, ctx, action, "refused", f"link {link.state}: nothing sent")
        tel = link.telemetry()
        if tel is None:
            return finish(event, ctx, action, "refused", "no telemetry yet")
        verdict = self.safety.check_rate(drone, action)
        if not verdict.ok:
            return finish(event, ctx, action, "refused", verdict.reason)
        if action in ("hold", "abort"):
            if not tel.flying:
                reason = "on the ground: nothing to hold"
                outcome = "control_disarmed" if action == "abort" else None
                return finish(event, ctx, action, "ignored", reason, outcome=outcome)
            return self.sent(event, ctx, action, link.hold(), link, track="hold")
        if action == "land":
            if not tel.flying:
                return finish(event, ctx, action, "ignored", "already on the ground")
            return self.sent(event, ctx, action, link.land(), link, track="land")
        if action in ("change_speed", "resume_speed"):
            if action == "change_speed":
                factor = mapped.factor or 0.5
                speed = max(self.mapping.min_speed_m_s, self.speeds[drone] * factor)
            else:
                speed = self.mapping.cruise_speed_m_s
            result = link.change_speed(speed)
            if result.ok:
                self.speeds[drone] = speed
            return self.sent(event, ctx, action, result, link)
        if action == "move":
            return self._move(event, ctx, mapped, link, tel)
        return finish(event, ctx, action, "refused", f"unhandled action {action!r}")

    def _move(
        self,
        event: CommandEvent,
        ctx: CommandContext,
        mapped: MappedAction,
        link: DroneLink,
        tel: Telemetry,
    ) -> ControlOutcome:
        action, finish = mapped.action, self.recorder.finish
        if not tel.flying or tel.position is None:
            why = "not flying" if tel.position is not None else "no local position"
            return finish(event, ctx, action, "refused", f"{why}: nothing sent")
        if tel.mode not in link.holding_modes():
            reason = f"vehicle in {tel.mode}: gestures do not override it"
            return finish(event, ctx, action, "refused", reason)
        # The mapping's step is in the body frame [forward, right, down]: rotate it by
        # the vehicle's yaw into local NED.
        step_len = mapped.step_m or self.mapping.step_m
        f, r, d = (c * step_len for c in mapped.direction or (0.0, 0.0, 0.0))
        yaw = tel.yaw
        step = (f * math.cos(yaw) - r * math.sin(yaw), f * math.sin(yaw) + r * math.cos(yaw), d)
        guided = link.guided_mode()
        origin = tel.position
        settling = tel.position_target
        if tel.mode == guided and settling is not None and tel.distance_to(settling) < 0.5:
            origin = settling  # step from where the vehicle is settling, not from noise
        target = (origin[0] + step[0], origin[1] + step[1], origin[2] + step[2])
        verdict = self.safety.check_move(step, target)
        if not verdict.ok:
            return finish(event, ctx, action, "refused", verdict.reason, target=target)
        if tel.mode != guided:
            result = link.enter_guided()
            if not result.ok:
                return self.sent(event, ctx, action, result, link, target=target)
        # The heading flown with the target (None: the autopilot's own; `sent` records it).
        heading = self.heading.yaw_for(event.drone, tel, target)
        result = link.goto_local(*target, yaw=heading)
        return self.sent(event, ctx, action, result, link, track="move", target=target)

    def sent(
        self,
        event: CommandEvent,
        ctx: CommandContext,
        action: str,
        result: CommandResult,
        link: DroneLink,
        *,
        track: str | None = None,
        target: tuple[float, float, float] | None = None,
    ) -> ControlOutcome:
        """Record what the link answered; track the outcome of what the vehicle took."""
        if result.ack in _NOTHING_SENT:
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
        out = self.recorder.finish(
            event, ctx, action, status, reason, result=result, outcome=outcome, target=target
        )
        if status == "sent" and track is not None:
            self.tracker.track(event, out, track, target, link)
        return out

    def hold(self, event: CommandEvent, ctx: CommandContext) -> ControlOutcome:
        """A hold the controller itself decided (the operator watchdog): no mapping, no
        gesture-control check, never rate-limited."""
        link = self.links[event.drone]
        with self.locks[event.drone]:
            self.recorder.begin(ctx, "hold")
            if link.state != LinkState.OK:
                reason = f"link {link.state}"
                return self.recorder.finish(event, ctx, "hold", "refused", reason)
            return self.sent(event, ctx, "hold", link.hold(), link, track="hold")
