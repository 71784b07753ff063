"""The simulated vehicle behind `proxima sim-drone`: an ArduCopter- or PX4-like quadcopter
that speaks MAVLink 2 over UDP the way SITL does.

Modules: `config` (`SimConfig`), `firmware` (what differs between ArduCopter and PX4 on
the vehicle side), `vehicle` (state machine and physics, no I/O), `failsafe` (fence,
battery, ground-station loss), `geo`, `params` and `param_sets` (the parameters and
their protocol), `mission` (the mission protocol), `version` (AUTOPILOT_VERSION), `ftp`
(MAVLink FTP, refused), `handlers` (commands -> vehicle, shared with the in-memory
link), `telemetry` (encoders, rates, message requests), `server` (`VehicleServer`: the
UDP socket, the loop and the table of services). It is the embedded default vehicle and
the test double of the drone link; this project's model of the autopilots' documented
behaviour, not ArduPilot or PX4 themselves.
"""

from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.server import VehicleServer
from proxima.drone.sim.vehicle import Vehicle

__all__ = ["SimConfig", "Vehicle", "VehicleServer"]
