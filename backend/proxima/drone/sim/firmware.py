"""What makes the simulated vehicle behave like ArduCopter or like PX4, one object each.

The vehicle's physics and state machine (`vehicle.Vehicle`) are shared; a `Firmware`
says which modes exist and how they are numbered, which hold position, from which the
motors may be armed, how NAV_TAKEOFF's altitude is read, the OFFBOARD rules, its
parameter set (`param_sets`) and what AUTOPILOT_VERSION says. The PX4 one is this
project's model of PX4's documented behaviour, not PX4 itself.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

from proxima.drone.mavlink.protocol import (
    ARDUCOPTER_MODES,
    PX4_MAIN_MODE_AUTO,
    PX4_MODES,
    mav,
    px4_custom_mode,
    px4_main_sub,
)
from proxima.drone.sim.param_sets import PARAM_SETS, ParamSet


class Firmware(ABC):
    """One autopilot's vehicle-side behaviour."""

    name: str  # as `--autopilot` and Telemetry.autopilot name it
    mav_autopilot: int  # HEARTBEAT.autopilot
    modes: tuple[str, ...]  # the modes this vehicle flies
    initial_mode: str
    guided_mode: str  # follows SET_POSITION_TARGET_LOCAL_NED
    # Modes in which the vehicle holds its position (no pilot sticks exist here).
    position_hold_modes: frozenset[str]
    armable_modes: frozenset[str]
    command_only_modes: frozenset[str]  # entered by a command, never by a mode switch
    takeoff_needs_guided: bool  # NAV_TAKEOFF only in `guided_mode`
    takeoff_mode: str | None  # the mode NAV_TAKEOFF switches to, if any ...
    after_takeoff_mode: str | None  # ... and the one it leaves it for at altitude
    setpoint_takes_off: bool  # a guided target above the ground takes off (else ignored)
    # The guided mode needs a setpoint stream: entered only while setpoints arrive, left
    # by the offboard-loss rule (`ParamSet.offboard_loss`) when they stop.
    needs_setpoint_stream: bool
    hold_mode: str  # where a "hold" failsafe action goes (ArduCopter BRAKE, PX4 Hold)
    reposition_mode: str  # DO_REPOSITION flies there (ArduCopter GUIDED, PX4 Hold)
    reposition_yaw: bool  # DO_REPOSITION's param 4 sets the yaw (PX4; ArduCopter ignores it)
    guided_mission_item: bool  # MISSION_ITEM_INT current=2 is a "fly to" (ArduPilot)
    mission_home_item: bool  # mission item 0 is the home position (ArduPilot)
    params: ParamSet
    flight_sw_version: tuple[int, int, int]  # AUTOPILOT_VERSION: the behaviour modelled

    @abstractmethod
    def custom_mode(self, mode: str) -> int:
        """HEARTBEAT.custom_mode of `mode`."""

    @abstractmethod
    def mode_from_params(self, custom_main: int, custom_sub: int) -> str | None:
        """The mode a DO_SET_MODE (params 2 and 3) asks for, None if not flown here."""

    @abstractmethod
    def mode_from_custom(self, custom_mode: int) -> str | None:
        """The mode a SET_MODE message's `custom_mode` asks for, None if not flown here."""

    @abstractmethod
    def takeoff_altitude(self, param7: float, home_amsl: float) -> float:
        """A finite NAV_TAKEOFF param 7 as metres above home."""


