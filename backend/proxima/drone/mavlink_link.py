"""`DroneLink` over MAVLink 2 with pymavlink, for ArduPilot and PX4 vehicles, SITL or real.

One thread owns the connection: it reads every message, sends a GCS heartbeat at 1 Hz,
watches the vehicle's heartbeat (LOST after `lost_after_s` of silence), sends queued
commands and retries them until a COMMAND_ACK arrives, and on PX4 streams the OFFBOARD
position setpoint above 2 Hz. Callers on other threads hand it work through a queue and
block on a future, so pymavlink is only ever touched by that one thread.

Connection strings are pymavlink's: `udpin:127.0.0.1:14550` (listen, what SITL sends
to), `udpout:HOST:PORT`, `tcp:HOST:PORT` (ArduPilot SITL serves tcp:127.0.0.1:5760), or a
serial device `/dev/ttyUSB0,57600`.
"""

from __future__ import annotations

import contextlib
import math
import os
import queue
import select
import threading
import time
from collections import Counter
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

from proxima.drone.events import DroneAlarmEvent, DroneStateEvent
from proxima.drone.link import CommandResult, DroneLink, LinkError, Telemetry
from proxima.events import EventBus
from proxima.types import LinkState

os.environ.setdefault("MAVLINK20", "1")  # speak MAVLink 2, as ArduPilot and PX4 do
from pymavlink import mavutil

mavutil.set_dialect("ardupilotmega")
mav = mavutil.mavlink

FORCE_DISARM_MAGIC = 21196
POSITION_ONLY_MASK = 0b110111111000  # use x, y, z; ignore velocity, acceleration, yaw rate
IGNORE_YAW = 0b10000000000
_LANDED = {0: "unknown", 1: "on_ground", 2: "in_air", 3: "takeoff", 4: "landing"}
_RESULTS = {
    0: "accepted",
    1: "temporarily_rejected",
    2: "denied",
    3: "unsupported",
    4: "failed",
    5: "in_progress",
    6: "cancelled",
}
_NOT_VEHICLES = {
    mav.MAV_TYPE_GCS,
    mav.MAV_TYPE_GIMBAL,
    mav.MAV_TYPE_CAMERA,
    mav.MAV_TYPE_ADSB,
    mav.MAV_TYPE_ONBOARD_CONTROLLER,
    mav.MAV_TYPE_ANTENNA_TRACKER,
}
STREAMED = (
    mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    mav.MAVLINK_MSG_ID_ATTITUDE,
    mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT,
    mav.MAVLINK_MSG_ID_SYS_STATUS,
    mav.MAVLINK_MSG_ID_EXTENDED_SYS_STATE,
    mav.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED,
)


@dataclass
class LinkConfig:
    """Timing of one link; defaults suit a local or radio link to ArduPilot or PX4."""

    heartbeat_hz: float = 1.0
    lost_after_s: float = 3.0
    ack_timeout_s: float = 0.5  # per attempt
    retries: int = 3  # resends after the first attempt
    in_progress_timeout_s: float = 10.0
    echo_timeout_s: float = 0.5  # wait for POSITION_TARGET_LOCAL_NED after a target
    setpoint_hz: float = 10.0  # PX4 OFFBOARD stream; PX4 needs more than 2 Hz
    telemetry_hz: float = 10.0  # asked for with SET_MESSAGE_INTERVAL; 0 leaves rates alone
    state_event_hz: float = 10.0
    brake_accel_m_s2: float = 2.5  # used to place the hold point ahead of a moving vehicle
    source_system: int = 255
    source_component: int = 190  # MAV_COMP_ID_MISSIONPLANNER
    target_system: int | None = None  # None: the first vehicle heard
    baud: int = 57600


@dataclass
class _Pending:
    action: str
    command: int
    params: list[float]
    future: Future
    timeout: float
    retries: int
    attempts: int = 0
    first_sent: float = 0.0
    deadline: float = 0.0


@dataclass
class _Setpoint:
    position: tuple[float, float, float]
    yaw: float | None = None
    sent_at: float = 0.0


@dataclass
class _State:
    fields: dict[str, Any] = field(default_factory=dict)
    last_heartbeat: float = 0.0
    target_echo_at: float = 0.0


class MavlinkLink(DroneLink):
    """A vehicle over pymavlink. Construct, `connect()`, command, `close()`."""

    def __init__(
        self,
        connection: str,
        name: str = "",
        *,
        config: LinkConfig | None = None,
        bus: EventBus | None = None,
    ) -> None:
        self.connection = connection
        self.name = name or connection
        self.cfg = config or LinkConfig()
        if self.cfg.setpoint_hz <= 2.0:
            raise ValueError("setpoint_hz must be above 2 Hz (PX4 leaves OFFBOARD otherwise)")
        self.bus = bus
        self.gesture_control = False  # set by the controller; shown in state events
        self._state = LinkState.CONNECTING
        self._lock = threading.Lock()
        self._s = _State()
        self._ops: queue.SimpleQueue[Callable[[Any], None]] = queue.SimpleQueue()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._conn: Any = None
        self._open_error = ""
        self._pending: dict[int, list[_Pending]] = {}
        self._setpoint: _Setpoint | None = None
        self._target: tuple[int, int] | None = None  # (system, component)
        self._vehicle_type = mav.MAV_TYPE_QUADROTOR
        self.sent_counts: Counter[str] = Counter()  # every message type sent but heartbeats
        self._first_heartbeat = threading.Event()

    # --- life cycle -------------------------------------------------------------------
    def connect(self, timeout: float = 10.0) -> None:
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._run, name=f"mavlink-{self.name}", daemon=True
            )
            self._thread.start()
        if not self._first_heartbeat.wait(timeout):
            why = f" ({self._open_error})" if self._open_error else ""
            raise LinkError(
                f"{self.name}: no heartbeat from a vehicle on {self.connection} "
                f"within {timeout:.0f} s{why}"
            )

    def close(self) -> None:
        self._stop.set()
        self._wake()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=3.0)
        for fd in (self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._wake_r = self._wake_w = -1

    @property
    def state(self) -> LinkState:
        return self._state

    @property
    def autopilot(self) -> str:
        return self._s.fields.get("autopilot", "unknown")

    def telemetry(self) -> Telemetry | None:
        with self._lock:
            if not self._s.last_heartbeat:
                return None
            return Telemetry(**self._s.fields)

    def sent_count(self) -> int:
        """How many messages other than heartbeats this link has sent."""
        return sum(self.sent_counts.values())

    # --- commands -----------------------------------------------------------------------
    def command_long(
        self,
        action: str,
        command: int,
        params: list[float] | tuple[float, ...] = (),
        *,
        timeout: float | None = None,
        retries: int | None = None,
    ) -> CommandResult:
        """Send COMMAND_LONG and wait for its COMMAND_ACK, resending (with an increasing
        `confirmation`) after each `timeout` up to `retries` times."""
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        sent = {"msg": "COMMAND_LONG", "command": _cmd_name(command), "params": p}
        refusal = self._refusal(action, sent)
        if refusal is not None:
            return refusal
        pending = _Pending(
            action=action,
            command=command,
            params=p,
            future=Future(),
            timeout=self.cfg.ack_timeout_s if timeout is None else timeout,
            retries=self.cfg.retries if retries is None else retries,
        )
        self._submit(lambda conn: self._enqueue_command(conn, pending))
        limit = pending.timeout * (pending.retries + 1) + self.cfg.in_progress_timeout_s + 2.0
        try:
            return pending.future.result(timeout=limit)
        except TimeoutError:
            return CommandResult(
                action,
                "timeout",
                False,
                pending.attempts,
                sent=sent,
                detail="link thread did not answer",
            )

    def set_mode(self, mode: str) -> CommandResult:
        mode = mode.upper()
        tel = self.telemetry()
        if tel is None:
            return CommandResult(f"mode {mode}", "not_connected", False)
        if tel.autopilot == "px4":
            if mode not in mavutil.px4_map:
                return CommandResult(
                    f"mode {mode}", "unknown_mode", False, detail=f"PX4 has no mode {mode!r}"
                )
            base, main, sub = mavutil.px4_map[mode]
            params = [base, main, sub]
        else:
            mapping = mavutil.mode_mapping_byname(self._vehicle_type) or {}
            if mode not in mapping:
                return CommandResult(
                    f"mode {mode}", "unknown_mode", False, detail=f"ArduPilot has no mode {mode!r}"
                )
            params = [mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mapping[mode]]
        result = self.command_long(f"mode {mode}", mav.MAV_CMD_DO_SET_MODE, params)
        if result.ok:
            self._acknowledged(mode=mode)
        return result

    def _acknowledged(self, **fields: Any) -> None:
        """Record what an accepted COMMAND_ACK established (the vehicle's own answer), so
        that callers need not wait up to a second for the next heartbeat to show it."""
        with self._lock:
            self._s.fields.update(fields)

    def guided_mode(self) -> str:
        """This autopilot's name for the mode that follows external targets."""
        return "OFFBOARD" if self.autopilot == "px4" else "GUIDED"

    def enter_guided(self) -> CommandResult:
        tel = self.telemetry()
        if tel is None:
            return CommandResult("enter_guided", "not_connected", False)
        if tel.autopilot != "px4":
            return self.set_mode("GUIDED")
        if tel.position is None:
            return CommandResult(
                "enter_guided",
                "no_position",
                False,
                detail="OFFBOARD needs a local position to hold",
            )
        if self._setpoint is None:
            self._set_stream(_Setpoint(tel.position, tel.yaw))
            time.sleep(3.5 / self.cfg.setpoint_hz)  # PX4 wants the stream before the switch
        return self.set_mode("OFFBOARD")

    def arm(self) -> CommandResult:
        result = self.command_long("arm", mav.MAV_CMD_COMPONENT_ARM_DISARM, [1])
        if result.ok:
            self._acknowledged(armed=True)
        return result

    def disarm(self, force: bool = False) -> CommandResult:
        self._set_stream(None)
        magic = FORCE_DISARM_MAGIC if force else 0
        action = "force_disarm" if force else "disarm"
        result = self.command_long(action, mav.MAV_CMD_COMPONENT_ARM_DISARM, [0, magic])
        if result.ok:
            self._acknowledged(armed=False)
        return result

    def takeoff(self, altitude_m: float) -> CommandResult:
        tel = self.telemetry()
        if tel is None:
            return CommandResult("takeoff", "not_connected", False)
        if tel.autopilot == "px4":
            home_amsl = tel.home[2] if tel.home else None
            if home_amsl is None and tel.global_position and tel.relative_alt is not None:
                home_amsl = tel.global_position[2] - tel.relative_alt
            if home_amsl is None:
                return CommandResult(
                    "takeoff", "no_position", False, detail="PX4 takeoff needs the home altitude"
                )
            steps = [lambda: self.arm()]
            nan = math.nan
            params = [0, 0, 0, nan, nan, nan, home_amsl + altitude_m]
        else:
            steps = [lambda: self.enter_guided(), lambda: self.arm()]
            params = [0, 0, 0, 0, 0, 0, altitude_m]
        for step in steps:
            result = step()
            if not result.ok:
                return CommandResult(
                    "takeoff",
                    result.ack,
                    False,
                    result.attempts,
                    result.latency_s,
                    result.confirmed,
                    result.sent,
                    f"{result.action} failed: {result.detail}",
                )
        return self.command_long("takeoff", mav.MAV_CMD_NAV_TAKEOFF, params)

    def goto_local(
        self, north: float, east: float, down: float, yaw: float | None = None
    ) -> CommandResult:
        sent = {
            "msg": "SET_POSITION_TARGET_LOCAL_NED",
            "frame": "LOCAL_NED",
            "x": north,
            "y": east,
            "z": down,
            "yaw": yaw,
        }
        refusal = self._refusal("goto", sent)
        if refusal is not None:
            return refusal
        tel = self.telemetry()
        if tel is not None and tel.mode != self.guided_mode():
            return CommandResult(
                "goto",
                "wrong_mode",
                False,
                sent=sent,
                detail=f"vehicle in {tel.mode}, not {self.guided_mode()}: "
                "call enter_guided() first; nothing sent",
            )
        target = (float(north), float(east), float(down))
        t0 = time.monotonic()
        if self.autopilot == "px4":
            self._set_stream(_Setpoint(target, yaw))
        else:
            self._submit(lambda conn: self._send_setpoint(conn, _Setpoint(target, yaw)))
        deadline = t0 + self.cfg.echo_timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                echo_at = self._s.target_echo_at
                echo = self._s.fields.get("position_target")
            if echo_at > t0 and echo is not None and math.dist(echo, target) < 0.05:
                return CommandResult("goto", "echoed", True, 1, time.monotonic() - t0, True, sent)
            time.sleep(0.005)
        return CommandResult(
            "goto",
            "sent",
            True,
            1,
            None,
            False,
            sent,
            "no POSITION_TARGET_LOCAL_NED echo: unconfirmed",
        )

    def hold(self) -> CommandResult:
        tel = self.telemetry()
        if tel is None:
            return CommandResult("hold", "not_connected", False)
        if tel.autopilot == "px4":
            self._set_stream(None)
            return self.set_mode("LOITER")  # PX4's Hold
        if tel.position is None:
            return self.set_mode("BRAKE")
        if tel.mode != "GUIDED":
            result = self.set_mode("GUIDED")
            if not result.ok:
                return result
        a = max(self.cfg.brake_accel_m_s2, 0.1)
        vel = tel.velocity or (0.0, 0.0, 0.0)
        stop = [p + v * abs(v) / (2 * a) for p, v in zip(tel.position, vel, strict=True)]
        result = self.goto_local(stop[0], stop[1], stop[2])
        return CommandResult(
            "hold",
            result.ack,
            result.ok,
            result.attempts,
            result.latency_s,
            result.confirmed,
            result.sent,
            result.detail,
        )

    def change_speed(self, speed_m_s: float) -> CommandResult:
        return self.command_long("change_speed", mav.MAV_CMD_DO_CHANGE_SPEED, [1, speed_m_s, -1])

    def land(self) -> CommandResult:
        self._set_stream(None)
        return self.command_long(
            "land", mav.MAV_CMD_NAV_LAND, [0, 0, 0, math.nan, math.nan, math.nan, 0]
        )

    def set_message_interval(self, msg_id: int, rate_hz: float) -> CommandResult:
        """Ask for a message at `rate_hz` (0 stops it)."""
        interval = 1e6 / rate_hz if rate_hz > 0 else -1
        return self.command_long(
            "message_interval", mav.MAV_CMD_SET_MESSAGE_INTERVAL, [msg_id, interval]
        )

    # --- thread side ------------------------------------------------------------------
    def _refusal(self, action: str, sent: dict) -> CommandResult | None:
        if self._state == LinkState.LOST:
            return CommandResult(
                action, "link_lost", False, sent=sent, detail="link lost: nothing sent"
            )
        if self._state != LinkState.OK or self._target is None:
            return CommandResult(
                action, "not_connected", False, sent=sent, detail="no heartbeat yet: nothing sent"
            )
        if self._stop.is_set():
            return CommandResult(action, "not_connected", False, sent=sent, detail="closed")
        return None

    def _submit(self, op: Callable[[Any], None]) -> None:
        self._ops.put(op)
        self._wake()

    def _wake(self) -> None:
        with contextlib.suppress(OSError):  # a full pipe already wakes the thread
            os.write(self._wake_w, b"x")

    def _set_stream(self, setpoint: _Setpoint | None) -> None:
        def op(conn: Any) -> None:
            self._setpoint = setpoint
            if setpoint is not None:
                self._send_setpoint(conn, setpoint)

        self._submit(op)

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
                    self._open_error = ""
                except Exception as exc:  # any failure to open: report and retry
                    self._open_error = f"{type(exc).__name__}: {exc}"
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
                self._check_pending(conn, now)
                if self._setpoint is not None and now >= next_sp:
                    if self._state == LinkState.OK:  # link lost: stop sending
                        self._send_setpoint(conn, self._setpoint)
                    next_sp = now + 1.0 / self.cfg.setpoint_hz
                self._watch(now)
                if now >= next_ev:
                    self._publish_state()
                    rate = self.cfg.state_event_hz if self._state == LinkState.OK else 1.0
                    next_ev = now + 1.0 / max(rate, 0.1)
                wait = min(next_hb, next_ev, self._next_deadline(now)) - time.monotonic()
                if self._setpoint is not None:
                    wait = min(wait, next_sp - time.monotonic())
                self._sleep(conn, max(0.0, min(wait, 0.05)))
            except Exception as exc:  # a broken connection: reopen it
                self._open_error = f"{type(exc).__name__}: {exc}"
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
            msg = conn.recv_msg()
            if msg is None:
                return
            self._on_message(msg)

    def _on_message(self, msg: Any) -> None:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        src = msg.get_srcSystem()
        now = time.monotonic()
        if kind == "HEARTBEAT" and self._target is None:
            if msg.type in _NOT_VEHICLES or msg.autopilot == mav.MAV_AUTOPILOT_INVALID:
                return
            if self.cfg.target_system not in (None, src):
                return
            self._target = (src, msg.get_srcComponent())
        if self._target is None or src != self._target[0]:
            return
        f = self._s.fields
        with self._lock:
            if kind == "HEARTBEAT":
                if msg.get_srcComponent() != self._target[1]:
                    return
                self._s.last_heartbeat = now
                f["system_id"] = src
                f["autopilot"] = "px4" if msg.autopilot == mav.MAV_AUTOPILOT_PX4 else "ardupilot"
                self._vehicle_type = msg.type
                f["mode"] = mavutil.mode_string_v10(msg)
                f["armed"] = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
                f.setdefault("landed", "unknown")
            elif kind == "LOCAL_POSITION_NED":
                f["position"] = (msg.x, msg.y, msg.z)
                f["velocity"] = (msg.vx, msg.vy, msg.vz)
            elif kind == "ATTITUDE":
                f["attitude"] = (msg.roll, msg.pitch, msg.yaw)
            elif kind == "SYS_STATUS":
                if msg.battery_remaining >= 0:
                    f["battery_pct"] = float(msg.battery_remaining)
                if msg.voltage_battery != 0xFFFF:
                    f["battery_voltage"] = msg.voltage_battery / 1000.0
            elif kind == "EXTENDED_SYS_STATE":
                f["landed"] = _LANDED.get(msg.landed_state, "unknown")
            elif kind == "GLOBAL_POSITION_INT":
                f["global_position"] = (msg.lat / 1e7, msg.lon / 1e7, msg.alt / 1000.0)
                f["relative_alt"] = msg.relative_alt / 1000.0
            elif kind == "POSITION_TARGET_LOCAL_NED":
                f["position_target"] = (msg.x, msg.y, msg.z)
                self._s.target_echo_at = now
            elif kind == "HOME_POSITION":
                f["home"] = (msg.latitude / 1e7, msg.longitude / 1e7, msg.altitude / 1000.0)
            elif kind == "STATUSTEXT":
                f["status_text"] = msg.text
            f["received"] = now
        if kind == "COMMAND_ACK":
            self._on_ack(msg, now)

    def _watch(self, now: float) -> None:
        last = self._s.last_heartbeat
        if not last:
            return
        silent = now - last > self.cfg.lost_after_s
        if self._state != LinkState.OK and not silent:
            was = self._state
            self._state = LinkState.OK
            self._request_streams()  # again after a loss: the vehicle may have rebooted
            if was == LinkState.CONNECTING:
                self._first_heartbeat.set()
            else:
                self._alarm("link_lost", f"{self.name}: link back", active=False)
            self._publish_state()
        elif self._state == LinkState.OK and silent:
            self._state = LinkState.LOST
            self._fail_all("link_lost", f"no heartbeat for {self.cfg.lost_after_s:.0f} s")
            self._alarm(
                "link_lost",
                f"{self.name}: no heartbeat for {self.cfg.lost_after_s:.0f} s; commands stopped",
            )
            self._publish_state()

    def _request_streams(self) -> None:
        """Ask for the telemetry this link reads, and for the home position."""
        conn = self._conn
        if conn is None:
            return
        if self.cfg.telemetry_hz > 0:
            for msg_id in STREAMED:
                interval = 1e6 / self.cfg.telemetry_hz
                self._enqueue_command(
                    conn,
                    _Pending(
                        "message_interval",
                        mav.MAV_CMD_SET_MESSAGE_INTERVAL,
                        [msg_id, interval, 0, 0, 0, 0, 0],
                        Future(),
                        self.cfg.ack_timeout_s,
                        self.cfg.retries,
                    ),
                )
        self._enqueue_command(
            conn,
            _Pending(
                "request_home",
                mav.MAV_CMD_REQUEST_MESSAGE,
                [mav.MAVLINK_MSG_ID_HOME_POSITION, 0, 0, 0, 0, 0, 0],
                Future(),
                self.cfg.ack_timeout_s,
                self.cfg.retries,
            ),
        )

    def _enqueue_command(self, conn: Any, p: _Pending) -> None:
        if self._state != LinkState.OK:
            ack = "link_lost" if self._state == LinkState.LOST else "not_connected"
            p.future.set_result(CommandResult(p.action, ack, False, detail="nothing sent"))
            return
        line = self._pending.setdefault(p.command, [])
        line.append(p)
        if len(line) == 1:  # an ACK names only the command: one of each in flight
            self._send_command(conn, p, time.monotonic())

    def _send_command(self, conn: Any, p: _Pending, now: float) -> None:
        assert self._target is not None
        if p.attempts == 0:
            p.first_sent = now
        conn.mav.command_long_send(
            self._target[0], self._target[1], p.command, min(p.attempts, 255), *p.params
        )
        self.sent_counts["COMMAND_LONG"] += 1
        p.attempts += 1
        p.deadline = now + p.timeout

    def _send_setpoint(self, conn: Any, sp: _Setpoint) -> None:
        if self._target is None or self._state != LinkState.OK:
            return
        mask = POSITION_ONLY_MASK | (IGNORE_YAW if sp.yaw is None else 0)
        conn.mav.set_position_target_local_ned_send(
            self._boot_ms(),
            self._target[0],
            self._target[1],
            mav.MAV_FRAME_LOCAL_NED,
            mask,
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

    def _boot_ms(self) -> int:
        return int(time.monotonic() * 1000) & 0xFFFFFFFF

    def _on_ack(self, msg: Any, now: float) -> None:
        target_sys = getattr(msg, "target_system", 0)
        if target_sys not in (0, self.cfg.source_system):
            return  # an answer to another ground station
        line = self._pending.get(msg.command)
        if not line:
            return
        p = line[0]
        result = _RESULTS.get(msg.result, f"result_{msg.result}")
        if result == "in_progress":
            p.deadline = now + self.cfg.in_progress_timeout_s
            return
        ok = result == "accepted"
        self._resolve(
            p,
            CommandResult(
                p.action, result, ok, p.attempts, now - p.first_sent, True, self._sent(p)
            ),
        )

    def _sent(self, p: _Pending) -> dict:
        return {"msg": "COMMAND_LONG", "command": _cmd_name(p.command), "params": p.params}

    def _resolve(self, p: _Pending, result: CommandResult) -> None:
        line = self._pending.get(p.command, [])
        if line and line[0] is p:
            line.pop(0)
        if not p.future.done():
            p.future.set_result(result)
        if line and self._conn is not None:
            self._send_command(self._conn, line[0], time.monotonic())
        elif not line:
            self._pending.pop(p.command, None)

    def _check_pending(self, conn: Any, now: float) -> None:
        for line in list(self._pending.values()):
            p = line[0]
            if now < p.deadline:
                continue
            if p.attempts <= p.retries:
                self._send_command(conn, p, now)
            else:
                self._resolve(
                    p,
                    CommandResult(
                        p.action,
                        "timeout",
                        False,
                        p.attempts,
                        None,
                        False,
                        self._sent(p),
                        f"no COMMAND_ACK after {p.attempts} attempts",
                    ),
                )

    def _next_deadline(self, now: float) -> float:
        deadlines = [line[0].deadline for line in self._pending.values() if line]
        return min(deadlines, default=now + 1.0)

    def _fail_all(self, ack: str, detail: str) -> None:
        for line in self._pending.values():
            for p in line:
                if not p.future.done():
                    p.future.set_result(
                        CommandResult(
                            p.action, ack, False, p.attempts, sent=self._sent(p), detail=detail
                        )
                    )
        self._pending.clear()
        self._setpoint = None

    # --- events -----------------------------------------------------------------------
    def _publish_state(self) -> None:
        if self.bus is None:
            return
        tel = self.telemetry()
        now, link = time.time(), str(self._state)
        if tel is None:
            self.bus.publish(
                DroneStateEvent(
                    t=now,
                    stream=self.name,
                    drone=self.name,
                    link=link,
                    gesture_control=self.gesture_control,
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


def _cmd_name(command: int) -> str:
    entry = mav.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else str(command)
