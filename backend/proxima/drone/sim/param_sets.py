"""The parameters each simulated autopilot answers, and what the vehicle reads from them.

The set per autopilot is what ground stations and SDKs ask for (MAVSDK: MIS_TAKEOFF_ALT,
MPC_XY_CRUISE, RTL_RETURN_ALT; QGroundControl and MAVProxy: speeds, fence, failsafes),
with the autopilots' own names, units (ArduPilot's centimetres and cm/s) and meanings.
Defaults come from `SimConfig` where it sets the same quantity (so `--max-speed 3` is
WPNAV_SPEED 300 / MPC_XY_CRUISE 3), otherwise they are the autopilot's documented
defaults; where the simulator's default differs from the autopilot's, the spec's doc
says so. Ranges are the autopilots' documented ranges, widened where the simulator's
command line allows more. A parameter with `obeyed=False` is stored and reported but
changes nothing here (no RC receiver exists, a system id change needs a reboot).

Failsafe and fence actions are named: "none" (a warning only), "hold", "rtl", "land",
"terminate" (motors off).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.params import INT8, INT16, INT32, REAL32, ParamSpec, ParamStore


@dataclass(frozen=True)
class Limits:
    """How the vehicle flies (SI units: m, m/s, m/s^2, s)."""

    cruise: float  # horizontal speed of position targets
    climb: float
    descent: float
    accel: float
    land_speed: float  # final descent in LAND
    takeoff_speed: float
    takeoff_alt: float  # NAV_TAKEOFF with a NaN altitude goes here (above home)
    rtl_alt: float
    disarm_delay: float  # armed on the ground without taking off: disarm (0: never)
    land_disarm: float  # landed: disarm after this (0: never)


@dataclass(frozen=True)
class Fence:
    """The active geofence around home: a radius and a ceiling (None: not checked)."""

    radius: float | None
    alt_max: float | None
    action: str


@dataclass(frozen=True)
class LossRule:
    """What the vehicle does when something stops arriving for `timeout` seconds."""

    timeout: float
    action: str


class ParamSet(ABC):
    """One autopilot's parameter names and how the vehicle reads them."""

    bytewise: bool  # PX4 sends integers' bytes in the float field; ArduPilot casts

    @abstractmethod
    def specs(self, cfg: SimConfig) -> list[ParamSpec]:
        """The parameters, in PARAM_VALUE index order, with defaults from `cfg`."""

    def store(self, cfg: SimConfig) -> ParamStore:
        return ParamStore(self.specs(cfg), self.bytewise)

    @abstractmethod
    def limits(self, p: ParamStore, cfg: SimConfig) -> Limits:
        """The flight limits the parameters set (`cfg` for what has no parameter)."""

    @abstractmethod
    def fence(self, p: ParamStore) -> Fence | None: ...

    @abstractmethod
    def battery(self, p: ParamStore, pct: float, volts: float) -> tuple[str, str] | None:
        """The most severe battery level reached, as (level, action), or None."""

    @abstractmethod
    def gcs_loss(self, p: ParamStore) -> LossRule | None:
        """The ground-station-loss failsafe, None when disabled."""

    def offboard_loss(self, p: ParamStore, cfg: SimConfig) -> LossRule:
        """How long a setpoint stream may pause (PX4 OFFBOARD), and what then."""
        return LossRule(cfg.offboard_loss_s, "hold")


# ArduCopter's action numbers, by parameter.
_AC_BATT_ACTIONS = {0: "none", 1: "land", 2: "rtl", 3: "rtl", 4: "land", 5: "terminate"}
_AC_FENCE_ACTIONS = {0: "none", 1: "rtl", 2: "land", 3: "rtl", 4: "hold", 5: "land"}
_AC_GCS_ACTIONS = {1: "rtl", 2: "rtl", 3: "rtl", 4: "land", 5: "land", 6: "rtl", 7: "hold"}
_AC_FENCE_ALT_MAX, _AC_FENCE_CIRCLE = 1, 2  # FENCE_TYPE bits


