"""`LinkConfig`: the timing of one MAVLink link."""

from __future__ import annotations

from dataclasses import dataclass


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
