"""The simulated multicopter itself: its state machine and physics, no I/O.

A point mass flown with speed and acceleration limits, with the modes, arming rules,
takeoff, landing, RTL, battery, geofence and failsafes of an ArduCopter- or PX4-like
vehicle (the `firmware.Firmware` decides which). Its limits are its parameters
(`params`, the autopilot's own names), read again whenever one changes. Commands come in
as method calls that answer with a MAV_RESULT and were checked by their caller
(`handlers`): a method here still refuses what it cannot fly (a non-finite number, a
target outside the simulated world). Time comes from `clock` (monotonic seconds), so
the MAVLink server runs it at real time and the in-memory link on its own clock. It is
not an aerodynamic model.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from proxima.drone.mavlink.fields import finite
from proxima.drone.mavlink.protocol import IGNORE_POSITION, IGNORE_VELOCITY, IGNORE_YAW, mav
from proxima.drone.sim import failsafe
from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.firmware import Firmware, firmware_for
from proxima.drone.sim.geo import global_from_local, local_from_global
from proxima.drone.sim.mission import MissionStore
from proxima.drone.sim.param_sets import Limits

GRAVITY = 9.81
WORLD_RADIUS_M = 100_000.0  # targets farther from home than this are refused
WORLD_CEILING_M = 10_000.0  # ... and higher or deeper than this

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
        self.params = self.fw.params.store(config)
        self._limits: tuple[int, Limits] | None = None
        self.missions = MissionStore()
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
        self.land_point: tuple[float, float] | None = None  # LAND flies here first
        self.speed_override: float | None = None  # DO_CHANGE_SPEED, below the cruise
        self.climb_override: float | None = None
        self.descent_override: float | None = None
        self.battery = config.battery_pct
        self.armed_on_ground_since: float | None = None
        self.touchdown_since: float | None = None
        self.rtl_phase = ""
        self.last_setpoint_at: float | None = None
        self.gcs_heard_at: float | None = None  # the newest ground-station heartbeat
        self.failsafes = failsafe.FailsafeState()

    # --- what it reports ---------------------------------------------------------------
    def statustext(self, text: str, severity: int = mav.MAV_SEVERITY_INFO) -> None:
        if self.on_text is not None:
            self.on_text(text, severity)

    @property
    def limits(self) -> Limits:
        """The flight limits its parameters set now."""
        if self._limits is None or self._limits[0] != self.params.version:
            self._limits = (self.params.version, self.fw.params.limits(self.params, self.cfg))
        return self._limits[1]

    @property
    def speed(self) -> float:
        """Horizontal speed of position targets: the cruise speed or a slower override."""
        cruise = self.limits.cruise
        return cruise if self.speed_override is None else min(self.speed_override, cruise)

    @property
    def climb(self) -> float:
        limit = self.limits.climb
        return limit if self.climb_override is None else min(self.climb_override, limit)

    @property
    def descent(self) -> float:
        limit = self.limits.descent
        return limit if self.descent_override is None else min(self.descent_override, limit)

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

    def battery_voltage(self, pct: float | None = None) -> float:
        """A 4S pack: 16.8 V full, 14.0 V empty (at `pct`, the current charge by default)."""
        return 14.0 + 2.8 * (self.battery if pct is None else pct) / 100.0

    def battery_current(self) -> float:
        """Amperes drawn: hover plus a share for speed; idle when disarmed."""
        return (15.0 + 2.0 * math.hypot(*self.vel)) if self.armed else 0.5

    def global_position(self) -> tuple[float, float, float]:
        """Latitude, longitude (degrees) and altitude AMSL (m) of the vehicle."""
        return global_from_local(self.cfg.home, *self.pos)

    def reported_target(self) -> tuple[float, float, float] | None:
        """The position target it reports (POSITION_TARGET_LOCAL_NED), in guided mode."""
        if self.target is None or not self.guided():
            return None
        tx, ty, tz = self.target
        return tx, ty, tz

    def armable(self) -> bool:
        """Whether arming would pass its checks now (SYS_STATUS's pre-arm bit)."""
        return self.mode in self.fw.armable_modes and not self._battery_too_low()

    # --- mode, arming ----------------------------------------------------------------
    def set_mode(self, name: str) -> int:
        """A commanded mode switch; returns a MAV_RESULT."""
        if name == self.mode:
            return mav.MAV_RESULT_ACCEPTED
        fw = self.fw
        if name == fw.guided_mode and fw.needs_setpoint_stream and not self._setpoints_streaming():
            self.statustext("Offboard: no setpoint stream", mav.MAV_SEVERITY_WARNING)
            return mav.MAV_RESULT_DENIED
        if name in self.fw.command_only_modes:
            return mav.MAV_RESULT_DENIED  # e.g. PX4 TAKEOFF: entered through NAV_TAKEOFF
        self.enter(name)
        return mav.MAV_RESULT_ACCEPTED

    def enter(self, name: str) -> None:
        """Switch to mode `name` (one of `fw.modes`) without a command's checks: what a
        failsafe does."""
        self.mode = name
        self.vel_target = None
        self.land_point = None
        if name == self.fw.guided_mode or name in self.fw.position_hold_modes:
            self.target = self._stopping_point() if self.in_air() else None
            self.target_mask = 0
        if name == "RTL":
            self.rtl_phase = "climb" if self.in_air() else ""
        if name == "LAND" and self.in_air():
            self.landed = mav.MAV_LANDED_STATE_LANDING
        self.statustext(f"Mode {name}")

    def arm(self, force: bool = False) -> int:
        if self.armed:
            return mav.MAV_RESULT_ACCEPTED
        if not force:
            if self.mode not in self.fw.armable_modes:
                self.statustext(f"Arm: mode {self.mode} not armable", mav.MAV_SEVERITY_ERROR)
                return mav.MAV_RESULT_FAILED
            if self._battery_too_low():
                self.statustext("PreArm: battery low", mav.MAV_SEVERITY_ERROR)
                return mav.MAV_RESULT_FAILED
        self.armed = True
        self.motors_on = True
        self.armed_on_ground_since = self.clock()
        self.failsafes = failsafe.FailsafeState()
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

    def _battery_too_low(self) -> bool:
        """Within 5 % of a battery level that makes the vehicle land or return."""
        pct = self.battery - 5.0
        level = self.fw.params.battery(self.params, pct, self.battery_voltage(pct))
        return level is not None and level[1] != "none"

    # --- flight commands ---------------------------------------------------------------
    def takeoff(self, altitude: float | None) -> int:
        """Climb to `altitude` metres above home (NAV_TAKEOFF, already converted; None:
        the takeoff-altitude parameter's)."""
        fw = self.fw
        if altitude is None:
            altitude = self.limits.takeoff_alt
        if not self.armed:
            self.statustext("Takeoff: not armed", mav.MAV_SEVERITY_ERROR)
            return mav.MAV_RESULT_FAILED
        if fw.takeoff_needs_guided and self.mode != fw.guided_mode:
            self.statustext(f"Takeoff: not in {fw.guided_mode}", mav.MAV_SEVERITY_ERROR)
            return mav.MAV_RESULT_FAILED
        if not math.isfinite(altitude) or not 0.0 < altitude <= WORLD_CEILING_M:
            self.statustext(f"Takeoff: bad altitude {altitude}", mav.MAV_SEVERITY_ERROR)
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
        """MAV_CMD_DO_CHANGE_SPEED: 0/1 ground speed, 2 climb, 3 descent; -1 no change,
        -2 back to the parameter's speed."""
        if speed_type not in (0, 1, 2, 3):
            return mav.MAV_RESULT_DENIED
        if speed == -1.0:
            return mav.MAV_RESULT_ACCEPTED  # "no change"
        value: float | None
        if speed == -2.0:
            value = None  # "return to default vehicle speed"
        elif math.isfinite(speed) and speed > 0.0:
            value = speed
        else:
            return mav.MAV_RESULT_DENIED
        if speed_type in (0, 1):
            self.speed_override = value
        elif speed_type == 2:
            self.climb_override = value
        else:
            self.descent_override = value
        what = "default" if value is None else f"{value:.1f} m/s"
        self.statustext(f"Speed set to {what} (type {speed_type})")
        return mav.MAV_RESULT_ACCEPTED

    def reposition(
        self,
        north: float,
        east: float,
        down: float,
        *,
        speed: float | None = None,
        yaw: float | None = None,
        change_mode: bool = True,
    ) -> int:
        """Fly to a local NED point in the firmware's reposition mode (DO_REPOSITION,
        ArduPilot's guided "fly to"); a MAV_RESULT."""
        if not self.armed or not self.in_air() or self.mode == "LAND":
            self.statustext("Reposition: not flying", mav.MAV_SEVERITY_WARNING)
            return mav.MAV_RESULT_DENIED
        if not self._in_world([north, east, down]):
            return mav.MAV_RESULT_DENIED
        mode = self.fw.reposition_mode
        if self.mode != mode:
            if not change_mode:
                return mav.MAV_RESULT_DENIED
            self.enter(mode)
        self.target = [north, east, down]
        self.target_mask = 0
        self.vel_target = None
        if speed is not None:
            self.speed_override = speed
        if yaw is not None and self.fw.reposition_yaw:
            self.yaw_target = _wrap(yaw)
        return mav.MAV_RESULT_ACCEPTED

    def fly_to_global(
        self, lat: float, lon: float, alt: float, relative: bool, *, change_mode: bool
    ) -> bool:
        """`reposition` to a latitude, longitude and altitude (above home if `relative`,
        else AMSL); whether it was accepted."""
        north, east = local_from_global(self.cfg.home, lat, lon)
        down = -alt if relative else self.cfg.home[2] - alt
        result = self.reposition(north, east, down, change_mode=change_mode)
        return result == mav.MAV_RESULT_ACCEPTED

    def land_start(self) -> int:
        """MAV_CMD_DO_LAND_START: fly the stored landing sequence (to its NAV_LAND point,
        then land); FAILED without one, as ArduPilot answers."""
        item = self.missions.landing_sequence()
        if item is None:
            self.statustext("No landing sequence in the mission", mav.MAV_SEVERITY_WARNING)
            return mav.MAV_RESULT_FAILED
        if not self.armed or not self.in_air():
            return mav.MAV_RESULT_DENIED
        point = None
        if item.global_frame and (item.x or item.y):
            point = local_from_global(self.cfg.home, item.x / 1e7, item.y / 1e7)
            if not self._in_world([point[0], point[1], 0.0]):
                return mav.MAV_RESULT_DENIED
        self.enter("LAND")
        self.land_point = point
        self.statustext("Landing sequence")
        return mav.MAV_RESULT_ACCEPTED

    def gcs_heard(self) -> None:
        """A ground station's heartbeat arrived (the GCS-loss failsafe watches these)."""
        self.gcs_heard_at = self.clock()
        self.failsafes.gcs_lost = False

    def _setpoints_streaming(self) -> bool:
        """PX4 enters OFFBOARD once setpoints arrive: one within the loss timeout will do
        (MAVSDK sends one, then starts offboard, then keeps streaming)."""
        timeout = self.fw.params.offboard_loss(self.params, self.cfg).timeout
        last = self.last_setpoint_at
        return last is not None and self.clock() - last <= timeout

    def _stopping_point(self) -> list[float]:
        """Where the vehicle can stop from its current velocity (ArduCopter's brake)."""
        a = max(self.limits.accel, 0.1)
        return [p + v * abs(v) / (2 * a) for p, v in zip(self.pos, self.vel, strict=True)]

    def _in_world(self, target: list[float]) -> bool:
        if not finite(*target):
            return False
        inside = math.hypot(target[0], target[1]) <= WORLD_RADIUS_M
        if not inside or abs(target[2]) > WORLD_CEILING_M:
            self.statustext("Target outside the simulated world", mav.MAV_SEVERITY_WARNING)
            return False
        return True

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
        ignored, as both autopilots do outside their guided mode). A used field that is
        not finite refuses the target; a NaN yaw keeps the heading."""
        use_pos = not mask & IGNORE_POSITION
        use_vel = not mask & IGNORE_VELOCITY
        bad_velocity = use_vel and not use_pos and not finite(*velocity)
        if (use_pos and not finite(*position)) or bad_velocity:
            return
        self.last_setpoint_at = self.clock()
        if not self.guided() or not self.armed:
            return
        if not self.in_air() and not self.fw.setpoint_takes_off:
            return  # ArduCopter needs NAV_TAKEOFF first
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
            if not self._in_world(target):
                return
            if self.fw.setpoint_takes_off and not self.in_air() and target[2] < -0.1:
                self.landed = mav.MAV_LANDED_STATE_TAKEOFF
            self.target = target
            self.target_mask = mask
            self.vel_target = None
        elif use_vel:
            self.vel_target = self._capped_velocity(velocity)
            self.target = None
            self.target_mask = mask
        if not mask & IGNORE_YAW and math.isfinite(yaw):
            self.yaw_target = _wrap(yaw)

    def _capped_velocity(self, velocity: tuple[float, float, float]) -> list[float]:
        """A velocity target within the speed, climb and descent limits."""
        vn, ve, vd = velocity
        horizontal = math.hypot(vn, ve)
        if horizontal > self.speed:
            vn, ve = vn / horizontal * self.speed, ve / horizontal * self.speed
        return [vn, ve, max(-self.climb, min(self.descent, vd))]

    # --- physics ---------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance the vehicle by `dt` seconds."""
        now = self.clock()
        fw = self.fw
        if fw.needs_setpoint_stream and self.guided() and not self._setpoints_streaming():
            rule = fw.params.offboard_loss(self.params, self.cfg)
            self.statustext("Offboard lost", mav.MAV_SEVERITY_WARNING)
            self.act(rule.action)
        if self.armed and self.in_air():
            failsafe.check(self, now)
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

    def act(self, action: str) -> None:
        """Carry out a failsafe action: "none", "hold", "rtl", "land" or "terminate"."""
        if action == "hold":
            self.enter(self.fw.hold_mode)
        elif action == "rtl":
            self.enter("RTL")
        elif action == "land":
            self.enter("LAND")
        elif action == "terminate":
            self.disarm(force=True, reason="flight termination")

    def _desired_velocity(self) -> list[float]:
        mode = self.mode
        if not self.in_air() and self.landed != mav.MAV_LANDED_STATE_TAKEOFF:
            return [0.0, 0.0, 0.0]
        if mode == "LAND":
            return self._land_velocity()
        if mode == "RTL":
            return self._rtl_velocity()
        if self.vel_target is not None and self.guided():
            return list(self.vel_target)
        if self.target is None:
            self.target = self._stopping_point()
        return self._toward(self.target, self.speed)

    def _land_velocity(self) -> list[float]:
        if self.land_point is not None:  # a landing sequence: get there first
            n, e = self.land_point
            if math.hypot(n - self.pos[0], e - self.pos[1]) > 0.3:
                self.target = [n, e, self.pos[2]]
                return self._toward(self.target, self.speed)
            self.land_point = None
        hold = self.target or self._stopping_point()
        self.target = [hold[0], hold[1], 0.0]
        v = self._toward(self.target, self.speed)
        speed = self.limits.land_speed if self.altitude() < 10 else self.descent
        return [v[0], v[1], speed]

    def _rtl_velocity(self) -> list[float]:
        alt = max(failsafe.rtl_altitude(self), self.altitude())
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
        a, k = self.limits.accel, self.cfg.position_gain
        dn, de, dd = (t - p for t, p in zip(target, self.pos, strict=True))
        dist = math.hypot(dn, de)
        out = [0.0, 0.0, 0.0]
        if dist > 1e-6:
            mag = min(speed, math.sqrt(2 * a * dist), k * dist)
            out[0], out[1] = dn / dist * mag, de / dist * mag
        if dd > 0:
            limit = self.descent
        elif self.landed == mav.MAV_LANDED_STATE_TAKEOFF:
            limit = min(self.limits.takeoff_speed, self.climb)
        else:
            limit = self.climb
        mag = min(limit, math.sqrt(2 * a * abs(dd)), k * abs(dd))
        out[2] = math.copysign(mag, dd)
        return out

    def _accelerate(self, desired: list[float], dt: float) -> None:
        a = self.limits.accel
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
            limits = self.limits
            if self.touchdown_since is not None:
                if limits.land_disarm > 0 and now - self.touchdown_since > limits.land_disarm:
                    self.touchdown_since = None
                    self.disarm(reason="landed")
            elif (
                self.armed_on_ground_since is not None
                and limits.disarm_delay > 0
                and now - self.armed_on_ground_since > limits.disarm_delay
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


def _wrap(angle: float) -> float:
    """An angle in radians into [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi
