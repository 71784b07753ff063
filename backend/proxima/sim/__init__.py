"""The closed-loop simulator: a scene shared by the synthetic operator, bystanders and the
simulated drones, whose cameras see the people from where each vehicle really is.

- `scene.py`: `Scene` (people, one clock, what a camera sees), `View`;
- `people.py`: the operator performing a script, bystanders (stand, arms, walk, gestures);
- `mount.py`: `CameraMount`, the camera on a vehicle, placed by its telemetry;
- `noise.py`: the live pose path's measured jitter and visibility noise, per frame;
- `config.py`: scene files (TOML); `uri.py`: `sim:SCENE[?KEY=VALUE&...][#DRONE]`;
- `registry.py`: the scenes and camera-carrying vehicles of this process;
- `source.py`: `SimSource`, a simulated camera as a `FrameSource`.

See docs/sim.md.
"""
