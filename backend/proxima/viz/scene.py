"""The viser server and its scene: geofence cylinder, ground grid, the operator, one
sphere and trail per drone (the driving drone larger and amber, a lost link red), each
drone's camera frustum and a line of sight from it to the operator coloured by how its
stream sees them (green full, amber partial, grey none); with a simulated scene in this
process (`proxima.sim`), the synthetic operator and the bystanders where they stand.

The server listens on 127.0.0.1 by default (its own port); a thread reads the bus and
redraws at most `view.update_hz` times a second, so the bus never waits on viser.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from proxima.drone.events import DroneStateEvent
from proxima.events import EventBus, HandoverEvent, PoseEvent
from proxima.settings import Settings
from proxima.viz.cameras import (
    SIGHT_COLORS,
    frustum_segments,
    operator_point,
    scene_people,
    sight_line,
)
from proxima.viz.model import SceneModel

COLORS = {
    "driving": (240, 180, 41),
    "idle": (88, 166, 255),
    "lost": (248, 81, 73),
    "trail": (160, 160, 160),
    "operator": (30, 30, 30),
    "operator_lost": (170, 170, 170),
    "fence": (248, 81, 73),
    "frustum": (88, 166, 255),
    "bystander": (120, 120, 200),
}
VIZ_TYPES = tuple(cls.type for cls in (DroneStateEvent, HandoverEvent, PoseEvent))


def geofence_segments(
    radius: float, min_alt: float, max_alt: float, sides: int = 72, posts: int = 12
) -> np.ndarray:
    """The geofence cylinder as (N, 2, 3) line segments: a ring at the lowest and the
    highest allowed altitude and vertical posts between them. Lines keep the scene
    inside the fence readable, where a shaded cylinder would veil it."""
    a = np.linspace(0.0, 2 * np.pi, sides + 1)
    ring = np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1)
    segs = []
    for z in (min_alt, max_alt):
        pts = np.column_stack([ring, np.full(len(ring), z)])
        segs.append(np.stack([pts[:-1], pts[1:]], axis=1))
    b = np.linspace(0.0, 2 * np.pi, posts, endpoint=False)
    foot = np.stack([radius * np.cos(b), radius * np.sin(b)], axis=1)
    lo = np.column_stack([foot, np.full(posts, min_alt)])
    hi = np.column_stack([foot, np.full(posts, max_alt)])
    segs.append(np.stack([lo, hi], axis=1))
    return np.concatenate(segs).astype(np.float32)


# A drone's marker: smaller than the 1 m moves of a gesture, so trails and neighbours
# stay visible (0.4 m across; the driving one 0.5 m). Labels sit above it, each drone's
# a little higher than the one before, so drones side by side do not cover each other's.
DRONE_RADIUS_M = 0.2
DRIVING_SCALE = 1.25
LABEL_Z_M = 0.45
LABEL_STEP_M = 0.35


class FleetView:
    """A running viser scene fed by `bus`. `start()` opens the port; `stop()` closes it."""

    def __init__(self, settings: Settings, bus: EventBus, port: int | None = None) -> None:
        self.settings = settings
        self.bus = bus
        self.model = SceneModel(settings)
        self.host = settings.server.viser_host
        self.port = settings.server.viser_port if port is None else port
        self.server: Any = None
        self._handles: dict[str, Any] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._sub: Any = None
        self._drawn_version = -1

    def start(self) -> FleetView:
        """Start viser and the drawing thread.

        Raises:
            OSError: the port is taken.
        """
        import viser

        self.server = viser.ViserServer(host=self.host, port=self.port, verbose=False)
        self.port = self.server.get_port()
        # No share button (it would offer a public tunnel) and viser's control panel
        # (a developer's: connection, camera, recording) minimised to its bar; the
        # scene carries no controls of ours, the console has them.
        self.server.gui.configure_theme(show_share_button=False, show_logo=False)
        self.server.gui.main_panel.minimize()
        self._static_scene()
        self._sub = self.bus.subscribe(maxsize=2000, types=VIZ_TYPES)
        self._thread = threading.Thread(target=self._run, name="viz", daemon=True)
        self._thread.start()
        return self

    def _static_scene(self) -> None:
        scene = self.server.scene
        safety = self.settings.safety
        radius = safety.geofence_radius_m
        scene.set_up_direction("+z")
        # Stand a little behind and beside the operator, looking at where drones fly.
        ox, oy = self.settings.view.operator_position
        self.server.initial_camera.position = (ox + 6.0, oy - 14.0, 7.0)
        self.server.initial_camera.look_at = (ox, oy - 3.0, 2.0)
        scene.add_grid(
            "/ground",
            width=2 * radius,
            height=2 * radius,
            cell_size=1.0,
            section_size=5.0,
        )
        scene.add_line_segments(
            "/geofence",
            geofence_segments(radius, safety.min_altitude_m, safety.max_altitude_m),
            colors=COLORS["fence"],
            thickness=2.0,
            thickness_units="screen",
        )
        scene.add_label(
            "/geofence/label",
            f"geofence r={radius:g} m",
            position=(radius, 0.0, safety.max_altitude_m / 2),
        )
        base = self.model.operator_base
        scene.add_label("/operator/label", "operator", position=(base[0], base[1], 2.0))

    def _run(self) -> None:
        period = 1.0 / self.settings.view.update_hz
        drawn_at = 0.0
        while not self._stop.is_set():
            event = self._sub.get(timeout=period)
            if event is not None:
                self.model.apply(event)
                for e in self._sub.drain():
                    self.model.apply(e)
            # Redraw on news, and at least once a second: a stream that stopped seeing
            # the operator publishes nothing, yet its line of sight must turn grey.
            if self.model.version != self._drawn_version or time.monotonic() - drawn_at > 1.0:
                self.draw()
                drawn_at = time.monotonic()
                self._stop.wait(period)

    def draw(self) -> None:
        """Push the model's current state to every browser viewing the scene."""
        snap = self.model.snapshot()
        self._drawn_version = snap["version"]
        scene = self.server.scene
        for name, d in snap["drones"].items():
            driving = name == snap["driving_drone"]
            color = (
                COLORS["lost"]
                if d["link"] == "lost"
                else (COLORS["driving"] if driving else COLORS["idle"])
            )
            pos = d["position"] if d["position"] is not None else d["home"]
            key = f"/drones/{name}"
            sphere = self._handles.get(key)
            if sphere is None:
                sphere = scene.add_icosphere(
                    key, radius=DRONE_RADIUS_M, color=color, position=tuple(pos),
                    cast_shadow=False,
                )  # fmt: skip
                self._handles[key] = sphere
                index = sum(
                    k.endswith("/label") and k.startswith("/drones/") for k in self._handles
                )
                self._handles[key + "/label"] = scene.add_label(
                    key + "/label", name, position=(0.0, 0.0, LABEL_Z_M + LABEL_STEP_M * index)
                )
            sphere.position = tuple(float(v) for v in pos)
            sphere.color = color
            sphere.scale = DRIVING_SCALE if driving else 1.0
            trail = d["trail"]
            if len(trail) >= 2:
                segs = np.stack([trail[:-1], trail[1:]], axis=1).astype(np.float32)
                tkey = f"/trails/{name}"
                handle = self._handles.get(tkey)
                if handle is not None:
                    handle.remove()
                self._handles[tkey] = scene.add_line_segments(
                    tkey,
                    segs,
                    colors=color if driving else COLORS["trail"],
                    thickness=3.0,
                    thickness_units="screen",
                )
        sim = self._sim_scene()  # the closed-loop simulator's people, when one runs
        base = self.model.operator_base
        target = operator_point(sim, (base[0], base[1], 1.0))
        for name, d in snap["drones"].items():
            cam = d["camera"]
            if cam is None:
                continue
            self._lines(f"/cameras/{name}/frustum", frustum_segments(cam), COLORS["frustum"], 1.5)
            self._lines(
                f"/cameras/{name}/sight", sight_line(cam, target), SIGHT_COLORS[d["sight"]], 3.0
            )
        people = scene_people(sim) if sim is not None else []
        for name, is_operator, segs in people:
            color = COLORS["operator"] if is_operator else COLORS["bystander"]
            self._lines(f"/people/{name}", segs, color, 4.0 if is_operator else 2.5)
        op = snap["operator"]
        if op is not None and not people:
            handle = self._handles.get("/operator/body")
            if handle is not None:
                handle.remove()
            color = COLORS["operator"] if snap["operator_visible"] else COLORS["operator_lost"]
            self._handles["/operator/body"] = scene.add_line_segments(
                "/operator/body", op, colors=color, thickness=4.0, thickness_units="screen"
            )

    def _lines(self, key: str, segs: np.ndarray, color: tuple[int, int, int], width: float) -> None:
        """Replace the line segments under `key`."""
        handle = self._handles.get(key)
        if handle is not None:
            handle.remove()
        self._handles[key] = self.server.scene.add_line_segments(
            key, segs, colors=color, thickness=width, thickness_units="screen"
        )

    @staticmethod
    def _sim_scene() -> Any:
        """The simulated scene of this process, if any camera looked at one."""
        from proxima.sim.registry import scenes

        return next((s for s in scenes() if s.views()), None)

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5.0)
        if self._sub is not None:
            self._sub.close()
        if self.server is not None:
            self.server.stop()
