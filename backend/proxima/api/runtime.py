"""Assembling a running console from settings: the event bus, the live engine for the
configured streams, the drone links and their controller, the 3D view and the web app.

Each part is built only when its settings ask for it (streams, drones, viser); a part
that cannot start is reported in `notes` and its routes answer 503 — the console never
pretends. `proxima serve` and the demo use this.
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from sqlalchemy import Engine

from proxima.api.app import create_app, open_database
from proxima.api.live import LiveState
from proxima.events import EventBus
from proxima.settings import Settings

log = logging.getLogger(__name__)


def control_settings(settings: Settings) -> Any:
    """The engine's ControlSettings with the overrides set in `settings.recognition`."""
    from proxima.control import ControlSettings

    r = settings.recognition
    names = {
        "filter_window": "filter_size",
        "threshold": "threshold",
        "debounce_s": "debounce_s",
        "arming_timeout_s": "idle_disarm_s",
        "handover_hold_s": "hold_s",
        "confirm": "confirm",
        "confirm_by_command": "confirm_by_command",
        "threshold_by_command": "threshold_by_command",
        "thumb_hand": "thumb_hand",
    }
    overrides = {
        theirs: getattr(r, ours) for ours, theirs in names.items() if getattr(r, ours) is not None
    }
    return ControlSettings(**overrides)


@dataclass
class ConsoleRuntime:
    """Every running part of one console process; `close()` stops them in order."""

    settings: Settings
    bus: EventBus
    app: FastAPI
    engine: Any = None  # proxima.engine.Engine
    drones: Any = None  # proxima.drone.controller.DroneController
    links: dict[str, Any] = field(default_factory=dict)
    view: Any = None  # proxima.viz.scene.FleetView
    training: Any = None  # proxima.federated.runner.FederatedRunner
    notes: list[str] = field(default_factory=list)

    def close(self) -> None:
        if self.training is not None:
            self.training.close()
        if self.engine is not None:
            self.engine.stop()
        if self.drones is not None:
            self.drones.close()
        for link in self.links.values():
            link.close()
        if self.view is not None:
            self.view.stop()


def _start_engine(settings: Settings, bus: EventBus, realtime: bool) -> Any:
    from proxima.engine import Engine, EngineSettings, StreamSpec

    specs = [
        StreamSpec(name=s.name, uri=s.uri, drone=s.drone)
        for s in sorted(settings.streams, key=lambda s: (s.priority, s.name))
    ]
    engine_settings = (
        EngineSettings(stride=settings.recognition.stride)
        if settings.recognition.stride is not None
        else EngineSettings()
    )
    engine = Engine(
        specs,
        bus,
        control=control_settings(settings),
        settings=engine_settings,
        realtime=realtime,
        checkpoint=settings.recognition.checkpoint,
    )
    engine.start()
    tap_thumbnails(engine, settings, bus)
    return engine


def tap_thumbnails(engine: Any, settings: Settings, bus: EventBus) -> list[str]:
    """Publish JPEG thumbnails of every camera stream's frames (at `server.thumbnail_hz`)
    from the engine's stream threads; replayed streams have no pixels and get none.
    Returns the streams tapped.

    The engine has no frame hook, so each camera pipeline's `process` is wrapped: the
    thumbnail is offered the frame, then the pipeline runs as before.
    """
    from proxima.api.thumbnails import ThumbnailTap

    tapped = []
    for s in settings.streams:
        pipeline = engine.pipelines.get(s.name)
        if s.kind != "camera" or pipeline is None:
            continue
        tap = ThumbnailTap(
            bus, s.name, settings.server.thumbnail_hz, settings.server.thumbnail_width
        )
        original = pipeline.process

        def process(frame: Any, _original: Any = original, _tap: ThumbnailTap = tap) -> Any:
            with contextlib.suppress(ValueError):  # an odd frame never stops recognition
                _tap.offer(frame)
            return _original(frame)

        pipeline.process = process
        tapped.append(s.name)
    return tapped


