"""The simulated multicopter itself: its state machine and physics, no I/O.

A point mass flown with speed and acceleration limits, with the modes, arming rules,
takeoff, landing, RTL, battery and failsafes of an ArduCopter- or PX4-like vehicle (the
`firmware.Firmware` decides which). Commands come in as method calls that answer with a
MAV_RESULT; time comes from `clock` (monotonic seconds), so the MAVLink server runs it
at real time and the in-memory link on its own clock. It is not an aerodynamic model.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from proxima.drone.mavlink.protocol import IGNORE_POSITION, IGNORE_VELOCITY, IGNORE_YAW, mav
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.firmware import Firmware, firmware_for

GRAVITY = 9.81
EARTH_RADIUS_M = 6_378_137.0

TextSink = Callable[[str, int], None]  # (text, MAV_SEVERITY)


class Vehicle:
    """One simulated quadcopter's state (local NED from the home point: metres, m/s,
    radians). Not thread-safe: its owner calls it from one thread."""

    def __init__(
        self,
        config: SimConfig,
        *,
        clock: Callable[[], float] = time.monotonic,
        on_text: TextSink | None = None,
    ) -> None:
        self.cfg = config
        self.fw: Firmware = firmware_for(config.autopilot)
        self.clock = clock
        self.on_text = on_text
        self.pos = [0.0, 0.0, 0.0]
        self.vel = [0.0, 0.0, 0.0]
        self.acc = [0.0, 0.0, 0.0]
        self.yaw = 0.0
        self.yaw_target: float | None = None
        self.armed = False
        self.motors_on = False
        self.mode = self.fw.initial_mode
        self.landed = mav.MAV_LANDED_STATE_ON_GROUND
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

    # --- what it reports ---------------------------------------------------------------
    def statustext(self, text: str, severity: int = mav.MAV_SEVERITY_INFO) -> None:
        if self.on_text is not None:
            self.on_text(text, severity)

    def altitude(self) -> float:
        return -self.pos[2]

    def in_air(self) -> bool:
        return self.landed != mav.MAV_LANDED_STATE_ON_GROUND

    def guided(self) -> bool:
        """In the mode that follows position targets."""
        return self.mode == self.fw.guided_mode

    def attitude(self) -> tuple[float, float, float]:
        """Roll, pitch, yaw: the tilt that produces the current horizontal acceleration."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        fwd = c * self.acc[0] + s * self.acc[1]
        right = -s * self.acc[0] + c * self.acc[1]
        return math.atan2(right, GRAVITY), -math.atan2(fwd, GRAVITY), self.yaw

    def battery_voltage(self) -> float:
        """A 4S pack: 16.8 V full, 14.0 V empty."""
        return 14.0 + 2.8 * self.battery / 100.0

    def battery_current(self) -> float:
        """Amperes drawn: hover plus a share for speed; idle when disarmed."""
        return (15.0 + 2.0 * math.hypot(*self.vel)) if self.armed else 0.5

    def global_position(self) -> tuple[float, float, float]:
        """Latitude, longitude (degrees) and altitude AMSL (m) of the vehicle."""
        lat0, lon0, alt0 = self.cfg.home
        lat = lat0 + math.degrees(self.pos[0] / EARTH_RADIUS_M)
        lon = lon0 + math.degrees(self.pos[1] / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
        return lat, lon, alt0 - self.pos[2]

    def reported_target(self) -> tuple[float, float, float] | None:
        """The position target it reports (POSITION_TARGET_LOCAL_NED), in guided mode."""
        if self.target is None or not self.guided():
            return None
        tx, ty, tz = self.target
        return tx, ty, tz

    # --- mode, arming ----------------------------------------------------------------
    def set_mode(self, name: str) -> int:
        """Switch mode; returns a MAV_RESULT."""
        if name == self.mode:
            return mav.MAV_RESULT_ACCEPTED
        fw = self.fw
        if name == fw.guided_mode and fw.needs_setpoint_stream and not self._setpoints_streaming():
            self.statustext("Offboard: no setpoint stream", mav.MAV_SEVERITY_WARNING)
            return mav.MAV_RESULT_DENIED
        if name in self.fw.command_only_modes:
            return mav.MAV_RESULT_DENIED  # e.g. PX4 TAKEOFF: entered through NAV_TAKEOFF
        self.mode = name
        self.vel_target = None
        if name == self.fw.guided_mode or name in self.fw.position_hold_modes:
            self.target = self._stopping_point() if self.in_air() else None
            self.target_mask = 0
        if name == "RTL":
            self.rtl_phase = "climb" if self.in_air() else ""
        if name == "LAND" and self.in_air():
            self.landed = mav.MAV_LANDED_STATE_LANDING
        self.statustext(f"Mode {name}")
        return mav.MAV_RESULT_ACCEPTED

    def arm(self, force: bool = False) -> int:
        if self.armed:
            return mav.MAV_RESULT_ACCEPTED
        if not force:
            if self.mode not in self.fw.armable_modes:
                self.statustext(f"Arm: mode {self.mode} not armable", mav.MAV_SEVERITY_ERROR)
                return mav.MAV_RESULT_FAILED
            if self.battery < self.cfg.battery_failsafe_pct + 5:
                self.statustext("PreArm: battery low", mav.MAV_SEVERITY_ERROR)
                return mav.MAV_RESULT_FAILED
        self.armed = True
        self.motors_on = True
        self.armed_on_ground_since = self.clock()
        self.statustext("Arming motors")
        return mav.MAV_RESULT_ACCEPTED

    def disarm(self, force: bool = False, reason: str = "") -> int:
        if not self.armed:
            return mav.MAV_RESULT_ACCEPTED
        if self.in_air() and not force:
            self.statustext("Disarm refused: in flight", mav.MAV_SEVERITY_ERROR)
            return mav.MAV_RESULT_FAILED
        self.armed = False
        self.motors_on = False
        self.target = None
        self.vel_target = None
        self.armed_on_ground_since = None
        self.statustext(f"Disarming motors{': ' + reason if reason else ''}")
        return mav.MAV_RESULT_ACCEPTED

    def takeoff(self, altitude: float) -> int:
        """Climb to `altitude` metres above home (NAV_TAKEOFF, already converted)."""
        fw = self.fw
        if not self.armed:
            self.statustext("Takeoff: not armed", mav.MAV_SEVERITY_ERROR)
            return mav.MAV_RESULT_FAILED
        if fw.takeoff_needs_guided and self.mode != fw.guided_mode:
            self.statustext(f"Takeoff: not in {fw.guided_mode}", mav.MAV_SEVERITY_ERROR)
            return mav.MAV_RESULT_FAILED
        if not math.isfinite(altitude) or altitude <= 0.0:
            return mav.MAV_RESULT_DENIED
        if self.in_air() and self.landed != mav.MAV_LANDED_STATE_TAKEOFF:
            return mav.MAV_RESULT_FAILED
        if fw.takeoff_mode is not None:
            self.mode = fw.takeoff_mode
        self.target = [self.pos[0], self.pos[1], -altitude]
        self.target_mask = 0
        self.landed = mav.MAV_LANDED_STATE_TAKEOFF
        self.armed_on_ground_since = None
        self.statustext(f"Takeoff to {altitude:.1f} m")
        return mav.MAV_RESULT_ACCEPTED

    def change_speed(self, speed_type: int, speed: float) -> int:
        """MAV_CMD_DO_CHANGE_SPEED: 0/1 ground speed, 2 climb, 3 descent; -1 no change."""
        if speed == -1.0:
            return mav.MAV_RESULT_ACCEPTED  # "no change"
        if not math.isfinite(speed) or speed <= 0.0:
            return mav.MAV_RESULT_DENIED
        if speed_type in (0, 1):
            self.speed = min(speed, self.cfg.max_speed)
        elif speed_type == 2:
            self.climb = min(speed, self.cfg.max_climb)
        elif speed_type == 3:
            self.descent = min(speed, self.cfg.max_descent)
        else:
            return mav.MAV_RESULT_DENIED
        self.statustext(f"Speed set to {speed:.1f} m/s (type {speed_type})")
        return mav.MAV_RESULT_ACCEPTED

    def _setpoints_streaming(self) -> bool:
        now = self.clock()
        recent = [t for t in self.setpoint_times if now - t < 1.0]
        return len(recent) >= 3 and now - recent[-1] < self.cfg.offboard_loss_s

    def _stopping_point(self) -> list[float]:
        """Where the vehicle can stop from its current velocity (ArduCopter's brake)."""
        a = max(self.cfg.max_accel, 0.1)
        return [p + v * abs(v) / (2 * a) for p, v in zip(self.pos, self.vel, strict=True)]

    # --- position targets ------------------------------------------------------------
    def position_target(
        self,
        frame: int,
        mask: int,
        position: tuple[float, float, float],
        velocity: tuple[float, float, float],
        yaw: float,
    ) -> None:
        """SET_POSITION_TARGET_LOCAL_NED (no answer in MAVLink: a refused target is
        ignored, as both autopilots do outside their guided mode)."""
        now = self.clock()
        self.setpoint_times = [t for t in self.setpoint_times if now - t < 1.0]
        self.setpoint_times.append(now)
        if not self.guided() or not self.armed:
            return
        if not self.in_air() and not self.fw.setpoint_takes_off:
            return  # ArduCopter needs NAV_TAKEOFF first
        use_pos = not mask & IGNORE_POSITION
        use_vel = not mask & IGNORE_VELOCITY
        if use_pos:
            offset = list(position)
            if frame == mav.MAV_FRAME_LOCAL_NED:
                target = offset
            elif frame == mav.MAV_FRAME_LOCAL_OFFSET_NED:
                target = [p + o for p, o in zip(self.pos, offset, strict=True)]
            elif frame == mav.MAV_FRAME_BODY_OFFSET_NED:
                c, s = math.cos(self.yaw), math.sin(self.yaw)
                n = c * offset[0] - s * offset[1]
                e = s * offset[0] + c * offset[1]
                target = [self.pos[0] + n, self.pos[1] + e, self.pos[2] + offset[2]]
            else:
                self.statustext(f"Frame {frame} unsupported", mav.MAV_SEVERITY_WARNING)
                return
            if self.fw.setpoint_takes_off and not self.in_air() and target[2] < -0.1:
                self.landed = mav.MAV_LANDED_STATE_TAKEOFF
            self.target = target
            self.target_mask = mask
            self.vel_target = None
        elif use_vel:
            self.vel_target = list(velocity)
            self.target = None
            self.target_mask = mask
        if not mask & IGNORE_YAW:
            self.yaw_target = yaw

    # --- physics ---------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance the vehicle by `dt` seconds."""
        now = self.clock()
        fw = self.fw
        if fw.needs_setpoint_stream and self.guided() and not self._setpoints_streaming():
            self.mode = fw.stream_loss_mode
            self.target = self._stopping_point() if self.in_air() else None
            self.statustext("Offboard lost: holding", mav.MAV_SEVERITY_WARNING)
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
        if not self.in_air() and self.landed != mav.MAV_LANDED_STATE_TAKEOFF:
            return [0.0, 0.0, 0.0]
        if mode == "LAND":
            hold = self.target or self._stopping_point()
            self.target = [hold[0], hold[1], 0.0]
            v = self._toward(self.target, self.speed)
            speed = self.cfg.land_speed if self.altitude() < 10 else self.descent
            return [v[0], v[1], speed]
        if mode == "RTL":
            return self._rtl_velocity()
        if self.vel_target is not None and self.guided():
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
                self.landed = mav.MAV_LANDED_STATE_LANDING
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
        taking_off = self.landed == mav.MAV_LANDED_STATE_TAKEOFF
        if taking_off and self.target is not None and abs(self.pos[2] - self.target[2]) < 0.1:
            self.landed = mav.MAV_LANDED_STATE_IN_AIR
            fw = self.fw
            if fw.after_takeoff_mode is not None and self.mode == fw.takeoff_mode:
                self.mode = fw.after_takeoff_mode
        if self.pos[2] >= 0.0:
            self.pos[2] = 0.0
            self.vel[2] = min(self.vel[2], 0.0)
            if self.landed in (mav.MAV_LANDED_STATE_LANDING, mav.MAV_LANDED_STATE_IN_AIR):
                self.landed = mav.MAV_LANDED_STATE_ON_GROUND
                self.vel = [0.0, 0.0, 0.0]
                self.touchdown_since = now
                self.statustext("Landed")
        if self.landed == mav.MAV_LANDED_STATE_ON_GROUND and self.armed:
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
            self.landed = mav.MAV_LANDED_STATE_IN_AIR
        if self.pos[2] >= 0.0:
            self.pos[2] = 0.0
            self.vel = [0.0, 0.0, 0.0]
            self.acc = [0.0, 0.0, 0.0]
            self.landed = mav.MAV_LANDED_STATE_ON_GROUND

    def _battery_step(self, dt: float) -> None:
        if not self.armed:
            return
        speed = math.hypot(*self.vel)
        self.battery -= 100.0 * dt / self.cfg.battery_flight_s * (1.0 + 0.05 * speed)
        self.battery = max(self.battery, 0.0)
        fs = self.cfg.battery_failsafe_pct
        if self.battery < fs and self.in_air() and self.mode != "LAND":
            self.statustext("Battery failsafe: landing", mav.MAV_SEVERITY_CRITICAL)
            self.set_mode("LAND")
