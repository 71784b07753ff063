"""The paper's real-robot experiment, reproduced in simulation (`proxima scenario
paper-flight`).

Two drones watch one operator: the main drone (its camera 4 m in front of the operator,
LASER front view) and the secondary (4 m to the operator's right, LASER right view). The
operator performs hover, have_command, move_to_left; the main drone moves 1 m to its
left and its camera loses the operator's feet (`CameraView`); the secondary's
recognition takes over; the operator performs have_command again, move_to_right and
land, which reach the main drone through the secondary; the main drone lands where it
started.

Everything on the way is the product's own code: stitched replay streams through the
live engine (per-stream recognition, the time-ordered merge, the priority arbiter,
debounce and arming), the drone controller (mapping, safety rules, command log) and
MAVLink links to two `proxima sim-drone` processes on 127.0.0.1. How replay time and
the vehicles' real time are joined is `FlightClock`'s business (see clock.py).
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from proxima.scenario.rig import DroneSpec, Progress, Rig, ScenarioError, choose_takes
from proxima.scenario.verdict import expected_position, judge_paper_flight

# The operator's performance: (gesture, seconds), 0.5 s transitions between them. The
# first hover lasts until the main camera has watched the operator for `regain_s`.
PLAN: tuple[tuple[str, float], ...] = (
    ("hover", 9.0),
    ("have_command", 5.0),
    ("move_to_left", 6.0),
    ("have_command", 6.0),
    ("move_to_right", 3.5),
    ("land", 6.0),
)
# The gesture commands the main drone must receive, and which camera saw each.
EXPECTED: tuple[tuple[str, str], ...] = (
    ("have_command", "main"),
    ("move_to_left", "main"),
    ("have_command", "secondary"),
    ("move_to_right", "secondary"),
    ("land", "secondary"),
)
MAIN = DroneSpec("main", home=(0.0, -4.0, 0.0), facing=0.0, role="main")
SECONDARY = DroneSpec("secondary", home=(-4.0, 0.0, 0.0), facing=math.pi / 2, role="secondary")


@dataclass
class PaperFlightConfig:
    """Knobs of the paper flight; the defaults are the documented run."""

    checkpoint: Path | None = None  # default: the shipped model
    data: str | None = None  # LASER folder (default: resolved as everywhere)
    part: str = "all"  # which rows of each clip to stitch from (see `proxima stitch`)
    seed: int | None = None  # None: the first seed whose takes see the whole operator
    main_view: str = "f"
    secondary_view: str = "r"
    altitude_m: float = 2.0
    tolerance_m: float = 0.3  # camera framing tolerance (CameraView)
    regain_s: float = 8.0  # how long the main camera must see the whole operator to drive
    land_tolerance_m: float = 0.3
    fps: float = 30.0
    work_dir: Path | None = None  # stitched CSVs, simulator logs, command log


def run_paper_flight(
    cfg: PaperFlightConfig | None = None, progress: Progress | None = None
) -> dict[str, Any]:
    """Fly the scenario and return its result: `timeline`, `drones`, `verdict`, ...

    Raises:
        ScenarioError: the scenario could not be set up (data, model, simulators).
    """
    cfg = cfg or PaperFlightConfig()
    work = cfg.work_dir or Path(tempfile.mkdtemp(prefix="proxima-paper-flight-"))
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()

    def say(phase: str) -> None:
        if progress:
            progress(phase, 0.0, None)

    say("loading the model and the clips")
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
    views = (cfg.main_view, cfg.secondary_view)
    seed, streams = choose_takes(clips, PLAN, views, cfg.part, cfg.seed)
    csv: dict[str, Path] = {}
    frames: dict[str, int] = {}
    last_t: dict[str, float] = {}  # the replay's time of each stream's last frame
    for name, view in zip(("main", "secondary"), views, strict=True):
        csv[name] = work / f"{name}.{view}.csv"
        streams[view].write(csv[name])
        frames[name] = len(streams[view].frames)
        last_t[name] = float(streams[view].frames[-1] - 1) / streams[view].fps
    duration = max(s.duration_s for s in streams.values())

    specs = [
        DroneSpec(**{**asdict(MAIN), "altitude_m": cfg.altitude_m}),
        DroneSpec(**{**asdict(SECONDARY), "altitude_m": cfg.altitude_m}),
    ]
    bus = EventBus()
    rig = Rig(work)
    rig.clock.watch(bus)
    rig.timeline.attach(bus)
    try:
        say("starting two simulated drones")
        rig.start_vehicles(specs, {s.name: bus for s in specs})
        say("take-off")
        rig.take_off_all()
        rig.camera("main", "main", cfg.tolerance_m)
        rig.camera("secondary", "secondary", cfg.tolerance_m)
        rig.controller(["main", "secondary"], bus)
        control = ControlSettings(regain_s=cfg.regain_s)
        engine = Engine(
            [
                StreamSpec(name="main", uri=f"replay:{csv['main']}@{cfg.fps:g}", drone="main"),
                StreamSpec(
                    name="secondary",
                    uri=f"replay:{csv['secondary']}@{cfg.fps:g}",
                    drone="secondary",
                ),
            ],
            bus,
            control=control,
            settings=EngineSettings(),
            drone="main",
            realtime=False,
            classifier=classifier,
        )
        rig.run_engines([engine], last_t, duration, progress)
        if rig.paths is not None:
            rig.paths.stop()
        states = rig.states()
        timeline = rig.timeline.timeline() + rig.camera_entries()
        timeline.sort(key=lambda e: e["t"] if e["t"] is not None else -1e9)
        main_tel = rig.links["main"].telemetry()
        paths = rig.path_series()
    finally:
        codes = rig.close()

    framing = rig.views["main"].framing or (0.0, 0.0, 0.0)
    yaw = main_tel.yaw if main_tel is not None else 0.0
    expected_end = expected_position(framing, yaw, [c for c, _ in EXPECTED])
    verdict = judge_paper_flight(
        timeline,
        states["main"],
        expected_end[:2],
        EXPECTED,
        tolerance_m=cfg.land_tolerance_m,
        problems=rig.clock.problems,
        truth={
            name: [dict(seg) for seg in streams[view].truth()["segments"]]
            for name, view in zip(("main", "secondary"), views, strict=True)
        },
    )
    states["main"]["expected_landing_ned"] = [
        round(expected_end[0], 3),
        round(expected_end[1], 3),
        0.0,
    ]
    return {
        "scenario": "paper-flight",
        "description": (
            "The paper's real-robot flight in simulation: the main drone loses the "
            "operator's feet after move_to_left, the secondary drone's recognition "
            "takes over, and have_command, move_to_right and land reach the main drone "
            "through it."
        ),
        "timeline": timeline,
        "drones": states,
        "verdict": verdict.to_dict(),
        "script": [{"gesture": g, "seconds": s} for g, s in PLAN],
        "expected_commands": [{"command": c, "stream": s} for c, s in EXPECTED],
        "streams": {
            name: {
                "csv": str(csv[name]),
                "view": view,
                "frames": frames[name],
                "truth": streams[view].truth()["segments"],
            }
            for name, view in zip(("main", "secondary"), views, strict=True)
        },
        "settings": {
            "checkpoint": str(cfg.checkpoint) if cfg.checkpoint else "shipped default",
            "part": cfg.part,
            "seed": seed,
            "control": control.model_dump(),
            "camera_tolerance_m": cfg.tolerance_m,
            "altitude_m": cfg.altitude_m,
            "layout_world_enu": {s.name: list(s.home) for s in specs},
        },
        **rig.run_record(duration, t0, paths, codes),
    }


__all__ = ["EXPECTED", "PLAN", "PaperFlightConfig", "ScenarioError", "run_paper_flight"]
