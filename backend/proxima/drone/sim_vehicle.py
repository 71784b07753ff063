"""A simulated multicopter that speaks MAVLink 2 over UDP the way ArduCopter SITL does.

It is the embedded default vehicle and the test double of the drone link: it sends to a
ground station at 127.0.0.1:PORT (so the station listens with `udpin:127.0.0.1:PORT`)
and answers every address it hears from. It flies a point mass with speed and
acceleration limits at real time, so the link, the safety rules and the tests meet the
same timing a real vehicle shows. `autopilot="px4"` switches the heartbeat, mode
encoding and OFFBOARD rules to PX4's, to exercise the link's PX4 path; it is this
project's model of PX4's documented behaviour, not PX4 itself.
"""

from __future__ import annotations

import contextlib
import math
import random
import select
import socket
import threading
import time
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

GRAVITY = 9.81
EARTH_RADIUS_M = 6_378_137.0
FORCE_DISARM_MAGIC = 21196  # ArduPilot/PX4: param2 of ARM_DISARM that disarms in flight

# ArduCopter custom mode numbers (the subset this vehicle flies).
COPTER_MODES: dict[str, int] = {
    "STABILIZE": 0,
    "ALT_HOLD": 2,
    "GUIDED": 4,
    "LOITER": 5,
    "RTL": 6,
    "LAND": 9,
    "POSHOLD": 16,
    "BRAKE": 17,
}
# PX4 custom mode = main << 16 | sub << 24.
PX4_MODES: dict[str, tuple[int, int]] = {
    "MANUAL": (1, 0),
    "ALTCTL": (2, 0),
    "POSCTL": (3, 0),
    "TAKEOFF": (4, 2),
    "LOITER": (4, 3),
    "RTL": (4, 5),
    "LAND": (4, 6),
    "OFFBOARD": (6, 0),
}
# Modes in which the vehicle holds its position (no pilot sticks exist here).
_HOLD_MODES = {"STABILIZE", "ALT_HOLD", "LOITER", "POSHOLD", "BRAKE", "MANUAL", "ALTCTL", "POSCTL"}
_ARMABLE_MODES = {"STABILIZE", "ALT_HOLD", "GUIDED", "LOITER", "POSHOLD"}  # ArduCopter
_ARMABLE_MODES |= {"MANUAL", "ALTCTL", "POSCTL", "OFFBOARD"}  # PX4 ("LOITER" is Hold)

# Messages the vehicle can stream and their default rates in Hz (0 = only on request).
_TELEMETRY_IDS = {
    mavlink.MAVLINK_MSG_ID_HEARTBEAT: "HEARTBEAT",
    mavlink.MAVLINK_MSG_ID_SYS_STATUS: "SYS_STATUS",
    mavlink.MAVLINK_MSG_ID_ATTITUDE: "ATTITUDE",
    mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: "LOCAL_POSITION_NED",
    mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: "GLOBAL_POSITION_INT",
    mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: "EXTENDED_SYS_STATE",
    mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED: "POSITION_TARGET_LOCAL_NED",
    mavlink.MAVLINK_MSG_ID_VFR_HUD: "VFR_HUD",
    mavlink.MAVLINK_MSG_ID_HOME_POSITION: "HOME_POSITION",
}


@dataclass
class SimConfig:
    """Everything that makes one simulated vehicle; defaults are ArduCopter-like."""

    port: int = 14550  # where the ground station listens
    out_ports: tuple[int, ...] = ()  # further ground stations (like SITL's extra --out)
    sysid: int = 1
    host: str = "127.0.0.1"
    autopilot: str = "ardupilot"  # "ardupilot" or "px4"
    rate_hz: float = 10.0  # default telemetry rate
    physics_hz: float = 50.0
    max_speed: float = 5.0  # horizontal m/s (WPNAV_SPEED)
    max_climb: float = 2.5  # m/s
    max_descent: float = 1.5  # m/s
    max_accel: float = 2.5  # m/s^2, horizontal and vertical
    position_gain: float = 3.0  # 1/s, final approach of the position controller
    land_speed: float = 0.5  # m/s in LAND
    rtl_altitude: float = 15.0  # m
    battery_pct: float = 100.0
    battery_flight_s: float = 1200.0  # hover time from full to empty
    battery_failsafe_pct: float = 10.0  # below this in flight: LAND
    disarm_delay_s: float = 10.0  # armed on the ground without taking off: disarm
    land_disarm_s: float = 0.5  # on the ground in LAND: disarm after this
    offboard_loss_s: float = 0.5  # PX4: no setpoint for this long leaves OFFBOARD
    home: tuple[float, float, float] = (50.0755, 14.4378, 300.0)  # lat, lon, alt AMSL
    loss: float = 0.0  # probability of dropping an incoming packet (tests of retries)
    seed: int = 0


