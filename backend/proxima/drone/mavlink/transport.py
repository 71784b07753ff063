"""The one thread that owns a pymavlink connection.

It opens (and after an error reopens) the connection, reads every message, follows the
first vehicle it hears, sends the GCS heartbeat, watches the vehicle's heartbeat
(CONNECTING -> OK -> LOST after `lost_after_s` of silence -> OK when it returns), sends
queued commands and retries them until their COMMAND_ACK (`acks.CommandBook`), and
streams the active position target when the autopilot needs a stream. Other threads
hand it work with `submit` and block on futures, so pymavlink is only ever touched by
this thread.

Connection strings are pymavlink's: `udpin:127.0.0.1:14550` (listen, what SITL sends
to), `udpout:HOST:PORT`, `tcp:HOST:PORT` (ArduPilot SITL serves tcp:127.0.0.1:5760), or a
serial device `/dev/ttyUSB0,57600`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import select
import threading
import time
import traceback
from collections import Counter
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from proxima.drone.link import CommandResult
from proxima.drone.mavlink.acks import CommandBook, PendingCommand
from proxima.drone.mavlink.config import LinkConfig
from proxima.drone.mavlink.protocol import NOT_VEHICLES, STREAMED, mav, mavutil
from proxima.drone.mavlink.setpoint import Setpoint
from proxima.drone.mavlink.telemetry import TelemetryStore
from proxima.types import LinkState

log = logging.getLogger(__name__)

Op = Callable[[Any], None]  # work for the owner thread, given the open connection


class MavlinkTransport:
    """A connection, its owner thread and what that thread keeps (see the module).

    `on_state_change(was, now)` and `publish_state()` are called from the owner thread:
    on every link-state change, and at `state_event_hz` while OK (1 Hz otherwise)."""

    def __init__(
        self,
        connection: str,
        name: str,
        config: LinkConfig,
        store: TelemetryStore,
        *,
        on_state_change: Callable[[LinkState, LinkState], None],
        publish_state: Callable[[], None],
    ) -> None:
        self.connection = connection
        self.name = name
        self.cfg = config
        self.store = store
        self._on_state_change = on_state_change
        self._publish_state = publish_state
        self.state = LinkState.CONNECTING
        self.first_heartbeat = threading.Event()
        self.open_error = ""
        self.target: tuple[int, int] | None = None  # the vehicle: (system, component)
        self.sent_counts: Counter[str] = Counter()  # every message type sent but heartbeats
        # What arrived that could not be used: BAD_DATA (bytes that are not MAVLink),
        # decode_error (a message the decoder choked on: a bug, logged), reopened (the
        # connection failed and was opened again).
        self.faults: Counter[str] = Counter()
        self.setpoint: Setpoint | None = None  # the streamed target (owner thread only)
        self._ops: queue.SimpleQueue[Op] = queue.SimpleQueue()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._conn: Any = None
        self.commands = CommandBook(self._transmit, config.in_progress_timeout_s)

    # --- life cycle -------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._stop.is_set()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        """Start the owner thread (once)."""
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._run, name=f"mavlink-{self.name}", daemon=True
            )
            self._thread.start()

    def close(self) -> None:
        """Stop the owner thread and close the connection (idempotent)."""
        self._stop.set()
        self._wake()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=3.0)
        for fd in (self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._wake_r = self._wake_w = -1

    # --- work from other threads --------------------------------------------------------
    def submit(self, op: Op) -> None:
        """Run `op(connection)` on the owner thread soon."""
        self._ops.put(op)
        self._wake()

    def command(self, p: PendingCommand) -> None:
        """Queue a COMMAND_LONG; `p.future` gets its CommandResult."""
        self.submit(lambda conn: self._enqueue_command(p))

    def set_stream(self, setpoint: Setpoint | None) -> None:
        """Stream `setpoint` at `setpoint_hz` from now on (sent at once), or stop."""

        def op(conn: Any) -> None:
            self.setpoint = setpoint
            if setpoint is not None:
                self._send_setpoint(conn, setpoint)

        self.submit(op)

    def send_once(self, setpoint: Setpoint) -> None:
        """Send one position target, not streamed."""
        self.submit(lambda conn: self._send_setpoint(conn, setpoint))

    def _wake(self) -> None:
        with contextlib.suppress(OSError):  # a full pipe already wakes the thread
            os.write(self._wake_w, b"x")

    # --- the owner thread -----------------------------------------------------------------
    def _open(self) -> Any:
        device, baud = self.connection, self.cfg.baud
        if "," in device and not device.startswith(("udp", "tcp")):
            device, _, b = device.rpartition(",")
            baud = int(b)
        return mavutil.mavlink_connection(
            device,
            baud=baud,
            source_system=self.cfg.source_system,
            source_component=self.cfg.source_component,
            autoreconnect=True,
            retries=1,
        )

    def _run(self) -> None:
        backoff = 0.5
        next_hb = next_sp = next_ev = time.monotonic()
        while not self._stop.is_set():
            if self._conn is None:
                try:
                    self._conn = self._open()
                    self.open_error = ""
                except Exception as exc:  # any failure to open: report and retry
                    self.open_error = f"{type(exc).__name__}: {exc}"
                    self._stop.wait(backoff)
                    backoff = min(backoff * 2, 5.0)
                    continue
            conn = self._conn
            try:
                self._drain(conn)
                while True:
                    try:
                        op = self._ops.get_nowait()
                    except queue.Empty:
                        break
                    op(conn)
                now = time.monotonic()
                if now >= next_hb:
                    conn.mav.heartbeat_send(
                        mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, mav.MAV_STATE_ACTIVE
                    )
                    next_hb = now + 1.0 / self.cfg.heartbeat_hz
                self.commands.check(now)
                if self.setpoint is not None and now >= next_sp:
                    if self.state == LinkState.OK:  # link lost: stop sending
                        self._send_setpoint(conn, self.setpoint)
                    next_sp = now + 1.0 / self.cfg.setpoint_hz
                self._watch(now)
                if now >= next_ev:
                    self._publish_state()
                    rate = self.cfg.state_event_hz if self.state == LinkState.OK else 1.0
                    next_ev = now + 1.0 / max(rate, 0.1)
                wait = min(next_hb, next_ev, self.commands.next_deadline(now)) - time.monotonic()
                if self.setpoint is not None:
                    wait = min(wait, next_sp - time.monotonic())
                self._sleep(conn, max(0.0, min(wait, 0.05)))
            except Exception as exc:  # a broken connection: reopen it
                self.open_error = f"{type(exc).__name__}: {exc}"
                self.faults["reopened"] += 1
                self._close_conn()
                self._stop.wait(backoff)
        self._close_conn()
        self._fail_all("not_connected", "link closed")

    def _close_conn(self) -> None:
        if self._conn is not None:
            with contextlib.suppress(Exception):  # closing a broken connection may fail
                self._conn.close()
            self._conn = None

    def _sleep(self, conn: Any, wait: float) -> None:
        fds = [self._wake_r]
        fd = getattr(conn, "fd", None)
        if isinstance(fd, int) and fd >= 0:
            fds.append(fd)
        else:
            wait = min(wait, 0.005)
        ready, _, _ = select.select(fds, [], [], wait)
        if self._wake_r in ready:
            try:
                while os.read(self._wake_r, 512):
                    pass
            except (BlockingIOError, OSError):
                pass

    def _drain(self, conn: Any) -> None:
        for _ in range(500):
            try:
                msg = conn.recv_msg()
            except OSError:
                raise  # the connection itself broke: reopen it (`_run`)
            except Exception:  # hostile bytes pymavlink did not turn into BAD_DATA
                self.faults["decode_error"] += 1
                log.warning("%s: undecodable message\n%s", self.name, traceback.format_exc())
                continue
            if msg is None:
                return
            try:
                self._on_message(msg)
            except Exception:  # a message we could not fold in: a bug; keep the link
                self.faults["decode_error"] += 1
                log.warning("%s: message %s not decoded", self.name, msg, exc_info=True)

    def _on_message(self, msg: Any) -> None:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            self.faults["BAD_DATA"] += 1
            return
        src = msg.get_srcSystem()
        now = time.monotonic()
        if kind == "HEARTBEAT" and self.target is None:
            if msg.type in NOT_VEHICLES or msg.autopilot == mav.MAV_AUTOPILOT_INVALID:
                return
            if self.cfg.target_system not in (None, src):
                return
            self.target = (src, msg.get_srcComponent())
        if self.target is None or src != self.target[0]:
            return
        self.store.decode(msg, now, self.target[1])
        if kind == "COMMAND_ACK":
            target_sys = getattr(msg, "target_system", 0)
            if target_sys in (0, self.cfg.source_system):  # not another station's answer
                self.commands.on_ack(msg.command, msg.result, now)

    def _watch(self, now: float) -> None:
        last = self.store.last_heartbeat
        if not last:
            return
        silent = now - last > self.cfg.lost_after_s
        if self.state != LinkState.OK and not silent:
            was = self.state
            self.state = LinkState.OK
            self._request_streams()  # again after a loss: the vehicle may have rebooted
            if was == LinkState.CONNECTING:
                self.first_heartbeat.set()
            self._on_state_change(was, self.state)
        elif self.state == LinkState.OK and silent:
            self.state = LinkState.LOST
            self._fail_all("link_lost", f"no heartbeat for {self.cfg.lost_after_s:.0f} s")
            self._on_state_change(LinkState.OK, self.state)

    def _fail_all(self, ack: str, detail: str) -> None:
        self.commands.fail_all(ack, detail)
        self.setpoint = None

    def _request_streams(self) -> None:
        """Ask for the telemetry the link reads, and for the home position."""
        if self._conn is None:
            return
        requests: list[tuple[str, int, list[float]]] = []
        if self.cfg.telemetry_hz > 0:
            interval = 1e6 / self.cfg.telemetry_hz
            for msg_id in STREAMED:
                requests.append(
                    ("message_interval", mav.MAV_CMD_SET_MESSAGE_INTERVAL, [msg_id, interval])
                )
        requests.append(
            ("request_home", mav.MAV_CMD_REQUEST_MESSAGE, [mav.MAVLINK_MSG_ID_HOME_POSITION])
        )
        for action, command, params in requests:
            full = [float(x) for x in params] + [0.0] * (7 - len(params))
            pending = PendingCommand(
                action, command, full, Future(), self.cfg.ack_timeout_s, self.cfg.retries
            )
            self._enqueue_command(pending)

    def _enqueue_command(self, p: PendingCommand) -> None:
        if self.state != LinkState.OK:
            ack = "link_lost" if self.state == LinkState.LOST else "not_connected"
            p.future.set_result(CommandResult(p.action, ack, False, detail="nothing sent"))
            return
        self.commands.add(p, time.monotonic())

    def _transmit(self, p: PendingCommand) -> bool:
        conn = self._conn
        if conn is None or self.target is None:
            return False
        conn.mav.command_long_send(
            self.target[0], self.target[1], p.command, min(p.attempts, 255), *p.params
        )
        self.sent_counts["COMMAND_LONG"] += 1
        return True

    def _send_setpoint(self, conn: Any, sp: Setpoint) -> None:
        if self.target is None or self.state != LinkState.OK:
            return
        conn.mav.set_position_target_local_ned_send(
            _boot_ms(),
            self.target[0],
            self.target[1],
            mav.MAV_FRAME_LOCAL_NED,
            sp.type_mask,
            *sp.position,
            0,
            0,
            0,
            0,
            0,
            0,
            sp.yaw or 0.0,
            0,
        )
        self.sent_counts["SET_POSITION_TARGET_LOCAL_NED"] += 1
        sp.sent_at = time.monotonic()


def _boot_ms() -> int:
    return int(time.monotonic() * 1000) & 0xFFFFFFFF
