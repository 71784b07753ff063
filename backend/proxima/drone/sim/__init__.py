"""The simulated vehicle behind `proxima sim-drone`: an ArduCopter- or PX4-like quadcopter
that speaks MAVLink 2 over UDP the way SITL does.

Modules: `config` (`SimConfig`), `firmware` (what differs between ArduCopter and PX4 on
the vehicle side), `vehicle` (state machine and physics, no I/O), `handlers` (commands
-> vehicle, shared with the in-memory link), `telemetry` (encoders and rates), `server`
(`VehicleServer`: the UDP socket and the loop). It is the embedded default vehicle and
the test double of the drone link; this project's model of the autopilots' documented
behaviour, not ArduPilot or PX4 themselves.
"""

from proxima.drone.sim.config import SimConfig
from proxima.drone.sim.server import VehicleServer
from proxima.drone.sim.vehicle import Vehicle

__all__ = ["SimConfig", "Vehicle", "VehicleServer"]
