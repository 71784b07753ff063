"""The paper's simulation experiment (`proxima scenario sim-two-drones`): two simulated
drones, each flown by recognised gestures to its final position.

Each drone has its own camera and its own decision path (one live engine and one drone
controller per drone, on separate buses, as two ground stations would), and each camera
replays its own operator performance stitched from LASER clips, as the paper's Gazebo
experiment fed a recorded performance to each simulated UAV: uav1 (4 m in front of the
operator, front view) gets have_command, move_to_left, move_upward, wave_off; uav2
(4 m to the operator's left, facing them, left view) gets have_command, move_to_right,
move_ahead, wave_off. The cameras keep the operator framed (no camera model here: with
one camera per drone there is nobody to hand over to). Both vehicles are real
`proxima sim-drone` processes over MAVLink on 127.0.0.1, on one `FlightClock`.
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from proxima.scenario.rig import DroneSpec, Progress, Rig, ScenarioError, choose_takes
from proxima.scenario.verdict import (
    Verdict,
    check_hovering_at,
    check_sequence,
    entries,
    expected_position,
)

UAV1 = DroneSpec("uav1", home=(0.0, -4.0, 0.0), facing=0.0, role="drone 1")
UAV2 = DroneSpec("uav2", home=(4.0, 0.0, 0.0), facing=-math.pi / 2, role="drone 2")
PLANS: dict[str, tuple[tuple[str, float], ...]] = {
    "uav1": (
        ("hover", 4.0),
        ("have_command", 4.0),
        ("move_to_left", 4.0),
        ("move_upward", 4.0),
        ("wave_off", 4.0),
    ),
    "uav2": (
        ("hover", 4.0),
        ("have_command", 4.0),
        ("move_to_right", 4.0),
        ("move_ahead", 4.0),
        ("wave_off", 4.0),
    ),
}
VIEWS = {"uav1": "f", "uav2": "l"}


@dataclass
class TwoDronesConfig:
    """Knobs of the two-drone experiment; the defaults are the documented run."""

    checkpoint: Path | None = None
    data: str | None = None
    part: str = "all"
    seed: int = 0
    altitude_m: float = 2.0
    final_tolerance_m: float = 0.3
    fps: float = 30.0
    work_dir: Path | None = None


def expected_commands(name: str) -> list[tuple[str, str]]:
    """The gesture commands drone `name` must receive (everything after the first hover,
    which comes before arming and sends nothing)."""
    return [(g, name) for g, _ in PLANS[name] if g != "hover"]


def run_two_drones(
    cfg: TwoDronesConfig | None = None, progress: Progress | None = None
) -> dict[str, Any]:
    """Fly both drones and return `timeline`, `drones`, `verdict`, ...

    Raises:
        ScenarioError: the experiment could not be set up (data, model, simulators).
    """
    cfg = cfg or TwoDronesConfig()
    work = cfg.work_dir or Path(tempfile.mkdtemp(prefix="proxima-two-drones-"))
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    if progress:
        progress("loading the model and the clips", 0.0, None)
    from proxima.control import ControlSettings
    from proxima.engine import Engine, EngineSettings, StreamSpec, load_classifier
    from proxima.events import EventBus
    from proxima.gesture.data_source import resolve_laser_dir
    from proxima.gesture.laser import load_laser_dir

    try:
        classifier = load_classifier(cfg.checkpoint)
        clips = load_laser_dir(resolve_laser_dir(cfg.data))
    except (FileNotFoundError, ValueError) as exc:
        raise ScenarioError(str(exc)) from exc
    specs = [
        DroneSpec(UAV1.name, UAV1.home, UAV1.facing, cfg.altitude_m, UAV1.role),
        DroneSpec(UAV2.name, UAV2.home, UAV2.facing, cfg.altitude_m, UAV2.role),
    ]
    csv: dict[str, Path] = {}
    frames: dict[str, int] = {}
    last_t: dict[str, float] = {}  # the replay's time of each stream's last frame
    truth: dict[str, list[dict[str, Any]]] = {}
    duration = 0.0
    for spec in specs:
        view = VIEWS[spec.name]
        _, streams = choose_takes(
            clips, PLANS[spec.name], (view,), cfg.part, cfg.seed, require_full=False
        )
        stream = streams[view]
        csv[spec.name] = work / f"{spec.name}.{view}.csv"
        stream.write(csv[spec.name])
        frames[spec.name] = len(stream.frames)
        last_t[spec.name] = float(stream.frames[-1] - 1) / stream.fps
        truth[spec.name] = [dict(s) for s in stream.truth()["segments"]]
        duration = max(duration, stream.duration_s)

    buses = {spec.name: EventBus() for spec in specs}
    rig = Rig(work)
    for name, bus in buses.items():
        rig.clock.watch(bus)
        rig.timeline.attach(bus, scope=name)
    try:
        if progress:
            progress("starting two simulated drones", 0.0, None)
        rig.start_vehicles(specs, buses)
        if progress:
            progress("take-off", 0.0, None)
        rig.take_off_all()
        starts = {n: link.telemetry() for n, link in rig.links.items()}
        engines = []
        for spec in specs:
            rig.controller([spec.name], buses[spec.name])
            engines.append(
                Engine(
                    [
                        StreamSpec(
                            name=spec.name,
                            uri=f"replay:{csv[spec.name]}@{cfg.fps:g}",
                            drone=spec.name,
                        )
                    ],
                    buses[spec.name],
                    control=ControlSettings(),
                    settings=EngineSettings(),
                    realtime=False,
                    classifier=classifier,
                )
            )
        rig.run_engines(engines, last_t, duration, progress)
        if rig.paths is not None:
            rig.paths.stop()
        states = rig.states()
        timeline = rig.timeline.timeline()
        paths = rig.path_series()
    finally:
        codes = rig.close()

    verdict = Verdict()
    for spec in specs:
        name = spec.name
        start = starts[name]
        assert start is not None and start.position is not None
        gestures = [g for g, _ in expected_commands(name)]
        target = expected_position(start.position, start.yaw, gestures)
        states[name]["start_ned"] = [round(v, 3) for v in start.position]
        states[name]["expected_final_ned"] = [round(v, 3) for v in target]
        mine = [e for e in timeline if e.get("scope") == name]
        check_hovering_at(verdict, name, states[name], target, cfg.final_tolerance_m)
        check_sequence(
            verdict, mine, expected_commands(name), name, {name: truth[name]}, label=f"{name}: "
        )
        safety = [c for c in entries(mine, "command") if not c.get("stream")]
        verdict.check(
            not safety,
            f"{name}: no safety hover (the operator stayed in view, wave_off ended control)",
            f"{name}: the engine hovered the drone (operator lost): {safety}",
        )
    for problem in rig.clock.problems:
        verdict.check(False, "", f"time coordination: {problem}")
    return {
        "scenario": "sim-two-drones",
        "description": (
            "The paper's simulation experiment: two simulated drones, each commanded by "
            "recognised gestures from its own camera to its final position."
        ),
        "timeline": timeline,
        "drones": states,
        "verdict": verdict.to_dict(),
        "scripts": {n: [{"gesture": g, "seconds": s} for g, s in p] for n, p in PLANS.items()},
        "expected_commands": {
            s.name: [{"command": c, "stream": st} for c, st in expected_commands(s.name)]
            for s in specs
        },
        "streams": {
            n: {"csv": str(csv[n]), "view": VIEWS[n], "frames": frames[n], "truth": truth[n]}
            for n in csv
        },
        "settings": {
            "checkpoint": str(cfg.checkpoint) if cfg.checkpoint else "shipped default",
            "part": cfg.part,
            "seed": cfg.seed,
            "altitude_m": cfg.altitude_m,
            "layout_world_enu": {s.name: list(s.home) for s in specs},
        },
        **rig.run_record(duration, t0, paths, codes),
    }
