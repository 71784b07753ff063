"""The drone link: MAVLink to ArduPilot/PX4 vehicles, the simulated quadcopter, the
gesture -> command mapping and the flight-safety rules (see docs/drone.md).

Modules: `link` (the DroneLink interface), `mavlink_link` (pymavlink implementation),
`sim_vehicle` (`proxima sim-drone`), `mapping` (+ `mapping.toml`), `safety`,
`controller` (CommandEvent -> vehicle, with the command log), `events`, `commands` (CLI).
Nothing is imported here, so `proxima --help` stays fast.
"""
