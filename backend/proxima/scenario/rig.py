"""The parts every scenario assembles, and their orderly shutdown: simulated vehicles
(`proxima sim-drone` processes), MAVLink links, drone controllers on the scenario
clock, live engines on stitched replay streams, the camera views, the flight clock and
the recorders. `Rig.close()` stops everything it started, processes by PID.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from proxima.drone.controller import DroneController
from proxima.drone.heading import HeadingPolicy
from proxima.drone.mavlink import MavlinkLink
from proxima.drone.safety import SafetyConfig, SafetyGate
from proxima.events import EventBus
from proxima.pose import operator_visible
from proxima.scenario.camera import CameraView
from proxima.scenario.clock import FlightClock, install_gate
from proxima.scenario.fleet import SimProcess, free_udp_port, start_sim, stop_all, take_off
from proxima.scenario.record import PathRecorder, TimelineRecorder, telemetry_state
from proxima.store.command_log import CommandLog
from proxima.types import Pose

Progress = Callable[[str, float, float | None], None]  # phase, done, total


class ScenarioError(RuntimeError):
    """The scenario could not be set up (no data, no checkpoint, a vehicle that did not
    start); the message names what is missing."""


@dataclass(frozen=True)
class DroneSpec:
    """One vehicle of a scenario: its name, where its local origin is in the world frame
    (metres, x east, y north, z up; the operator stands at the origin), the direction its
    camera looks (radians, 0 = north; a gimbal pointed at the operator: the vehicles
    themselves keep the heading north they start with), and its hover altitude."""

    name: str
    home: tuple[float, float, float]
    facing: float = 0.0
    altitude_m: float = 2.0
    role: str = ""


def fully_visible(xyz: np.ndarray, visibility: np.ndarray) -> np.ndarray:
    """Per frame, whether `proxima.pose.operator_visible` holds (the FULL sight)."""
    return np.array(
        [
            operator_visible(Pose(t=0.0, xyz=x, visibility=v))
            for x, v in zip(xyz, visibility, strict=True)
        ]
    )


def longest_blink(full: np.ndarray) -> int:
    """The longest run of frames in which the operator is not FULL."""
    best = run = 0
    for f in full:
        run = 0 if f else run + 1
        best = max(best, run)
    return best


def choose_takes(
    clips: Sequence[Any],
    plan: Sequence[tuple[str, float]],
    views: Sequence[str],
    part: str,
    seed: int | None,
    tries: int = 40,
    require_full: bool = True,
    full_views: Sequence[str] | None = None,
    max_blink: int = 0,
) -> tuple[int, dict[str, Any]]:
    """Stitch `plan` for `views`; with `seed` None, the first seed whose streams of
    `full_views` (default: all) see the whole operator (FULL) on every frame but blinks
    of at most `max_blink` frames (if `require_full`), so that only the scenario's own
    camera model takes the feet away. Returns (seed, streams).

    Raises:
        ScenarioError: the plan cannot be stitched, or no seed (or not the given seed)
            meets the condition.
    """
    from proxima.evaluation.stitch import StitchError, stitch_views

    checked = list(full_views) if full_views is not None else list(views)
    seeds = [seed] if seed is not None else list(range(tries if require_full else 1))
    for s in seeds:
        try:
            streams = stitch_views(clips, plan, views=views, part=part, seed=s)
        except StitchError as exc:
            raise ScenarioError(f"cannot stitch the scenario's streams: {exc}") from exc
        if not require_full or all(
            longest_blink(fully_visible(streams[v].xyz, streams[v].visibility)) <= max_blink
            for v in checked
        ):
            return s, streams
    which = f"seed {seed}" if seed is not None else f"any of seeds 0..{tries - 1}"
    raise ScenarioError(
        f"with {which}, the stitched {'/'.join(checked)} streams do not see the whole "
        "operator on every frame (LASER clips lose the feet in places); try another --seed"
    )


class Rig:
    """Owns every running part of one scenario (see the module)."""

    def __init__(self, work_dir: Path, sim_args: Sequence[str] = ()) -> None:
        self.work_dir = work_dir
        self.sim_args = tuple(sim_args)
        self.clock = FlightClock()
        self.timeline = TimelineRecorder(self.clock.now)
        self.specs: dict[str, DroneSpec] = {}
        self.sims: dict[str, SimProcess] = {}
        self.links: dict[str, MavlinkLink] = {}
        self.controllers: list[DroneController] = []
        self.engines: list[Any] = []
        self.views: dict[str, CameraView] = {}
        self.paths: PathRecorder | None = None
        self.stream_start_wall: float | None = None
        self._streaming = False

    # --- vehicles -----------------------------------------------------------------------
    def start_vehicles(self, specs: Sequence[DroneSpec], buses: dict[str, EventBus]) -> None:
        """Start one simulator per drone, connect a link to each (its state events go to
        `buses[name]`) and wait for position telemetry.

        Raises:
            ScenarioError: a simulator did not start or was not heard in time.
        """
        for sysid, spec in enumerate(specs, start=1):
            self.specs[spec.name] = spec
            port = free_udp_port()
            log = self.work_dir / f"sim-{spec.name}.log"
            self.sims[spec.name] = start_sim(spec.name, port, sysid, self.sim_args, log)
        for spec in specs:
            sim = self.sims[spec.name]
            link = MavlinkLink(sim.connection, spec.name, bus=buses.get(spec.name))
            self.links[spec.name] = link
            try:
                link.connect(timeout=20.0)
            except Exception as exc:
                raise ScenarioError(f"{spec.name}: simulator not heard: {exc}") from exc
            ok = link.wait_for(lambda t: t.position is not None and t.landed != "unknown", 10.0)
            if ok is None:
                raise ScenarioError(f"{spec.name}: no position telemetry from the simulator")
        self.clock.track_vehicles(self.links.values())
        self.paths = PathRecorder(self.links, self._path_time).start()

    def _path_time(self) -> float | None:
        return self.clock.now() if self._streaming else None

    def take_off_all(self) -> None:
        """Pre-flight: every vehicle takes off to its altitude (in parallel), as a pilot
        does before handing over to gesture control.

        Raises:
            ScenarioError: a vehicle refused or did not get there.
        """
        errors: list[str] = []

        def one(name: str) -> None:
            try:
                take_off(self.links[name], self.specs[name].altitude_m)
            except RuntimeError as exc:
                errors.append(str(exc))

        threads = [threading.Thread(target=one, args=(n,)) for n in self.links]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        if errors:
            raise ScenarioError("; ".join(errors))
        for name, link in self.links.items():
            tel = link.telemetry()
            self.timeline.add(
                {
                    "t": None,
                    "kind": "preflight",
                    "drone": name,
                    "detail": f"took off to {self.specs[name].altitude_m} m",
                    "position_ned": [round(v, 3) for v in tel.position]
                    if tel and tel.position
                    else None,
                }
            )

    def controller(
        self, names: Sequence[str], bus: EventBus, heading: HeadingPolicy | None = None
    ) -> DroneController:
        """A drone controller for `names` on `bus`, its safety rules on the scenario
        clock, its command log in the work folder, flying moves with `heading`."""
        log = CommandLog(self.work_dir / f"commands-{'-'.join(names)}.db")
        safety = SafetyGate(SafetyConfig(), clock=self.clock.now)
        ctl = DroneController(
            {n: self.links[n] for n in names}, safety=safety, log=log, bus=bus, heading=heading
        )
        ctl.attach(bus)
        self.controllers.append(ctl)
        return ctl

    def camera(self, stream: str, drone: str, tolerance_m: float) -> CameraView:
        """The camera view of `stream`, carried by `drone`, framed from where it hovers."""
        view = CameraView(stream, drone, self.links[drone], tolerance_m=tolerance_m)
        view.set_framing()
        self.views[stream] = view
        return view

    # --- streams ------------------------------------------------------------------------
    def run_engines(
        self,
        engines: Sequence[Any],
        last_t: dict[str, float],
        duration_s: float,
        progress: Progress | None = None,
    ) -> None:
        """Start the engines behind the clock's gate, run them to the end of their
        streams, and let the vehicles settle."""
        self.stream_start_wall = time.monotonic()
        self._streaming = True
        for engine in engines:
            self.engines.append(engine)
            names = {spec.name for spec in engine.specs}
            views = {s: v.apply for s, v in self.views.items() if s in names}
            install_gate(engine, self.clock, last_t, views)
            engine.start()
        while not all(e.wait(0.2) for e in engines):
            if progress:
                progress("flight", self.clock.now(), duration_s)
        if progress:
            progress("settling", self.clock.now(), duration_s)
        self.clock.settle()
        if progress:
            progress("done", duration_s, duration_s)

    # --- results ------------------------------------------------------------------------
    def states(self) -> dict[str, dict[str, Any]]:
        """Each drone's final state (telemetry, link, gesture control, world position)."""
        from proxima.scenario.plot import world_xy

        out: dict[str, dict[str, Any]] = {}
        for name, link in self.links.items():
            spec = self.specs[name]
            state = telemetry_state(link.telemetry(), str(link.state))
            state["gesture_control"] = bool(getattr(link, "gesture_control", False))
            state["role"] = spec.role
            state["sysid"] = self.sims[name].sysid
            state["connection"] = self.sims[name].connection
            state["home_world_enu"] = list(spec.home)
            state["facing_deg"] = round(math.degrees(spec.facing), 1)
            if state.get("position_ned"):
                state["position_world_enu"] = [
                    round(v, 3) for v in world_xy(spec.home, state["position_ned"])
                ]
            view = next((v for v in self.views.values() if v.drone == name), None)
            if view is not None and view.framing is not None:
                state["camera_framing_ned"] = [round(v, 3) for v in view.framing]
            out[name] = state
        return out

    def camera_entries(self) -> list[dict[str, Any]]:
        """The camera framing changes as timeline entries."""
        rows = []
        for view in self.views.values():
            for ch in view.changes:
                rows.append(
                    {
                        "t": round(ch.t, 3),
                        "kind": "view",
                        "stream": ch.stream,
                        "drone": ch.drone,
                        "framed": ch.framed,
                        "offset_m": ch.offset_m,
                        "detail": "whole operator in view"
                        if ch.framed
                        else "feet out of the image (landmarks 27-32 low visibility)",
                    }
                )
        return rows

    def path_series(self) -> dict[str, list[list[float]]]:
        if self.paths is None:
            return {}
        return self.paths.as_time_series(self.stream_start_wall or time.monotonic())

    def run_record(
        self, duration_s: float, t0: float, paths: dict[str, Any], codes: dict[str, int]
    ) -> dict[str, Any]:
        """The timing, flight paths and simulator outcome every scenario result carries."""
        return {
            "timing": {
                "stream_s": round(duration_s, 3),
                "realtime_stream_s": round(self.clock.realtime_s, 3),
                "wall_s": round(time.monotonic() - t0, 3),
                "coordination": "lock-step replay, real time only while a drone moves",
            },
            "paths": paths,
            "simulator_exit_codes": codes,
            "simulator_pids": {n: sim.pid for n, sim in self.sims.items()},
            "work_dir": str(self.work_dir),
        }

    def close(self) -> dict[str, int]:
        """Stop engines, controllers, links and simulators (by PID); the exit codes."""
        for engine in self.engines:
            engine.stop()
        if self.paths is not None:
            self.paths.stop()
        for ctl in self.controllers:
            ctl.close()
        for link in self.links.values():
            link.close()
        return stop_all(list(self.sims.values()))