def federated_drones(settings: Settings) -> list[Any] | None:
    """One federated client per configured drone, named like it, so the samples labelled
    for a drone in the console join that drone's local data; partition i of n (with the
    default view partition and three drones: one camera view each). None (the runner's
    default fleet) when fewer than two drones are configured."""
    if len(settings.drones) < 2:
        return None
    from proxima.federated.deploy import Drone

    n = len(settings.drones)
    db = str(Path(settings.server.db_path).resolve())
    return [Drone(d.name, i, n, samples_db=db) for i, d in enumerate(settings.drones)]


def _start_drones(settings: Settings, bus: EventBus, db: Engine, rt: ConsoleRuntime) -> Any:
    from proxima.drone.controller import DroneController, EmergencyStopService
    from proxima.drone.mavlink import MavlinkLink
    from proxima.drone.safety import SafetyConfig
    from proxima.store.command_log import CommandLog

    for d in settings.drones:
        link = MavlinkLink(d.connection, d.name, bus=bus)
        rt.links[d.name] = link
        try:
            link.connect(timeout=10.0)
        except Exception as exc:  # the link keeps trying; its state shows "connecting"
            rt.notes.append(f"drone {d.name}: {exc}")
    controller = DroneController(
        rt.links, safety=SafetyConfig.from_settings(settings), log=CommandLog(db), bus=bus
    )
    controller.attach(bus)
    rt.drones = controller
    return EmergencyStopService(controller)


def build_runtime(
    settings: Settings,
    *,
    bus: EventBus | None = None,
    engine: bool = True,
    drones: bool = True,
    view: bool | None = None,
    realtime: bool = True,
    training: bool | None = None,
) -> ConsoleRuntime:
    """Start every configured part and build the app (serve it with uvicorn).

    Raises:
        sqlalchemy.exc.SQLAlchemyError: the database cannot be opened or migrated.
    """
    bus = bus or EventBus()
    db = open_database(settings)  # first: every other part writes to it
    # Listening before anything publishes: stream and link states are sent on change only.
    live = LiveState(bus)
    rt = ConsoleRuntime(settings=settings, bus=bus, app=FastAPI())
    estop = None
    if drones and settings.drones:
        try:
            estop = _start_drones(settings, bus, db, rt)
        except Exception as exc:
            rt.notes.append(f"drone links not started: {type(exc).__name__}: {exc}")
    elif not settings.drones:
        rt.notes.append("no drones configured: emergency stop unavailable")

    promoter = None
    if engine and settings.streams:
        try:
            rt.engine = _start_engine(settings, bus, realtime)
            from proxima.api.promote import EnginePromoter

            promoter = EnginePromoter(rt.engine, settings.recognition.checkpoint)
        except Exception as exc:
            rt.notes.append(f"live engine not started: {type(exc).__name__}: {exc}")
    elif not settings.streams:
        rt.notes.append("no streams configured: the Live page stays empty")

    if view if view is not None else settings.server.viser_enabled:
        try:
            from proxima.viz.scene import FleetView

            rt.view = FleetView(settings, bus).start()
        except Exception as exc:
            rt.notes.append(f"3D view not started: {type(exc).__name__}: {exc}")

    runner = None
    if training if training is not None else settings.training.enabled:
        try:
            from proxima.federated.runner import FederatedRunner

            runner = FederatedRunner(
                settings.server.db_path,
                settings.server.models_dir,
                bus=bus,
                engine=settings.training.engine,
                drones=federated_drones(settings),
            )
            rt.training = runner
        except Exception as exc:
            rt.notes.append(f"federated runner not available: {type(exc).__name__}: {exc}")
    else:
        rt.notes.append("federated training disabled: runs cannot be started")

    rt.app = create_app(
        settings,
        bus,
        training=runner,
        estop=estop,
        promoter=promoter,
        viz_port=rt.view.port if rt.view else None,
        db_engine=db,
        live=live,
    )
    return rt
