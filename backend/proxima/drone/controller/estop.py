"""The two-step emergency stop: `request` sends nothing and returns a one-time token;
`confirm(token)` within `estop_confirm_s` disarms gesture control and lands the drone
(or, kind "kill", stops its motors: the drone falls; only for a runaway). The token
rules are `SafetyGate`'s; this module turns a confirmed stop into vehicle commands, and
`EmergencyStopService` offers it to the console.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from proxima.drone.controller.execute import CommandExecutor
from proxima.drone.controller.record import CommandContext, CommandRecorder, ControlOutcome
from proxima.drone.events import DroneAlarmEvent
from proxima.drone.link import DroneLink
from proxima.drone.safety import EmergencyStopRequest, SafetyGate
from proxima.events import CommandEvent

if TYPE_CHECKING:
    from proxima.drone.controller.dispatch import DroneController

COMMAND = "emergency_stop"


class EmergencyStops:
    """Emergency stops of the drones on `links`."""

    def __init__(
        self,
        links: Mapping[str, DroneLink],
        safety: SafetyGate,
        executor: CommandExecutor,
        recorder: CommandRecorder,
    ) -> None:
        self.links = links
        self.safety = safety
        self.executor = executor
        self.recorder = recorder

    def request(self, drone: str, kind: str = "land") -> EmergencyStopRequest:
        """Step one of two: nothing is sent; confirm with the returned token.

        Raises:
            KeyError: unknown drone.  ValueError: unknown kind.
        """
        if drone not in self.links:
            raise KeyError(f"unknown drone {drone!r}")
        req = self.safety.request_emergency_stop(drone, kind)
        event = CommandEvent(t=time.time(), stream="", command=COMMAND, drone=drone)
        self.recorder.finish(
            event,
            CommandContext(drone, "api", COMMAND),
            f"request_{kind}",
            "pending",
            f"awaiting confirmation within {req.confirm_within_s:.0f} s",
            outcome="awaiting_confirmation",
        )
        return req

    def confirm(self, token: str, drone: str | None = None) -> ControlOutcome:
        """Step two: land (or kill the motors of) the drone the token was issued for.
        Gesture control of that drone is disarmed first.

        Raises:
            EmergencyStopError: unknown, used or expired token, or a token issued for
                another drone than `drone` (nothing is sent).
        """
        req = self.safety.confirm_emergency_stop(token, drone)
        drone = req.drone
        self.safety.mark_stopped(drone)
        self.executor.set_control(drone, False)
        link = self.links[drone]
        link.emergency_stopped = True
        self.recorder.alarm(drone, "emergency_stop", f"emergency stop ({req.kind}) confirmed")
        event = CommandEvent(t=time.time(), stream="", command=COMMAND, drone=drone)
        ctx = CommandContext(drone, "api", COMMAND)
        self.recorder.begin(ctx, req.kind)
        result = link.land() if req.kind == "land" else link.disarm(force=True)
        track = "land" if req.kind == "land" else None
        return self.executor.sent(event, ctx, req.kind, result, link, track=track)

    def resume(self, drone: str) -> ControlOutcome:
        """A supervisor clears the stop: gesture control may be armed again (by the next
        have_command); nothing is sent to the vehicle (take off with its own controls).

        Raises:
            KeyError: unknown drone.  ValueError: the drone is not stopped.
        """
        link = self.links[drone]
        if not self.safety.clear_stop(drone):
            raise ValueError(f"{drone} is not emergency-stopped")
        link.emergency_stopped = False
        self.recorder.publish(
            DroneAlarmEvent(
                t=time.time(), stream=drone, drone=drone, kind="emergency_stop",
                message=f"{drone}: resumed by a supervisor", active=False,
            )
        )  # fmt: skip
        event = CommandEvent(t=time.time(), stream="", command="resume", drone=drone)
        return self.recorder.finish(
            event,
            CommandContext(drone, "api", "resume"),
            "resume",
            "done",
            "resumed: have_command arms gesture control again",
            outcome="resumed",
        )

    def stopped(self) -> list[str]:
        return sorted(d for d in self.links if self.safety.is_stopped(d))


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

    def resume(self, drone: str, user: str) -> dict[str, Any]:
        """Raises: KeyError: unknown drone.  ValueError: not stopped."""
        out = self.controller.estops.resume(drone)
        return {"ok": True, "detail": out.reason, "log_id": out.log_id, "resumed_by": user}

    def stopped(self) -> list[str]:
        """The drones emergency-stopped and not resumed yet."""
        return self.controller.estops.stopped()
