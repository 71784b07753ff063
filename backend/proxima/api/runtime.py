"""Assembling a running console from settings: the event bus, the live engine for the
configured streams, the drone links and their controller, the 3D view and the web app.

Each part is built only when its settings ask for it (streams, drones, viser); a part
that cannot start is reported in `notes` and its routes answer 503 — the console never
pretends. `proxima serve` and the demo use this.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fastapi import FastAPI
from sqlalchemy import Engine as DbEngine

from proxima.api.app import create_app, open_database
from proxima.api.live import LiveState
from proxima.events import EventBus
from proxima.settings import Settings

if TYPE_CHECKING:
    from proxima.api.promote import EnginePromoter
    from proxima.engine import Engine
    from proxima.engine.stream import Classifier
    from proxima.federated.runner import FederatedRunner

log = logging.getLogger(__name__)


@dataclass
class ConsoleRuntime:
    """Every running part of one console process; `close()` stops them in order."""

    settings: Settings
    bus: EventBus
    app: FastAPI
    realtime: bool = True  # file and replay streams paced to their timestamps
    engine: Engine | None = None
    promoter: EnginePromoter | None = None  # follows `engine`
    drones: Any = None  # proxima.drone.controller.DroneController
    links: dict[str, Any] = field(default_factory=dict)
    view: Any = None  # proxima.viz.scene.FleetView
    training: FederatedRunner | None = None
    notes: list[str] = field(default_factory=list)

    def close(self) -> None:
        """Stop every part, Flower's processes first; a part that fails to stop is logged
        and the others are stopped all the same."""
        steps: list[tuple[str, Any]] = []
        if self.training is not None:
            steps.append(("federated runner", self.training.close))
        if self.engine is not None:
            steps.append(("live engine", self.engine.stop))
        if self.drones is not None:
            steps.append(("drone controller", self.drones.close))
        if self.links:
            steps.append(("simulated cameras", lambda: _unregister_cameras(self.links)))
        steps += [(f"drone link {name}", link.close) for name, link in self.links.items()]
        if self.view is not None:
            steps.append(("3D view", self.view.stop))
        for what, stop in steps:
            try:
                stop()
            except Exception:
                log.exception("could not stop the %s", what)

    def restart_engine(self) -> Engine:
        """Stop the live engine and start a fresh one on the same streams (new stream
        time, disarmed) with the classifier the old one ran, so a promoted model stays;
        the thumbnails and the promoter follow. The demo's replay loop uses this.

        Raises:
            RuntimeError: no live engine runs in this console.
        """
        old = self.engine
        if old is None:
            raise RuntimeError("no live engine runs in this console")
        old.stop()
        # The new engine starts disarmed: say so on the bus, so the drones' gesture
        # control and every tile follow (the old engine's last word may be "armed").
        from proxima.events import ArmingEvent

        for spec in old.specs:
            self.bus.publish(
                ArmingEvent(
                    t=0.0,
                    stream=spec.name,
                    armed=False,
                    reason="engine restarted: have_command again",
                )
            )
        # The common model from a stream without one of its own (the promoter puts the
        # streams' own models back when it attaches).
        own = self.promoter.stream_checkpoints() if self.promoter is not None else {}
        common = next((sp.name for sp in old.specs if sp.name not in own), old.specs[0].name)
        engine = start_engine(self.settings, self.bus, self.realtime, old.classifier(common))
        self.engine = engine
        if self.promoter is not None:
            self.promoter.attach(engine)
        return engine


def start_engine(
    settings: Settings, bus: EventBus, realtime: bool, classifier: Classifier | None = None
) -> Engine:
    """The live engine for the configured streams (ranked by priority, then name), with
    thumbnails tapped from the first frame, started. `classifier` replaces
    `settings.engine.checkpoint` for the streams that name no checkpoint of their own.

    Raises:
        FileNotFoundError, ValueError: a checkpoint is missing or not a checkpoint.
    """
    from proxima.engine import Engine

    specs = sorted(settings.streams, key=lambda s: (s.priority, s.name))
    engine = Engine(
        specs,
        bus,
        control=settings.recognition,
        settings=settings.engine,
        realtime=realtime,
        classifier=classifier,
    )
    tap_thumbnails(engine, settings, bus)
    return engine.start()


def tap_thumbnails(engine: Engine, settings: Settings, bus: EventBus) -> list[str]:
    """Publish JPEG thumbnails of every camera stream's frames (at `server.thumbnail_hz`)
    through a frame tap on the engine's stream threads; replayed streams have no pixels
    and get none. Returns the streams tapped."""
    from proxima.api.thumbnails import ThumbnailTap

    running = {spec.name for spec in engine.specs}
    tapped = []
    for s in settings.streams:
        if s.kind != "camera" or s.name not in running:
            continue
        tap = ThumbnailTap(
            bus, s.name, settings.server.thumbnail_hz, settings.server.thumbnail_width
        )
        engine.add_tap(s.name, on_frame=tap)
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


def _start_drones(settings: Settings, bus: EventBus, db: DbEngine, rt: ConsoleRuntime) -> Any:
    from proxima.drone.controller import DroneController, EmergencyStopService
    from proxima.drone.heading import HeadingPolicy
    from proxima.drone.mavlink import MavlinkLink
    from proxima.sim.registry import register_links
    from proxima.store.command_log import CommandLog

    for d in settings.drones:
        link = MavlinkLink(d.connection, d.name, bus=bus)
        rt.links[d.name] = link
        try:
            link.connect(timeout=10.0)
        except Exception as exc:  # the link keeps trying; its state shows "connecting"
            rt.notes.append(f"drone {d.name}: {exc}")
    heading = HeadingPolicy.from_drones(settings.drones, settings.view.operator_position)
    controller = DroneController(
        rt.links, safety=settings.safety, log=CommandLog(db), bus=bus, heading=heading
    )
    controller.attach(bus)
    rt.drones = controller
    register_links(rt.links, settings.drones)  # `sim:SCENE#NAME` sees through their cameras
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
    rt = ConsoleRuntime(settings=settings, bus=bus, app=FastAPI(), realtime=realtime)
    estop = None
    if drones and settings.drones:
        try:
            estop = _start_drones(settings, bus, db, rt)
        except Exception as exc:
            rt.notes.append(f"drone links not started: {type(exc).__name__}: {exc}")
    elif not settings.drones:
        rt.notes.append("no drones configured: emergency stop unavailable")

    if engine and settings.streams:
        try:
            rt.engine = start_engine(settings, bus, realtime)
            from proxima.api.promote import EnginePromoter

            rt.promoter = EnginePromoter(rt.engine, settings.engine.checkpoint)
            from proxima.api.promote import restore_promoted, restore_stream_models
            from proxima.store.audit import AuditLog

            restored = restore_promoted(rt.promoter, AuditLog(db), settings.server.models_dir)
            if restored:
                rt.notes.append(f"live engine runs {restored}, promoted before the restart")
            for item in restore_stream_models(
                rt.promoter, AuditLog(db), settings.server.models_dir
            ):
                rt.notes.append(f"stream {item}, promoted for it before the restart")
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

    if training if training is not None else settings.training.enabled:
        try:
            from proxima.federated.runner import FederatedRunner

            # Runs train models the live engine can take: its window length by default.
            window: dict[str, int] = {}
            if rt.engine is not None:
                window = {"window": rt.engine.classifier(rt.engine.specs[0].name).window}
            defaults = settings.training.run_config(**window)
            rt.training = FederatedRunner(
                settings.server.db_path,
                settings.server.models_dir,
                bus=bus,
                flower_runtime=settings.training.flower_runtime,
                drones=federated_drones(settings),
                defaults=defaults,
                security=settings.training,
            )
        except Exception as exc:
            rt.notes.append(f"federated runner not available: {type(exc).__name__}: {exc}")
    else:
        rt.notes.append("federated training disabled: runs cannot be started")

    rt.app = create_app(
        settings,
        bus,
        training=rt.training,
        estop=estop,
        promoter=rt.promoter,
        viz_port=rt.view.port if rt.view else None,
        db_engine=db,
        live=live,
    )
    return rt


def _unregister_cameras(links: dict[str, Any]) -> None:
    """Forget the drones' cameras `sim:SCENE#NAME` streams looked through."""
    from proxima.sim.registry import unregister_vehicle

    for name in links:
        unregister_vehicle(name)
