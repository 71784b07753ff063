"""`create_app`: the console's FastAPI application for one settings object and one bus.

Building the app migrates the database to the newest schema (keeping its rows) and
makes sure a first supervisor exists; the hub binds to the server's loop at start-up.
Every error answers `ErrorOut` (`api/errors.py`); the built frontend is served at `/`,
except under `/api` and `/viser` (the 3D view's proxy), which it never shadows.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Callable, MutableMapping
from contextlib import asynccontextmanager
from typing import Any

from fastapi import FastAPI
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles
from sqlalchemy import Engine as DbEngine
from starlette.routing import Match, Mount
from starlette.types import Scope

from proxima import __version__
from proxima.api.audit import Audit
from proxima.api.auth import VIEW_PATH
from proxima.api.errors import install_error_handlers
from proxima.api.hub import WebSocketHub
from proxima.api.interfaces import EmergencyStop, ModelPromoter, TrainingRunner
from proxima.api.live import LiveState
from proxima.api.recorder import SampleRecorder
from proxima.api.routers import (
    audit,
    auth,
    calibration,
    commands,
    config,
    drones,
    health,
    models,
    samples,
    streams,
    training,
    users,
    view,
    ws,
)
from proxima.api.services import Console
from proxima.api.throttle import LoginThrottle, ThrottlePolicy
from proxima.events import EventBus
from proxima.settings import Settings
from proxima.store import migrations
from proxima.store.audit import AuditLog
from proxima.store.base import make_engine, make_sessionmaker
from proxima.store.users import ensure_first_supervisor

ROUTERS = (
    health.router,
    auth.router,
    users.router,
    config.router,
    streams.router,
    drones.router,
    commands.router,
    samples.router,
    calibration.router,
    training.router,
    models.router,
    audit.router,
    ws.router,
)

API_DESCRIPTION = """The operator console's API. Log in with `POST /api/auth/login`, then send
`Authorization: Bearer TOKEN`; only `/api/health` and the login are open. Every error is an
`ErrorOut`: 401 no valid session, 403 not allowed, 404 no such thing, 409 refused by the
server's state, 422 the request does not match its schema (each problem in `errors`), 429
too many failed logins (`Retry-After`), 503 the subsystem does not run in this server."""


class FrontendMount(Mount):
    """The built frontend at `/`, matching no path under `/api` or `/viser`: those answer
    their own 404 and 405 (as `ErrorOut`, with `Allow`) instead of the file server's."""

    def matches(self, scope: Scope) -> tuple[Match, MutableMapping[str, Any]]:
        path = scope.get("path", "")
        if path in ("/api", VIEW_PATH) or path.startswith(("/api/", f"{VIEW_PATH}/")):
            return Match.NONE, {}
        return super().matches(scope)


_NOT_BUILT = """<!doctype html><title>Proxima</title>
<p>The console's frontend is not built. Run <code>make frontend</code>
(npm install &amp;&amp; npm run build in frontend/), then reload.</p>"""


def _announce_one_time_password(user: str, password: str) -> None:
    print(
        "\n"
        "  First start: created supervisor account\n"
        f"    user:     {user}\n"
        f"    password: {password}   (one-time: you must change it at first login)\n"
        "  Set PROXIMA_ADMIN_USER and PROXIMA_ADMIN_PASSWORD to choose them instead.\n",
        flush=True,
    )


def open_database(
    settings: Settings,
    db_engine: DbEngine | None = None,
    announce: Callable[[str, str], None] = _announce_one_time_password,
) -> DbEngine:
    """The console's database, migrated to the newest schema (rows kept), with a first
    supervisor (from the environment, or a printed one-time password). Idempotent.

    Raises:
        sqlalchemy.exc.SQLAlchemyError: the database cannot be opened or migrated.
    """
    db_engine = db_engine or make_engine(settings.server.db_path)
    migrations.upgrade(db_engine)
    admin_password = settings.admin_password.get_secret_value() if settings.admin_password else None
    with make_sessionmaker(db_engine)() as session:
        created = ensure_first_supervisor(session, settings.admin_user, admin_password)
    if created is not None:
        announce(*created)
    return db_engine


def create_app(
    settings: Settings,
    bus: EventBus,
    *,
    training: TrainingRunner | None = None,
    estop: EmergencyStop | None = None,
    promoter: ModelPromoter | None = None,
    viz_port: int | None = None,
    db_engine: DbEngine | None = None,
    live: LiveState | None = None,
    announce: Callable[[str, str], None] = _announce_one_time_password,
) -> FastAPI:
    """The console app. Subsystems that are not running are passed as None and their
    routes answer 503 with the reason. `live` is the bus listener the snapshots come
    from; pass one made before any publisher started, or a stream's first state (sent
    once) is missed.

    Raises:
        sqlalchemy.exc.SQLAlchemyError: the database cannot be opened or migrated.
    """
    db_engine = open_database(settings, db_engine, announce)
    sessions = make_sessionmaker(db_engine)

    live = live or LiveState(bus)
    console = Console(
        settings=settings,
        bus=bus,
        db_engine=db_engine,
        sessions=sessions,
        hub=WebSocketHub(bus, live),
        live=live,
        recorder=SampleRecorder(bus, sessions),
        audit=Audit(AuditLog(db_engine)),
        throttle=LoginThrottle(
            ThrottlePolicy(
                free_failures=settings.server.login_free_failures,
                base_s=settings.server.login_backoff_s,
                max_s=settings.server.login_backoff_max_s,
            )
        ),
        training=training,
        estop=estop,
        promoter=promoter,
        viz_port=viz_port,
    )

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        console.hub.start()
        yield
        console.hub.stop()
        console.recorder.join(timeout=1.0)

    # No open /docs: the schema is served to logged-in users at /api/openapi.json.
    app = FastAPI(
        title="Proxima console",
        version=__version__,
        description=API_DESCRIPTION,
        lifespan=lifespan,
        openapi_url=None,
        docs_url=None,
        redoc_url=None,
    )
    from proxima.api.alarms import AlarmMonitor

    console.alarms = AlarmMonitor(
        bus,
        settings.server.battery_warn_pct,
        settings.server.battery_critical_pct,
        audit=console.audit,
        geofence_radius_m=settings.safety.geofence_radius_m,
        max_altitude_m=settings.safety.max_altitude_m,
    )
    app.state.console = console
    install_error_handlers(app)
    for router in ROUTERS:
        app.include_router(router, prefix="/api")
    app.include_router(view.router)

    static = settings.static_dir()
    if (static / "index.html").is_file():
        app.router.routes.append(
            FrontendMount("/", app=StaticFiles(directory=static, html=True), name="static")
        )
    else:

        @app.get("/", include_in_schema=False)
        def not_built() -> HTMLResponse:
            return HTMLResponse(_NOT_BUILT, status_code=503)

    return app