class ArduCopter(Firmware):
    """ArduCopter: starts in STABILIZE, takes off from GUIDED with the altitude above
    home, and follows single position targets in GUIDED once airborne."""

    name = "ardupilot"
    mav_autopilot = mav.MAV_AUTOPILOT_ARDUPILOTMEGA
    modes = ("STABILIZE", "ALT_HOLD", "GUIDED", "LOITER", "RTL", "LAND", "POSHOLD", "BRAKE")
    initial_mode = "STABILIZE"
    guided_mode = "GUIDED"
    position_hold_modes = frozenset({"STABILIZE", "ALT_HOLD", "LOITER", "POSHOLD", "BRAKE"})
    armable_modes = frozenset({"STABILIZE", "ALT_HOLD", "GUIDED", "LOITER", "POSHOLD"})
    command_only_modes: frozenset[str] = frozenset()
    takeoff_needs_guided = True
    takeoff_mode = None
    after_takeoff_mode = None
    setpoint_takes_off = False
    needs_setpoint_stream = False
    hold_mode = "BRAKE"
    reposition_mode = "GUIDED"
    reposition_yaw = False
    guided_mission_item = True
    mission_home_item = True
    params = PARAM_SETS["ardupilot"]
    flight_sw_version = (4, 5, 0)

    def custom_mode(self, mode: str) -> int:
        return ARDUCOPTER_MODES[mode]

    def mode_from_params(self, custom_main: int, custom_sub: int) -> str | None:
        for name in self.modes:
            if ARDUCOPTER_MODES[name] == custom_main:
                return name
        return None

    def mode_from_custom(self, custom_mode: int) -> str | None:
        return self.mode_from_params(custom_mode, 0)

    def takeoff_altitude(self, param7: float, home_amsl: float) -> float:
        return param7  # above home


class PX4(Firmware):
    """PX4: starts in Hold (AUTO.LOITER), takes off through AUTO.TAKEOFF with the
    altitude AMSL, and flies OFFBOARD only while setpoints keep coming."""

    name = "px4"
    mav_autopilot = mav.MAV_AUTOPILOT_PX4
    modes = ("MANUAL", "ALTCTL", "POSCTL", "TAKEOFF", "LOITER", "RTL", "LAND", "OFFBOARD")
    initial_mode = "LOITER"
    guided_mode = "OFFBOARD"
    position_hold_modes = frozenset({"MANUAL", "ALTCTL", "POSCTL", "LOITER"})
    armable_modes = frozenset({"MANUAL", "ALTCTL", "POSCTL", "OFFBOARD", "LOITER"})
    command_only_modes = frozenset({"TAKEOFF"})
    takeoff_needs_guided = False
    takeoff_mode = "TAKEOFF"
    after_takeoff_mode = "LOITER"
    setpoint_takes_off = True
    needs_setpoint_stream = True
    hold_mode = "LOITER"
    reposition_mode = "LOITER"
    reposition_yaw = True
    guided_mission_item = False
    mission_home_item = False
    params = PARAM_SETS["px4"]
    flight_sw_version = (1, 15, 0)

    def custom_mode(self, mode: str) -> int:
        _, main, sub = PX4_MODES[mode]
        return px4_custom_mode(main, sub)

    def mode_from_params(self, custom_main: int, custom_sub: int) -> str | None:
        want = (custom_main, custom_sub)
        for name in self.modes:
            code = PX4_MODES[name][1:]
            # AUTO modes are told apart by their sub mode; the others by the main mode.
            if code == want or (code[0] == want[0] and code[0] != PX4_MAIN_MODE_AUTO):
                return name
        return None

    def mode_from_custom(self, custom_mode: int) -> str | None:
        return self.mode_from_params(*px4_main_sub(custom_mode))

    def takeoff_altitude(self, param7: float, home_amsl: float) -> float:
        return param7 - home_amsl  # PX4 sends AMSL


FIRMWARES: dict[str, Firmware] = {f.name: f for f in (ArduCopter(), PX4())}


def firmware_for(autopilot: str) -> Firmware:
    """The firmware model for `autopilot` ("ardupilot" or "px4").

    Raises:
        ValueError: another name.
    """
    try:
        return FIRMWARES[autopilot]
    except KeyError:
        raise ValueError(f"autopilot must be 'ardupilot' or 'px4', got {autopilot!r}") from None
