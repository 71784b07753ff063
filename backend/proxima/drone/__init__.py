"""The drones: the DroneLink interface and its backends, the simulated quadcopter, the
gesture -> command mapping, the flight-safety rules and the controller (see docs/drone.md).

`link` (DroneLink, Telemetry, CommandResult), `events`, `mapping` (+ `mapping.toml`),
`safety`, `controller/` (CommandEvent -> vehicle, with the command log), `mavlink/` (the
MAVLink backend), `memory/` (the in-process backend for tests), `sim/` (`proxima
sim-drone`), `cli` (the `sim-drone` and `drone-cmd` commands). Nothing is imported here,
so `proxima --help` stays fast.
"""
