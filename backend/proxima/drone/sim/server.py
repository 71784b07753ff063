"""The simulated vehicle's MAVLink side: UDP the way ArduCopter SITL speaks it.

It sends MAVLink 2 to a ground station at HOST:PORT (so the station listens with
`udpin:127.0.0.1:PORT`) and to every address it hears from, decodes what arrives and
hands each message to the service that owns it: the vehicle's commands (`handlers`),
telemetry and message requests (`telemetry`), parameters (`params`), missions
(`mission`), MAVLink FTP (`ftp`). Every command gets a COMMAND_ACK (UNSUPPORTED for one
nobody handles). `run(stop)` owns the socket and the clock: it steps the physics at
`physics_hz`, streams the telemetry and lets each service do its timed work.

Nothing that arrives is trusted: a datagram that does not parse is dropped whole (and
the parser starts afresh), a message for another system or component is ignored, and a
handler that raises is counted in `handler_errors` and logged to stderr rather than
stopping the vehicle (the fuzz test requires that count to stay 0).
"""

from __future__ import annotations

import contextlib
import random
import select
import socket
import sys
import threading
import time
import traceback
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from proxima.drone.mavlink.fields import degrees_e7
from proxima.drone.mavlink.protocol import mav
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.ftp import FtpService
from proxima.drone.sim.handlers import (
    Command,
    global_position_target,
    set_mode_message,
    vehicle_command,
)
from proxima.drone.sim.mission import MissionService
from proxima.drone.sim.params import ParamService
from proxima.drone.sim.telemetry import TelemetryStreams
from proxima.drone.sim.vehicle import Vehicle

PEER_TIMEOUT_S = 10.0  # stop sending to an address not heard from for this long
AUTOPILOT_COMPONENTS = (0, mav.MAV_COMP_ID_AUTOPILOT1)  # target_component we answer to

MessageHandler = Callable[[Any], None]


class Service(Protocol):
    """A part of the vehicle's MAVLink side: the messages it handles and its timed work."""

    @property
    def messages(self) -> Mapping[str, MessageHandler]: ...

    def tick(self, now: float) -> None: ...


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
        self.parser = self._new_parser()
        self.telemetry = TelemetryStreams(self.vehicle, self.mav, config.rate_hz, config.physics_hz)
        self.services: list[Service] = [
            self.telemetry,
            ParamService(self.vehicle.params, self.mav, self._statustext),
            MissionService(self.vehicle, self.mav, time.monotonic),
            FtpService(self.mav, config.sysid),
        ]
        self.packets_in = 0
        self.packets_dropped = 0
        self.bad_datagrams = 0  # did not parse as MAVLink
        self.handler_errors = 0  # a handler raised: a bug, logged to stderr
        self.handled: Counter[str] = Counter()  # messages given to a handler, by type
        self.messages: dict[str, MessageHandler] = {
            "HEARTBEAT": self._heartbeat,
            "COMMAND_LONG": self._command_long,
            "COMMAND_INT": self._command_int,
            "SET_MODE": self._set_mode,
            "SET_POSITION_TARGET_LOCAL_NED": self._position_target,
            "SET_POSITION_TARGET_GLOBAL_INT": self._global_target,
        }
        for service in self.services:
            self.messages.update(service.messages)
        self.commands: dict[int, Callable[[Command], int]] = dict(self.telemetry.commands)

    def _new_parser(self) -> Any:
        parser = mav.MAVLink(None, srcSystem=self.cfg.sysid, srcComponent=1)
        parser.robust_parsing = True  # bad bytes become BAD_DATA, not exceptions
        return parser

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
            for msg in self._parse(data):
                self._handle(msg)

    def _parse(self, data: bytes) -> list[Any]:
        """The messages of one datagram. A datagram is whole or nothing: bytes left over
        (a truncated packet) would otherwise swallow the start of the next datagram, so
        the parser starts afresh after a broken one."""
        try:
            msgs = self.parser.parse_buffer(data) or []
        except Exception:  # pymavlink raises more than MAVError on hostile bytes
            msgs = None
        good = [m for m in msgs or () if m.get_type() != "BAD_DATA"]
        if msgs is None or len(good) < len(msgs) or self.parser.buf_len():
            self.bad_datagrams += 1
            self.parser = self._new_parser()
        return good

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
                    for service in self.services:
                        self._guarded(service.tick, now)
                    next_tick += dt
                    if now - next_tick > 1.0:  # we were suspended: do not replay the past
                        next_tick = now + dt
        finally:
            self.sock.close()

    def _statustext(self, text: str, severity: int) -> None:
        self.mav.statustext_send(severity, text[:50].encode())

    # --- incoming messages -----------------------------------------------------------
    def _handle(self, msg: Any) -> None:
        if getattr(msg, "target_system", 0) not in (0, self.cfg.sysid):
            return
        if getattr(msg, "target_component", 0) not in AUTOPILOT_COMPONENTS:
            return  # for a camera, a gimbal, ... of this system: not ours
        handler = self.messages.get(msg.get_type())
        if handler is not None:
            self.handled[msg.get_type()] += 1
            self._guarded(handler, msg)

    def _guarded(self, fn: Callable[[Any], None], arg: Any) -> None:
        try:
            fn(arg)
        except Exception:  # a bug: keep flying, count it, say where
            self.handler_errors += 1
            print(f"sim-drone: handler error\n{traceback.format_exc()}", file=sys.stderr)

    def _heartbeat(self, msg: Any) -> None:
        if msg.type == mav.MAV_TYPE_GCS:
            self.vehicle.gcs_heard()

    def _command_long(self, msg: Any) -> None:
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6]
        self._command(Command.of(msg.command, [*params, msg.param7]), msg)

    def _command_int(self, msg: Any) -> None:
        params = [msg.param1, msg.param2, msg.param3, msg.param4]
        params += [degrees_e7(msg.x), degrees_e7(msg.y), msg.z]
        self._command(Command.of(msg.command, params, msg.frame), msg)

    def _command(self, command: Command, msg: Any) -> None:
        handler = self.commands.get(command.id)
        if handler is not None:
            result: int | None = handler(command)
        else:
            result = vehicle_command(self.vehicle, command)
        self._ack(command.id, mav.MAV_RESULT_UNSUPPORTED if result is None else result, msg)
        self.telemetry.send_requested()

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

    def _global_target(self, msg: Any) -> None:
        global_position_target(
            self.vehicle,
            msg.coordinate_frame,
            msg.type_mask,
            (msg.lat_int, msg.lon_int),
            msg.alt,
            (msg.vx, msg.vy, msg.vz),
            msg.yaw,
        )

    def _ack(self, command: int, result: int, msg: Any) -> None:
        self.mav.command_ack_send(
            command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