def _volts(pct: float) -> float:
    """The simulated 4S pack's voltage at `pct` (see Vehicle.battery_voltage)."""
    return round(14.0 + 2.8 * pct / 100.0, 2)


class ArduCopterParams(ParamSet):
    """ArduCopter 4.x names and units (cm, cm/s, V)."""

    bytewise = False

    def specs(self, cfg: SimConfig) -> list[ParamSpec]:
        cm = 100.0
        return [
            ParamSpec("SYSID_THISMAV", INT16, cfg.sysid, 1, 255, "system id", obeyed=False),
            ParamSpec("FRAME_CLASS", INT8, 1, 0, 20, "1: quad", obeyed=False),
            ParamSpec(
                "PILOT_TKOFF_ALT",
                REAL32,
                cfg.takeoff_alt * cm,
                0,
                1000,
                "cm; NAV_TAKEOFF altitude when param7 is NaN (ArduCopter default 0)",
            ),
            ParamSpec("WPNAV_SPEED", REAL32, cfg.max_speed * cm, 10, 2000, "cm/s horizontal"),
            ParamSpec("WPNAV_SPEED_UP", REAL32, cfg.max_climb * cm, 10, 1000, "cm/s climb"),
            ParamSpec("WPNAV_SPEED_DN", REAL32, cfg.max_descent * cm, 10, 500, "cm/s descent"),
            ParamSpec("WPNAV_ACCEL", REAL32, cfg.max_accel * cm, 50, 2000, "cm/s/s"),
            ParamSpec("LAND_SPEED", REAL32, cfg.land_speed * cm, 10, 500, "cm/s final descent"),
            ParamSpec("RTL_ALT", REAL32, cfg.rtl_altitude * cm, 200, 300000, "cm RTL altitude"),
            ParamSpec("FENCE_ENABLE", INT8, 0, 0, 1, "geofence on"),
            ParamSpec("FENCE_TYPE", INT8, 3, 0, 15, "1 ceiling, 2 circle (4 polygon not flown)"),
            ParamSpec("FENCE_RADIUS", REAL32, 300, 30, 10000, "m circle around home"),
            ParamSpec("FENCE_ALT_MAX", REAL32, 100, 10, 1000, "m ceiling above home"),
            ParamSpec("FENCE_ACTION", INT8, 1, 0, 5, "0 report, 1 RTL, 2 land, 4 brake"),
            ParamSpec("FENCE_MARGIN", REAL32, 2, 1, 10, "m", obeyed=False),
            ParamSpec(
                "BATT_LOW_VOLT",
                REAL32,
                _volts(cfg.battery_failsafe_pct),
                0,
                100,
                "V low-battery failsafe (0 off; ArduCopter default 10.5)",
            ),
            ParamSpec("BATT_CRT_VOLT", REAL32, 0, 0, 100, "V critical failsafe (0 off)"),
            ParamSpec(
                "BATT_FS_LOW_ACT", INT8, 1, 0, 5, "1 land, 2 RTL (ArduCopter default 0: none)"
            ),
            ParamSpec("BATT_FS_CRT_ACT", INT8, 0, 0, 5, "1 land, 2 RTL"),
            ParamSpec("FS_GCS_ENABLE", INT8, 0, 0, 7, "GCS-loss failsafe: 1 RTL, 5 land"),
            ParamSpec("FS_GCS_TIMEOUT", REAL32, 5, 2, 120, "s without a GCS heartbeat"),
            ParamSpec("FS_THR_ENABLE", INT8, 0, 0, 7, "RC failsafe (no RC here)", obeyed=False),
            ParamSpec("DISARM_DELAY", INT8, cfg.disarm_delay_s, 0, 127, "s armed on ground"),
        ]

    def limits(self, p: ParamStore, cfg: SimConfig) -> Limits:
        cm = 0.01
        return Limits(
            cruise=p["WPNAV_SPEED"] * cm,
            climb=p["WPNAV_SPEED_UP"] * cm,
            descent=p["WPNAV_SPEED_DN"] * cm,
            accel=p["WPNAV_ACCEL"] * cm,
            land_speed=p["LAND_SPEED"] * cm,
            takeoff_speed=p["WPNAV_SPEED_UP"] * cm,
            takeoff_alt=p["PILOT_TKOFF_ALT"] * cm,
            rtl_alt=p["RTL_ALT"] * cm,
            disarm_delay=p["DISARM_DELAY"],
            land_disarm=cfg.land_disarm_s,  # ArduCopter has no parameter for it
        )

    def fence(self, p: ParamStore) -> Fence | None:
        kind = int(p["FENCE_TYPE"])
        if not p["FENCE_ENABLE"] or not kind & (_AC_FENCE_ALT_MAX | _AC_FENCE_CIRCLE):
            return None
        return Fence(
            p["FENCE_RADIUS"] if kind & _AC_FENCE_CIRCLE else None,
            p["FENCE_ALT_MAX"] if kind & _AC_FENCE_ALT_MAX else None,
            _AC_FENCE_ACTIONS.get(int(p["FENCE_ACTION"]), "rtl"),
        )

    def battery(self, p: ParamStore, pct: float, volts: float) -> tuple[str, str] | None:
        for level, limit, action in (
            ("critical", p["BATT_CRT_VOLT"], p["BATT_FS_CRT_ACT"]),
            ("low", p["BATT_LOW_VOLT"], p["BATT_FS_LOW_ACT"]),
        ):
            if limit > 0 and volts < limit:
                return level, _AC_BATT_ACTIONS.get(int(action), "none")
        return None

    def gcs_loss(self, p: ParamStore) -> LossRule | None:
        action = _AC_GCS_ACTIONS.get(int(p["FS_GCS_ENABLE"]))
        return None if action is None else LossRule(p["FS_GCS_TIMEOUT"], action)