@dataclass
class _Peer:
    addr: tuple[str, int]
    last_heard: float = field(default_factory=time.monotonic)


class SimVehicle:
    """One simulated quadcopter. `run(stop)` owns the socket and the clock until `stop`
    is set; everything else is called from that loop only."""

    def __init__(self, config: SimConfig) -> None:
        if config.autopilot not in ("ardupilot", "px4"):
            raise ValueError(f"autopilot must be 'ardupilot' or 'px4', got {config.autopilot!r}")
        if not 1 <= config.sysid <= 255:
            raise ValueError(f"sysid must be 1..255, got {config.sysid}")
        self.cfg = config
        self.px4 = config.autopilot == "px4"
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((config.host, 0))
        self.sock.setblocking(False)
        self.out_addr = (config.host, config.port)
        self.extra_addrs = [(config.host, p) for p in config.out_ports]
        self.peers: dict[tuple[str, int], _Peer] = {}
        self.mav = mavlink.MAVLink(self, srcSystem=config.sysid, srcComponent=1)
        self.rng = random.Random(config.seed)
        self.t0 = time.monotonic()
        # vehicle state (local NED from the home point, metres, m/s, radians)
        self.pos = [0.0, 0.0, 0.0]
        self.vel = [0.0, 0.0, 0.0]
        self.acc = [0.0, 0.0, 0.0]
        self.yaw = 0.0
        self.yaw_target: float | None = None
        self.armed = False
        self.motors_on = False
        self.mode = "LOITER" if self.px4 else "STABILIZE"
        self.landed = mavlink.MAV_LANDED_STATE_ON_GROUND
        self.target: list[float] | None = None  # position target (NED)
        self.target_mask = 0
        self.vel_target: list[float] | None = None
        self.speed = config.max_speed
        self.climb = config.max_climb
        self.descent = config.max_descent
        self.battery = config.battery_pct
        self.armed_on_ground_since: float | None = None
        self.touchdown_since: float | None = None
        self.rtl_phase = ""
        self.setpoint_times: list[float] = []
        self.intervals: dict[int, float] = {}
        for msg_id in _TELEMETRY_IDS:
            self.intervals[msg_id] = 1.0 / config.rate_hz if config.rate_hz > 0 else 0.0
        self.intervals[mavlink.MAVLINK_MSG_ID_HEARTBEAT] = 1.0
        self.intervals[mavlink.MAVLINK_MSG_ID_HOME_POSITION] = 0.0
        self.next_send: dict[int, float] = dict.fromkeys(self.intervals, self.t0)
        self.packets_in = 0
        self.packets_dropped = 0

    # --- transport -------------------------------------------------------------------
    def write(self, buf: bytes) -> None:
        """Called by pymavlink's encoder: send one packet to the station and every peer."""
        now = time.monotonic()
        targets = {self.out_addr, *self.extra_addrs}
        targets |= {a for a, p in self.peers.items() if now - p.last_heard < 10.0}
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
            except mavlink.MAVError:
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
                    self.step(dt)
                    self._stream(now)
                    next_tick += dt
                    if now - next_tick > 1.0:  # we were suspended: do not replay the past
                        next_tick = now + dt
        finally:
            self.sock.close()

    # --- helpers ---------------------------------------------------------------------
    def boot_ms(self) -> int:
        return int((time.monotonic() - self.t0) * 1000) & 0xFFFFFFFF

    def statustext(self, text: str, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        self.mav.statustext_send(severity, text[:50].encode())

    def altitude(self) -> float:
        return -self.pos[2]

    def in_air(self) -> bool:
        return self.landed != mavlink.MAV_LANDED_STATE_ON_GROUND

    def custom_mode(self) -> int:
        if self.px4:
            main, sub = PX4_MODES[self.mode]
            return (main << 16) | (sub << 24)
        return COPTER_MODES[self.mode]

    def mode_from(self, custom_main: float, custom_sub: float) -> str | None:
        """The mode name a SET_MODE / DO_SET_MODE asks for, or None if unknown here."""
        if self.px4:
            want = (int(custom_main), int(custom_sub))
            for name, code in PX4_MODES.items():
                if code == want or (code[0] == want[0] and code[0] != 4):
                    return name
            return None
        for name, number in COPTER_MODES.items():
            if number == int(custom_main):
                return name
        return None

    # --- mode, arming ----------------------------------------------------------------
    def set_mode(self, name: str) -> int:
        """Switch mode; returns a MAV_RESULT."""
        if name == self.mode:
            return mavlink.MAV_RESULT_ACCEPTED
        if name == "OFFBOARD" and not self._setpoints_streaming():
            self.statustext("Offboard: no setpoint stream", mavlink.MAV_SEVERITY_WARNING)
            return mavlink.MAV_RESULT_DENIED
        if name in ("TAKEOFF",):
            return mavlink.MAV_RESULT_DENIED  # entered through NAV_TAKEOFF only
        self.mode = name
        self.vel_target = None
        if name in ("GUIDED", "OFFBOARD") or name in _HOLD_MODES:
            self.target = self._stopping_point() if self.in_air() else None
            self.target_mask = 0
        if name == "RTL":
            self.rtl_phase = "climb" if self.in_air() else ""
        if name == "LAND" and self.in_air():
            self.landed = mavlink.MAV_LANDED_STATE_LANDING
        self.statustext(f"Mode {name}")
        return mavlink.MAV_RESULT_ACCEPTED

    def arm(self, force: bool = False) -> int:
        if self.armed:
            return mavlink.MAV_RESULT_ACCEPTED
        if not force:
            if self.mode not in _ARMABLE_MODES:
                self.statustext(f"Arm: mode {self.mode} not armable", mavlink.MAV_SEVERITY_ERROR)
                return mavlink.MAV_RESULT_FAILED
            if self.battery < self.cfg.battery_failsafe_pct + 5:
                self.statustext("PreArm: battery low", mavlink.MAV_SEVERITY_ERROR)
                return mavlink.MAV_RESULT_FAILED
        self.armed = True
        self.motors_on = True
        self.armed_on_ground_since = time.monotonic()
        self.statustext("Arming motors")
        return mavlink.MAV_RESULT_ACCEPTED

    def disarm(self, force: bool = False, reason: str = "") -> int:
        if not self.armed:
            return mavlink.MAV_RESULT_ACCEPTED
        if self.in_air() and not force:
            self.statustext("Disarm refused: in flight", mavlink.MAV_SEVERITY_ERROR)
            return mavlink.MAV_RESULT_FAILED
        self.armed = False
        self.motors_on = False
        self.target = None
        self.vel_target = None
        self.armed_on_ground_since = None
        self.statustext(f"Disarming motors{': ' + reason if reason else ''}")
        return mavlink.MAV_RESULT_ACCEPTED

    def takeoff(self, altitude: float) -> int:
        guided = "OFFBOARD" if self.px4 else "GUIDED"
        if not self.armed:
            self.statustext("Takeoff: not armed", mavlink.MAV_SEVERITY_ERROR)
            return mavlink.MAV_RESULT_FAILED
        if not self.px4 and self.mode != guided:
            self.statustext("Takeoff: not in GUIDED", mavlink.MAV_SEVERITY_ERROR)
            return mavlink.MAV_RESULT_FAILED
        if not math.isfinite(altitude) or altitude <= 0.0:
            return mavlink.MAV_RESULT_DENIED
        if self.in_air() and self.landed != mavlink.MAV_LANDED_STATE_TAKEOFF:
            return mavlink.MAV_RESULT_FAILED
        if self.px4:
            self.mode = "TAKEOFF"
        self.target = [self.pos[0], self.pos[1], -altitude]
        self.target_mask = 0
        self.landed = mavlink.MAV_LANDED_STATE_TAKEOFF
        self.armed_on_ground_since = None
        self.statustext(f"Takeoff to {altitude:.1f} m")
        return mavlink.MAV_RESULT_ACCEPTED

    def _setpoints_streaming(self) -> bool:
        now = time.monotonic()
        recent = [t for t in self.setpoint_times if now - t < 1.0]
        return len(recent) >= 3 and now - recent[-1] < self.cfg.offboard_loss_s

    def _stopping_point(self) -> list[float]:
        """Where the vehicle can stop from its current velocity (ArduCopter's brake)."""
        a = max(self.cfg.max_accel, 0.1)
        return [p + v * abs(v) / (2 * a) for p, v in zip(self.pos, self.vel, strict=True)]

    # --- incoming messages -----------------------------------------------------------
    def _handle(self, msg: mavlink.MAVLink_message) -> None:
        kind = msg.get_type()
        target = getattr(msg, "target_system", None)
        if target not in (None, 0, self.cfg.sysid):
            return
        if kind == "COMMAND_LONG":
            self._command(
                msg.command,
                [
                    msg.param1,
                    msg.param2,
                    msg.param3,
                    msg.param4,
                    msg.param5,
                    msg.param6,
                    msg.param7,
                ],
                msg,
            )
        elif kind == "COMMAND_INT":
            params = [
                msg.param1,
                msg.param2,
                msg.param3,
                msg.param4,
                msg.x / 1e7,
                msg.y / 1e7,
                msg.z,
            ]
            self._command(msg.command, params, msg)
        elif kind == "SET_MODE":
            name = self._decode_set_mode(msg.base_mode, msg.custom_mode)
            result = self.set_mode(name) if name else mavlink.MAV_RESULT_DENIED
            self._ack(mavlink.MAVLINK_MSG_ID_SET_MODE, result, msg)
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            self._position_target(msg)

    def _decode_set_mode(self, base_mode: int, custom_mode: int) -> str | None:
        if not base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return None
        if self.px4:
            return self.mode_from((custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF)
        return self.mode_from(custom_mode, 0)

    def _ack(self, command: int, result: int, msg: mavlink.MAVLink_message) -> None:
        self.mav.command_ack_send(
            command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )

    def _command(self, cmd: int, p: list[float], msg: mavlink.MAVLink_message) -> None:
        result = mavlink.MAV_RESULT_UNSUPPORTED
        if cmd == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            force = int(p[1]) == FORCE_DISARM_MAGIC
            result = self.arm(force) if p[0] >= 0.5 else self.disarm(force, "commanded")
            if force and p[0] < 0.5:
                self.motors_on = False
        elif cmd == mavlink.MAV_CMD_DO_SET_MODE:
            name = None
            if int(p[0]) & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
                name = self.mode_from(p[1], p[2])
            result = self.set_mode(name) if name else mavlink.MAV_RESULT_DENIED
        elif cmd == mavlink.MAV_CMD_NAV_TAKEOFF:
            altitude = p[6] - self.cfg.home[2] if self.px4 else p[6]
            result = self.takeoff(altitude)
        elif cmd == mavlink.MAV_CMD_NAV_LAND:
            result = self.set_mode("LAND")
        elif cmd == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            result = self.set_mode("RTL")
        elif cmd == mavlink.MAV_CMD_DO_CHANGE_SPEED:
            result = self._change_speed(int(p[0]), p[1])
        elif cmd == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            result = self._set_interval(int(p[0]), p[1])
        elif cmd == mavlink.MAV_CMD_GET_MESSAGE_INTERVAL:
            msg_id = int(p[0])
            if msg_id in self.intervals:
                interval = self.intervals[msg_id]
                self.mav.message_interval_send(msg_id, int(interval * 1e6) if interval else -1)
                result = mavlink.MAV_RESULT_ACCEPTED
            else:
                result = mavlink.MAV_RESULT_DENIED
        elif cmd == mavlink.MAV_CMD_REQUEST_MESSAGE:
            msg_id = int(p[0])
            result = (
                mavlink.MAV_RESULT_ACCEPTED
                if self._send_one(msg_id)
                else (mavlink.MAV_RESULT_DENIED)
            )
        self._ack(cmd, result, msg)

    def _change_speed(self, speed_type: int, speed: float) -> int:
        if speed == -1.0:
            return mavlink.MAV_RESULT_ACCEPTED  # "no change"
        if not math.isfinite(speed) or speed <= 0.0:
            return mavlink.MAV_RESULT_DENIED
        if speed_type in (0, 1):
            self.speed = min(speed, self.cfg.max_speed)
        elif speed_type == 2:
            self.climb = min(speed, self.cfg.max_climb)
        elif speed_type == 3:
            self.descent = min(speed, self.cfg.max_descent)
        else:
            return mavlink.MAV_RESULT_DENIED
        self.statustext(f"Speed set to {speed:.1f} m/s (type {speed_type})")
        return mavlink.MAV_RESULT_ACCEPTED

    def _set_interval(self, msg_id: int, interval_us: float) -> int:
        if msg_id not in self.intervals:
            return mavlink.MAV_RESULT_DENIED
        if interval_us < 0:
            self.intervals[msg_id] = 0.0
        elif interval_us == 0:
            default = 1.0 / self.cfg.rate_hz if self.cfg.rate_hz > 0 else 0.0
            self.intervals[msg_id] = 1.0 if msg_id == 0 else default
        else:
            self.intervals[msg_id] = max(interval_us / 1e6, 1.0 / self.cfg.physics_hz)
        self.next_send[msg_id] = time.monotonic()
        return mavlink.MAV_RESULT_ACCEPTED

    def _position_target(self, msg: mavlink.MAVLink_message) -> None:
        self.setpoint_times = [t for t in self.setpoint_times if time.monotonic() - t < 1.0]
        self.setpoint_times.append(time.monotonic())
        guided = "OFFBOARD" if self.px4 else "GUIDED"
        if self.mode != guided or not self.armed:
            return  # both autopilots ignore guided targets outside their guided mode
        if not self.in_air() and not self.px4:
            return  # ArduCopter needs NAV_TAKEOFF first
        mask = msg.type_mask
        frame = msg.coordinate_frame
        use_pos = not mask & 0b111
        use_vel = not mask & 0b111000
        if use_pos:
            offset = [msg.x, msg.y, msg.z]
            if frame == mavlink.MAV_FRAME_LOCAL_NED:
                target = offset
            elif frame == mavlink.MAV_FRAME_LOCAL_OFFSET_NED:
                target = [p + o for p, o in zip(self.pos, offset, strict=True)]
            elif frame == mavlink.MAV_FRAME_BODY_OFFSET_NED:
                c, s = math.cos(self.yaw), math.sin(self.yaw)
                n = c * offset[0] - s * offset[1]
                e = s * offset[0] + c * offset[1]
                target = [self.pos[0] + n, self.pos[1] + e, self.pos[2] + offset[2]]
            else:
                self.statustext(f"Frame {frame} unsupported", mavlink.MAV_SEVERITY_WARNING)
                return
            if self.px4 and not self.in_air() and target[2] < -0.1:
                self.landed = mavlink.MAV_LANDED_STATE_TAKEOFF
            self.target = target
            self.target_mask = mask
            self.vel_target = None
        elif use_vel:
            self.vel_target = [msg.vx, msg.vy, msg.vz]
            self.target = None
            self.target_mask = mask
        if not mask & 0b10000000000:  # yaw given
            self.yaw_target = msg.yaw

    # --- physics ---------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance the vehicle by `dt` seconds."""
        now = time.monotonic()
        if self.px4 and self.mode == "OFFBOARD" and not self._setpoints_streaming():
            self.mode = "LOITER"
            self.target = self._stopping_point() if self.in_air() else None
            self.statustext("Offboard lost: holding", mavlink.MAV_SEVERITY_WARNING)
        if not self.motors_on:
            self._fall(dt)
            return
        desired = self._desired_velocity()
        self._accelerate(desired, dt)
        for i in range(3):
            self.pos[i] += self.vel[i] * dt
        self._yaw_step(dt)
        self._ground_contact(now)
        self._battery_step(dt)

    def _desired_velocity(self) -> list[float]:
        mode = self.mode
        if not self.in_air() and self.landed != mavlink.MAV_LANDED_STATE_TAKEOFF:
            return [0.0, 0.0, 0.0]
        if mode == "LAND":
            hold = self.target or self._stopping_point()
            self.target = [hold[0], hold[1], 0.0]
            v = self._toward(self.target, self.speed)
            speed = self.cfg.land_speed if self.altitude() < 10 else self.descent
            return [v[0], v[1], speed]
        if mode == "RTL":
            return self._rtl_velocity()
        if self.vel_target is not None and mode in ("GUIDED", "OFFBOARD"):
            return list(self.vel_target)
        if self.target is None:
            self.target = self._stopping_point()
        return self._toward(self.target, self.speed)

    def _rtl_velocity(self) -> list[float]:
        alt = max(self.cfg.rtl_altitude, self.altitude())
        if self.rtl_phase == "climb":
            self.target = [self.pos[0], self.pos[1], -alt]
            if abs(self.pos[2] + alt) < 0.2:
                self.rtl_phase = "return"
        if self.rtl_phase == "return":
            self.target = [0.0, 0.0, self.pos[2]]
            if math.hypot(self.pos[0], self.pos[1]) < 0.3:
                self.rtl_phase = ""
                self.mode = "LAND"
                self.landed = mavlink.MAV_LANDED_STATE_LANDING
                self.statustext("RTL: landing")
        return self._toward(self.target or self.pos, self.speed)

    def _toward(self, target: list[float], speed: float) -> list[float]:
        """Velocity that reaches `target` without overshoot: capped by `speed`, by the
        braking distance (sqrt(2 a d)) and, near the target, by a proportional gain."""
        a, k = self.cfg.max_accel, self.cfg.position_gain
        dn, de, dd = (t - p for t, p in zip(target, self.pos, strict=True))
        dist = math.hypot(dn, de)
        out = [0.0, 0.0, 0.0]
        if dist > 1e-6:
            mag = min(speed, math.sqrt(2 * a * dist), k * dist)
            out[0], out[1] = dn / dist * mag, de / dist * mag
        limit = self.descent if dd > 0 else self.climb
        mag = min(limit, math.sqrt(2 * a * abs(dd)), k * abs(dd))
        out[2] = math.copysign(mag, dd)
        return out

    def _accelerate(self, desired: list[float], dt: float) -> None:
        a = self.cfg.max_accel
        dvn, dve = desired[0] - self.vel[0], desired[1] - self.vel[1]
        dv = math.hypot(dvn, dve)
        scale = min(1.0, a * dt / dv) if dv > 1e-9 else 0.0
        self.acc[0], self.acc[1] = dvn * scale / dt, dve * scale / dt
        dvd = desired[2] - self.vel[2]
        self.acc[2] = max(-a * dt, min(a * dt, dvd)) / dt
        for i in range(3):
            self.vel[i] += self.acc[i] * dt

    def _yaw_step(self, dt: float) -> None:
        if self.yaw_target is None:
            return
        err = (self.yaw_target - self.yaw + math.pi) % (2 * math.pi) - math.pi
        step = math.radians(90.0) * dt
        self.yaw += max(-step, min(step, err))
        if abs(err) <= step:
            self.yaw = self.yaw_target
            self.yaw_target = None

    def _ground_contact(self, now: float) -> None:
        taking_off = self.landed == mavlink.MAV_LANDED_STATE_TAKEOFF
        if taking_off and self.target is not None and abs(self.pos[2] - self.target[2]) < 0.1:
            self.landed = mavlink.MAV_LANDED_STATE_IN_AIR
            if self.px4 and self.mode == "TAKEOFF":
                self.mode = "LOITER"
        if self.pos[2] >= 0.0:
            self.pos[2] = 0.0
            self.vel[2] = min(self.vel[2], 0.0)
            if self.landed in (mavlink.MAV_LANDED_STATE_LANDING, mavlink.MAV_LANDED_STATE_IN_AIR):
                self.landed = mavlink.MAV_LANDED_STATE_ON_GROUND
                self.vel = [0.0, 0.0, 0.0]
                self.touchdown_since = now
                self.statustext("Landed")
        if self.landed == mavlink.MAV_LANDED_STATE_ON_GROUND and self.armed:
            if self.touchdown_since is not None and now - self.touchdown_since > (
                self.cfg.land_disarm_s
            ):
                self.touchdown_since = None
                self.disarm(reason="landed")
            elif self.armed_on_ground_since is not None and now - self.armed_on_ground_since > (
                self.cfg.disarm_delay_s
            ):
                self.disarm(reason="auto-disarm")

    def _fall(self, dt: float) -> None:
        if self.pos[2] < 0.0:
            self.vel[2] += GRAVITY * dt
            self.pos[2] += self.vel[2] * dt
            self.landed = mavlink.MAV_LANDED_STATE_IN_AIR
        if self.pos[2] >= 0.0:
            self.pos[2] = 0.0
            self.vel = [0.0, 0.0, 0.0]
            self.acc = [0.0, 0.0, 0.0]
            self.landed = mavlink.MAV_LANDED_STATE_ON_GROUND

    def _battery_step(self, dt: float) -> None:
        if not self.armed:
            return
        speed = math.hypot(*self.vel)
        self.battery -= 100.0 * dt / self.cfg.battery_flight_s * (1.0 + 0.05 * speed)
        self.battery = max(self.battery, 0.0)
        fs = self.cfg.battery_failsafe_pct
        if self.battery < fs and self.in_air() and self.mode != "LAND":
            self.statustext("Battery failsafe: landing", mavlink.MAV_SEVERITY_CRITICAL)
            self.set_mode("LAND")

    # --- telemetry -------------------------------------------------------------------
    def _stream(self, now: float) -> None:
        for msg_id, interval in self.intervals.items():
            if interval <= 0.0 or now < self.next_send[msg_id]:
                continue
            nxt = self.next_send[msg_id] + interval
            self.next_send[msg_id] = nxt if nxt > now else now + interval
            self._send_one(msg_id)

    def _send_one(self, msg_id: int) -> bool:
        """Send one telemetry message now; False if this vehicle does not produce it."""
        m = self.mav
        t = self.boot_ms()
        x, y, z = self.pos
        vx, vy, vz = self.vel
        if msg_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT:
            base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            base |= mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
            if self.armed:
                base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
            ap = mavlink.MAV_AUTOPILOT_PX4 if self.px4 else mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
            status = mavlink.MAV_STATE_ACTIVE if self.armed else mavlink.MAV_STATE_STANDBY
            m.heartbeat_send(mavlink.MAV_TYPE_QUADROTOR, ap, base, self.custom_mode(), status)
        elif msg_id == mavlink.MAVLINK_MSG_ID_SYS_STATUS:
            frac = self.battery / 100.0
            volts = 14.0 + 2.8 * frac
            amps = (15.0 + 2.0 * math.hypot(vx, vy, vz)) if self.armed else 0.5
            sensors = 0x3FFF
            m.sys_status_send(
                sensors,
                sensors,
                sensors,
                250,
                int(volts * 1000),
                int(amps * 100),
                round(self.battery),
                0,
                0,
                0,
                0,
                0,
                0,
            )
        elif msg_id == mavlink.MAVLINK_MSG_ID_ATTITUDE:
            c, s = math.cos(self.yaw), math.sin(self.yaw)
            fwd = c * self.acc[0] + s * self.acc[1]
            right = -s * self.acc[0] + c * self.acc[1]
            pitch = -math.atan2(fwd, GRAVITY)
            roll = math.atan2(right, GRAVITY)
            m.attitude_send(t, roll, pitch, self.yaw, 0.0, 0.0, 0.0)
        elif msg_id == mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED:
            m.local_position_ned_send(t, x, y, z, vx, vy, vz)
        elif msg_id == mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT:
            lat, lon, alt = self.global_position()
            hdg = int(math.degrees(self.yaw) % 360 * 100)
            m.global_position_int_send(
                t,
                int(lat * 1e7),
                int(lon * 1e7),
                int(alt * 1000),
                int(-z * 1000),
                int(vx * 100),
                int(vy * 100),
                int(vz * 100),
                hdg,
            )
        elif msg_id == mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE:
            m.extended_sys_state_send(mavlink.MAV_VTOL_STATE_UNDEFINED, self.landed)
        elif msg_id == mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED:
            if self.target is None or self.mode not in ("GUIDED", "OFFBOARD"):
                return True
            tx, ty, tz = self.target
            mask = 0b110111111000
            m.position_target_local_ned_send(
                t, mavlink.MAV_FRAME_LOCAL_NED, mask, tx, ty, tz, 0, 0, 0, 0, 0, 0, self.yaw, 0
            )
        elif msg_id == mavlink.MAVLINK_MSG_ID_VFR_HUD:
            hdg = int(math.degrees(self.yaw) % 360)
            throttle = 50 if self.motors_on else 0
            m.vfr_hud_send(math.hypot(vx, vy), math.hypot(vx, vy), hdg, throttle, -z, -vz)
        elif msg_id == mavlink.MAVLINK_MSG_ID_HOME_POSITION:
            lat, lon, alt = self.cfg.home
            m.home_position_send(
                int(lat * 1e7), int(lon * 1e7), int(alt * 1000), 0, 0, 0, [1, 0, 0, 0], 0, 0, 0
            )
        else:
            return False
        return True

    def global_position(self) -> tuple[float, float, float]:
        """Latitude, longitude (degrees) and altitude AMSL (m) of the vehicle."""
        lat0, lon0, alt0 = self.cfg.home
        lat = lat0 + math.degrees(self.pos[0] / EARTH_RADIUS_M)
        lon = lon0 + math.degrees(self.pos[1] / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
        return lat, lon, alt0 - self.pos[2]
