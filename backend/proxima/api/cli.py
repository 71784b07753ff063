"""`proxima serve`: the operator console (web app, WebSocket hub, 3D view) on top of the
live engine and the drone links named in the settings."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer


def register(app: typer.Typer) -> None:
    app.command("serve")(serve)


def serve(
    config: Annotated[
        Path | None,
        typer.Option(help="TOML settings file (default: PROXIMA_CONFIG, else ./proxima.toml)"),
    ] = None,
    host: Annotated[str | None, typer.Option(help="address to bind (default 127.0.0.1)")] = None,
    port: Annotated[int | None, typer.Option(help="HTTP port (default 8000)")] = None,
    db: Annotated[Path | None, typer.Option(help="SQLite database file")] = None,
    engine: Annotated[bool, typer.Option(help="run the live engine for the streams")] = True,
    drones: Annotated[bool, typer.Option(help="connect to the configured drones")] = True,
    view: Annotated[bool | None, typer.Option(help="serve the 3D view (viser)")] = None,
) -> None:
    """Serve the operator console. Log in with PROXIMA_ADMIN_USER / PROXIMA_ADMIN_PASSWORD
    (first start), or with the one-time password printed at first start. SIGINT, SIGTERM
    and SIGHUP stop it and every process it started."""
    import signal

    from rich.console import Console

    from proxima.api.runtime import build_runtime
    from proxima.api.server import ForegroundServer, StopSignals
    from proxima.settings import Settings, SettingsError

    out = Console(stderr=True)
    server: dict[str, object] = {}
    if host is not None:
        server["host"] = host
    if port is not None:
        server["port"] = port
    if db is not None:
        server["db_path"] = db
    try:
        settings = Settings.load(config)
        if server:
            settings = settings.model_copy(
                update={"server": settings.server.model_copy(update=server)}
            )
    except SettingsError as exc:
        out.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    s = settings.server
    with StopSignals() as signals:  # from here on, a signal stops what was started
        runtime = build_runtime(settings, engine=engine, drones=drones, view=view)
        try:
            url = f"{'https' if s.tls else 'http'}://{s.host}:{s.port}/"
            out.print(f"Proxima console: {url}")
            if runtime.view is not None:
                out.print(f"3D view:         {url}viser/ (through the console, same login)")
            for note in runtime.notes:
                out.print(f"[yellow]note:[/yellow] {note}")
            console_server = ForegroundServer(runtime.app, s.host, s.port, s)
            signals.on_stop = console_server.stop
            if signals.received is None:  # else a signal came while starting: stop now
                console_server.run()
        finally:
            out.print("stopping: federated runner, engine, drone links, 3D view ...")
            runtime.close()
    if signals.received is not None:
        out.print(f"stopped on {signal.Signals(signals.received).name}.")
