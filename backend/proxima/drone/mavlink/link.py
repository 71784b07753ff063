"""`MavlinkLink`: a DroneLink over MAVLink 2 with pymavlink, to ArduPilot and PX4 vehicles,
SITL or real.

The commands are `actions.MavlinkActions`'; this class gives them the transport (one
owner thread, `transport.MavlinkTransport`), the telemetry decoded from the vehicle's
messages (`telemetry.TelemetryStore`) and publishes the link's state and alarms on the
event bus.
"""

from __future__ import annotations

import time
from collections import Counter
from concurrent.futures import Future
from typing import Any

from proxima.drone.events import DroneAlarmEvent, DroneStateEvent
from proxima.drone.link import CommandResult, LinkError, Telemetry
from proxima.drone.mavlink.acks import PendingCommand
from proxima.drone.mavlink.actions import MavlinkActions
from proxima.drone.mavlink.autopilot import Autopilot
from proxima.drone.mavlink.config import LinkConfig
from proxima.drone.mavlink.protocol import mav
from proxima.drone.mavlink.setpoint import Setpoint
from proxima.drone.mavlink.telemetry import TelemetryStore
from proxima.drone.mavlink.transport import MavlinkTransport
from proxima.events import EventBus
from proxima.types import LinkState


class MavlinkLink(MavlinkActions):
    """A vehicle over pymavlink. Construct, `connect()`, command, `close()`.

    `connection` is a pymavlink connection string (see `transport`)."""

    def __init__(
        self,
        connection: str,
        name: str = "",
        *,
        config: LinkConfig | None = None,
        bus: EventBus | None = None,
    ) -> None:
        super().__init__(config)
        self.connection = connection
        self.name = name or connection
        self.bus = bus
        self._store = TelemetryStore()
        self._io = MavlinkTransport(
            connection,
            self.name,
            self.cfg,
            self._store,
            on_state_change=self._on_state_change,
            publish_state=self._publish_state,
        )

    # --- life cycle -------------------------------------------------------------------
    def connect(self, timeout: float = 10.0) -> None:
        self._io.start()
        if not self._io.first_heartbeat.wait(timeout):
            error = self._io.open_error
            why = f" ({error})" if error else ""
            raise LinkError(
                f"{self.name}: no heartbeat from a vehicle on {self.connection} "
                f"within {timeout:.0f} s{why}"
            )

    def close(self) -> None:
        self._io.close()

    @property
    def state(self) -> LinkState:
        return self._io.state

    def telemetry(self) -> Telemetry | None:
        return self._store.snapshot()

    @property
    def sent_counts(self) -> Counter[str]:
        """Messages sent by type, heartbeats not counted."""
        return self._io.sent_counts

    @property
    def running(self) -> bool:
        """Whether the link's owner thread is running (from `connect()` to `close()`)."""
        return self._io.running

    @property
    def faults(self) -> Counter[str]:
        """What arrived unusable: BAD_DATA, decode_error (logged), reopened."""
        return self._io.faults

    def sent_count(self) -> int:
        """How many messages other than heartbeats this link has sent."""
        return sum(self._io.sent_counts.values())

    def set_message_interval(self, msg_id: int, rate_hz: float) -> CommandResult:
        """Ask for a message at `rate_hz` (0 stops it)."""
        interval = 1e6 / rate_hz if rate_hz > 0 else -1
        return self.command_long(
            "message_interval", mav.MAV_CMD_SET_MESSAGE_INTERVAL, [msg_id, interval]
        )

    # --- the transport primitives -------------------------------------------------------
    def _policy(self) -> Autopilot:
        return self._store.autopilot

    def _vehicle_type(self) -> int:
        return self._store.vehicle_type

    def _closed(self) -> bool:
        return self._io.closed

    def _has_vehicle(self) -> bool:
        return self._io.target is not None

    def _command(
        self,
        action: str,
        command: int,
        params: list[float],
        sent: dict,
        timeout: float,
        retries: int,
    ) -> CommandResult:
        future: Future[CommandResult] = Future()
        pending = PendingCommand(action, command, params, future, timeout, retries)
        self._io.command(pending)
        limit = timeout * (retries + 1) + self.cfg.in_progress_timeout_s + 2.0
        try:
            return future.result(timeout=limit)
        except TimeoutError:
            return CommandResult(
                action,
                "timeout",
                False,
                pending.attempts,
                sent=sent,
                detail="link thread did not answer",
            )

    def _set_stream(self, setpoint: Setpoint | None) -> None:
        self._io.set_stream(setpoint)

    def _streaming(self) -> bool:
        return self._io.setpoint is not None

    def _send_once(self, setpoint: Setpoint) -> None:
        self._io.send_once(setpoint)

    def _echo(self) -> tuple[float, tuple[float, float, float] | None]:
        return self._store.echo()

    def _acknowledged(self, **fields: Any) -> None:
        self._store.update(**fields)

    # --- events (called from the owner thread) ---------------------------------------------
    def _on_state_change(self, was: LinkState, now: LinkState) -> None:
        if now == LinkState.LOST:
            lost = self.cfg.lost_after_s
            self._alarm(
                "link_lost", f"{self.name}: no heartbeat for {lost:.0f} s; commands stopped"
            )
        elif was == LinkState.LOST:
            self._alarm("link_lost", f"{self.name}: link back", active=False)
        self._publish_state()

    def _publish_state(self) -> None:
        if self.bus is None:
            return
        tel = self.telemetry()
        now, link = time.time(), str(self.state)
        if tel is None:
            self.bus.publish(
                DroneStateEvent(
                    t=now,
                    stream=self.name,
                    drone=self.name,
                    link=link,
                    gesture_control=self.gesture_control,
                    stopped=self.emergency_stopped,
                )
            )
            return
        self.bus.publish(
            DroneStateEvent(
                t=now,
                stream=self.name,
                drone=self.name,
                link=link,
                gesture_control=self.gesture_control,
                stopped=self.emergency_stopped,
                autopilot=tel.autopilot,
                mode=tel.mode,
                armed=tel.armed,
                landed=tel.landed,
                position=_rounded(tel.position),
                velocity=_rounded(tel.velocity),
                attitude=_rounded(tel.attitude),
                battery_pct=tel.battery_pct,
                battery_voltage=tel.battery_voltage,
                global_position=list(tel.global_position) if tel.global_position else None,
                position_target=_rounded(tel.position_target),
                heard_age_s=round(max(time.monotonic() - tel.received, 0.0), 3),
            )
        )

    def _alarm(self, kind: str, message: str, active: bool = True) -> None:
        if self.bus is not None:
            self.bus.publish(
                DroneAlarmEvent(
                    t=time.time(),
                    stream=self.name,
                    drone=self.name,
                    kind=kind,
                    message=message,
                    active=active,
                )
            )


def _rounded(v: tuple[float, ...] | None) -> list[float] | None:
    return None if v is None else [round(float(x), 4) for x in v]
