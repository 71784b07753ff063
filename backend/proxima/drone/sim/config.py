"""`SimConfig`: everything that makes one simulated vehicle."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class SimConfig:
    """One simulated vehicle: where it sends MAVLink, who it is, how it flies. Defaults
    are ArduCopter-like. The flight limits are the defaults of the autopilot's
    parameters (`param_sets`): a PARAM_SET changes them while it flies."""

    port: int = 14550  # where the ground station listens
    out_ports: tuple[int, ...] = ()  # further ground stations (like SITL's extra --out)
    sysid: int = 1
    host: str = "127.0.0.1"
    autopilot: str = "ardupilot"  # "ardupilot" or "px4"
    rate_hz: float = 10.0  # default telemetry rate
    physics_hz: float = 50.0
    max_speed: float = 5.0  # horizontal m/s (WPNAV_SPEED, MPC_XY_CRUISE)
    max_climb: float = 2.5  # m/s
    max_descent: float = 1.5  # m/s
    max_accel: float = 2.5  # m/s^2, horizontal and vertical
    takeoff_alt: float = 2.5  # m: NAV_TAKEOFF with a NaN altitude (MIS_TAKEOFF_ALT)
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
