"""The simulated vehicle's MAVLink side: UDP the way ArduCopter SITL speaks it.

It sends MAVLink 2 to a ground station at HOST:PORT (so the station listens with
`udpin:127.0.0.1:PORT`) and to every address it hears from, decodes what arrives
(COMMAND_LONG, COMMAND_INT, SET_MODE, SET_POSITION_TARGET_LOCAL_NED) into calls on the
`Vehicle` and answers every command with a COMMAND_ACK. `run(stop)` owns the socket and
the clock: it steps the physics at `physics_hz` and streams the telemetry.
"""

from __future__ import annotations

import contextlib
import random
import select
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from proxima.drone.mavlink.protocol import mav
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.handlers import set_mode_message, vehicle_command
from proxima.drone.sim.telemetry import TelemetryStreams
from proxima.drone.sim.vehicle import Vehicle

PEER_TIMEOUT_S = 10.0  # stop sending to an address not heard from for this long


@dataclass
class _Peer:
    addr: tuple[str, int]
    last_heard: float = field(default_factory=time.monotonic)


class VehicleServer:
    """One simulated quadcopter on a UDP socket. `run(stop)` owns the socket and the
    clock until `stop` is set; everything else is called from that loop only."""

    def __init__(self, config: SimConfig) -> None:
        self.vehicle = Vehicle(config, on_text=self._statustext)  # checks the autopilot
        if not 1 <= config.sysid <= 255:
            raise ValueError(f"sysid must be 1..255, got {config.sysid}")
        self.cfg = config
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((config.host, 0))
        self.sock.setblocking(False)
        self.out_addr = (config.host, config.port)
        self.extra_addrs = [(config.host, p) for p in config.out_ports]
        self.peers: dict[tuple[str, int], _Peer] = {}
        self.rng = random.Random(config.seed)
        self.mav = mav.MAVLink(self, srcSystem=config.sysid, srcComponent=1)
        self.telemetry = TelemetryStreams(self.vehicle, self.mav, config.rate_hz, config.physics_hz)
        self.packets_in = 0
        self.packets_dropped = 0
        self._messages: dict[str, Callable[[Any], None]] = {
            "COMMAND_LONG": self._command_long,
            "COMMAND_INT": self._command_int,
            "SET_MODE": self._set_mode,
            "SET_POSITION_TARGET_LOCAL_NED": self._position_target,
        }

    # --- transport -------------------------------------------------------------------
    def write(self, buf: bytes) -> None:
        """Called by pymavlink's encoder: send one packet to the station and every peer."""
        now = time.monotonic()
        targets = {self.out_addr, *self.extra_addrs}
        targets |= {a for a, p in self.peers.items() if now - p.last_heard < PEER_TIMEOUT_S}
        for addr in targets:
            # nobody listening yet (ICMP port unreachable): like SITL, keep going
            with contextlib.suppress(OSError):
                self.sock.sendto(buf, addr)

    def _receive(self) -> None:
        while True:
            try:
                data, addr = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return  # a previous send hit a closed port; nothing to read
            self.packets_in += 1
            if self.cfg.loss > 0 and self.rng.random() < self.cfg.loss:
                self.packets_dropped += 1
                continue
            peer = self.peers.get(addr)
            if peer is None:
                self.peers[addr] = _Peer(addr)
            else:
                peer.last_heard = time.monotonic()
            try:
                msgs = self.mav.parse_buffer(data) or []
            except mav.MAVError:
                continue
            for msg in msgs:
                self._handle(msg)

    def run(self, stop: threading.Event) -> None:
        """Fly until `stop` is set: receive, step physics at `physics_hz`, stream."""
        dt = 1.0 / self.cfg.physics_hz
        next_tick = time.monotonic()
        try:
            while not stop.is_set():
                wait = max(0.0, next_tick - time.monotonic())
                ready, _, _ = select.select([self.sock], [], [], wait)
                if ready:
                    self._receive()
                now = time.monotonic()
                if now >= next_tick:
                    self.vehicle.step(dt)
                    self.telemetry.stream(now)
                    next_tick += dt
                    if now - next_tick > 1.0:  # we were suspended: do not replay the past
                        next_tick = now + dt
        finally:
            self.sock.close()

    def _statustext(self, text: str, severity: int) -> None:
        self.mav.statustext_send(severity, text[:50].encode())

    # --- incoming messages -----------------------------------------------------------
    def _handle(self, msg: Any) -> None:
        target = getattr(msg, "target_system", None)
        if target not in (None, 0, self.cfg.sysid):
            return
        handler = self._messages.get(msg.get_type())
        if handler is not None:
            handler(msg)

    def _command_long(self, msg: Any) -> None:
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6]
        self._command(msg.command, [*params, msg.param7], msg)

    def _command_int(self, msg: Any) -> None:
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.x / 1e7, msg.y / 1e7]
        self._command(msg.command, [*params, msg.z], msg)

    def _command(self, command: int, params: list[float], msg: Any) -> None:
        if self.telemetry.handles(command):
            result: int | None = self.telemetry.command(command, params)
        else:
            result = vehicle_command(self.vehicle, command, params)
        self._ack(command, mav.MAV_RESULT_UNSUPPORTED if result is None else result, msg)

    def _set_mode(self, msg: Any) -> None:
        result = set_mode_message(self.vehicle, msg.base_mode, msg.custom_mode)
        self._ack(mav.MAVLINK_MSG_ID_SET_MODE, result, msg)

    def _position_target(self, msg: Any) -> None:
        self.vehicle.position_target(
            msg.coordinate_frame,
            msg.type_mask,
            (msg.x, msg.y, msg.z),
            (msg.vx, msg.vy, msg.vz),
            msg.yaw,
        )

    def _ack(self, command: int, result: int, msg: Any) -> None:
        self.mav.command_ack_send(
            command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
