"""The MAVLink backend: `MavlinkLink` (pymavlink) and what it is made of.

Modules: `protocol` (the MAVLink constants the link and the simulator share), `autopilot`
(ArduPilot and PX4 policies), `actions` (DroneLink commands as MAVLink commands),
`transport` (the owner thread), `acks` (COMMAND_ACK and retries), `telemetry` (decoding),
`setpoint`, `config` (`LinkConfig`), `link` (`MavlinkLink`). Importing this package
imports pymavlink.
"""

from proxima.drone.mavlink.config import LinkConfig
from proxima.drone.mavlink.link import MavlinkLink

__all__ = ["LinkConfig", "MavlinkLink"]
