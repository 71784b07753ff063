"""A plain pymavlink ground station for the protocol tests, sharing no code with
Proxima's link: it sends what a test says and waits for what the vehicle answers."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from pymavlink import mavutil


class Gcs:
    """A station listening where the simulator sends (`udpin:127.0.0.1:PORT`)."""

    def __init__(self, port: int, sysid: int = 1, source_system: int = 250) -> None:
        self.conn = mavutil.mavlink_connection(
            f"udpin:127.0.0.1:{port}", source_system=source_system, source_component=190
        )
        self.sysid = sysid
        self.m = mavutil.mavlink
        hb = self.conn.wait_heartbeat(timeout=15)
        assert hb is not None, "no heartbeat from the simulator"
        # Let the vehicle hear us (it answers every address it hears from).
        self.conn.mav.heartbeat_send(
            self.m.MAV_TYPE_GCS, self.m.MAV_AUTOPILOT_INVALID, 0, 0, self.m.MAV_STATE_ACTIVE
        )

    def close(self) -> None:
        self.conn.close()

    def wait(
        self,
        kind: str | list[str],
        predicate: Callable[[Any], bool] = lambda _: True,
        timeout: float = 3.0,
    ) -> Any:
        """The next message of `kind` matching `predicate`.

        Raises:
            AssertionError: none within `timeout` seconds.
        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.conn.recv_match(type=kind, blocking=True, timeout=0.1)
            if msg is not None and predicate(msg):
                return msg
        raise AssertionError(f"no {kind} matching within {timeout} s")

    def collect(self, kind: str, seconds: float) -> list[Any]:
        """Every message of `kind` for `seconds`."""
        out, deadline = [], time.monotonic() + seconds
        while time.monotonic() < deadline:
            msg = self.conn.recv_match(type=kind, blocking=True, timeout=0.05)
            if msg is not None:
                out.append(msg)
        return out

    def command(self, command: int, *params: float, component: int = 1) -> int:
        """COMMAND_LONG (missing params 0); its COMMAND_ACK result."""
        p = [*params, *([0.0] * (7 - len(params)))]
        self.conn.mav.command_long_send(self.sysid, component, command, 0, *p)
        return self.wait("COMMAND_ACK", lambda a: a.command == command).result

    def command_int(
        self, command: int, frame: int, *params: float, x: int, y: int, z: float
    ) -> int:
        """COMMAND_INT with params 1-4; its COMMAND_ACK result."""
        p = [*params, *([0.0] * (4 - len(params)))]
        self.conn.mav.command_int_send(self.sysid, 1, frame, command, 0, 0, *p, x, y, z)
        return self.wait("COMMAND_ACK", lambda a: a.command == command).result