_PX4_FENCE_ACTIONS = {0: "none", 1: "none", 2: "hold", 3: "rtl", 4: "terminate", 5: "land"}
_PX4_DLL_ACTIONS = {1: "hold", 2: "rtl", 3: "land", 5: "terminate", 6: "terminate"}
_PX4_OBL_ACTIONS = {3: "rtl", 4: "land", 6: "terminate", 7: "terminate"}  # else hold


class PX4Params(ParamSet):
    """PX4 1.14+ names and units (m, m/s, battery fractions)."""

    bytewise = True

    def specs(self, cfg: SimConfig) -> list[ParamSpec]:
        fs = cfg.battery_failsafe_pct / 100.0
        return [
            ParamSpec("MAV_SYS_ID", INT32, cfg.sysid, 1, 255, "system id", obeyed=False),
            ParamSpec("MIS_TAKEOFF_ALT", REAL32, cfg.takeoff_alt, 0, 80, "m above home"),
            ParamSpec("MPC_XY_CRUISE", REAL32, cfg.max_speed, 0.1, 20, "m/s horizontal"),
            ParamSpec("MPC_Z_VEL_MAX_UP", REAL32, cfg.max_climb, 0.5, 10, "m/s climb"),
            ParamSpec("MPC_Z_VEL_MAX_DN", REAL32, cfg.max_descent, 0.5, 10, "m/s descent"),
            ParamSpec("MPC_ACC_HOR", REAL32, cfg.max_accel, 0.5, 20, "m/s/s"),
            ParamSpec("MPC_TKO_SPEED", REAL32, cfg.max_climb, 0.5, 10, "m/s takeoff climb"),
            ParamSpec("MPC_LAND_SPEED", REAL32, cfg.land_speed, 0.1, 5, "m/s final descent"),
            ParamSpec("RTL_RETURN_ALT", REAL32, cfg.rtl_altitude, 0, 150, "m (PX4 default 60)"),
            ParamSpec("GF_ACTION", INT32, 2, 0, 5, "2 hold, 3 return, 4 terminate, 5 land"),
            ParamSpec("GF_MAX_HOR_DIST", REAL32, 0, 0, 10000, "m from home (0 off)"),
            ParamSpec("GF_MAX_VER_DIST", REAL32, 0, 0, 10000, "m above home (0 off)"),
            ParamSpec("BAT_LOW_THR", REAL32, 0.15, 0.12, 0.5, "fraction: warning"),
            ParamSpec("BAT_CRIT_THR", REAL32, fs, 0.05, 0.5, "fraction (PX4 default 0.07)"),
            ParamSpec("BAT_EMERGEN_THR", REAL32, min(0.05, fs), 0.03, 0.5, "fraction"),
            ParamSpec(
                "COM_LOW_BAT_ACT", INT32, 2, 0, 3, "2 land at critical (PX4 default 0: warn)"
            ),
            ParamSpec("COM_OF_LOSS_T", REAL32, cfg.offboard_loss_s, 0, 60, "s (PX4 default 1)"),
            ParamSpec("COM_OBL_RC_ACT", INT32, 0, 0, 7, "offboard loss: 3 RTL, 4 land, else hold"),
            ParamSpec("NAV_DLL_ACT", INT32, 0, 0, 6, "GCS loss: 1 hold, 2 RTL, 3 land"),
            ParamSpec("COM_DL_LOSS_T", REAL32, 10, 5, 300, "s without a GCS heartbeat"),
            ParamSpec("COM_RC_LOSS_T", REAL32, 0.5, 0, 35, "s (no RC here)", obeyed=False),
            ParamSpec("COM_DISARM_LAND", REAL32, cfg.land_disarm_s, -1, 20, "s (PX4 default 2)"),
            ParamSpec("COM_DISARM_PRFLT", REAL32, cfg.disarm_delay_s, -1, 20, "s armed on ground"),
        ]

    def limits(self, p: ParamStore, cfg: SimConfig) -> Limits:
        return Limits(
            cruise=p["MPC_XY_CRUISE"],
            climb=p["MPC_Z_VEL_MAX_UP"],
            descent=p["MPC_Z_VEL_MAX_DN"],
            accel=p["MPC_ACC_HOR"],
            land_speed=p["MPC_LAND_SPEED"],
            takeoff_speed=p["MPC_TKO_SPEED"],
            takeoff_alt=p["MIS_TAKEOFF_ALT"],
            rtl_alt=p["RTL_RETURN_ALT"],
            disarm_delay=max(p["COM_DISARM_PRFLT"], 0.0),
            land_disarm=max(p["COM_DISARM_LAND"], 0.0),
        )

    def fence(self, p: ParamStore) -> Fence | None:
        hor, ver = p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"]
        if int(p["GF_ACTION"]) == 0 or (hor <= 0 and ver <= 0):
            return None
        action = _PX4_FENCE_ACTIONS.get(int(p["GF_ACTION"]), "hold")
        return Fence(hor if hor > 0 else None, ver if ver > 0 else None, action)

    def battery(self, p: ParamStore, pct: float, volts: float) -> tuple[str, str] | None:
        fraction, act = pct / 100.0, int(p["COM_LOW_BAT_ACT"])
        if fraction < p["BAT_EMERGEN_THR"]:
            return "emergency", "land" if act in (2, 3) else "none"
        if fraction < p["BAT_CRIT_THR"]:
            return "critical", {2: "land", 3: "rtl"}.get(act, "none")
        if fraction < p["BAT_LOW_THR"]:
            return "low", "none"
        return None

    def gcs_loss(self, p: ParamStore) -> LossRule | None:
        action = _PX4_DLL_ACTIONS.get(int(p["NAV_DLL_ACT"]))
        return None if action is None else LossRule(p["COM_DL_LOSS_T"], action)

    def offboard_loss(self, p: ParamStore, cfg: SimConfig) -> LossRule:
        return LossRule(p["COM_OF_LOSS_T"], _PX4_OBL_ACTIONS.get(int(p["COM_OBL_RC_ACT"]), "hold"))


PARAM_SETS: dict[str, ParamSet] = {"ardupilot": ArduCopterParams(), "px4": PX4Params()}
