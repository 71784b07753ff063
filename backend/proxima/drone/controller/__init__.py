"""From a decided command to a vehicle: mapping, safety, link, log, result events.

Modules, one job each: `dispatch` (`DroneController`: the engine's events to one worker
per drone), `execute` (a command into vehicle actions under the safety rules), `record`
(the command log and `CommandResultEvent`s), `outcomes` (watching a sent command until
it is reached, landed or given up), `watchdog` (link lost, operator lost), `estop` (the
two-step emergency stop and the console's `EmergencyStopService`).
"""

from proxima.drone.controller.dispatch import DroneController
from proxima.drone.controller.estop import EmergencyStopService
from proxima.drone.controller.record import ControlOutcome

__all__ = ["ControlOutcome", "DroneController", "EmergencyStopService"]
