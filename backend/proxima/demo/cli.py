"""`proxima demo` (what `make demo` runs): simulated drones, replayed camera streams in a
loop, the console and the 3D view, from the shipped `config/demo.toml` by default."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from proxima.shipped import DEMO_CONFIG, SIM_DEMO_CONFIG, shipped_path

if TYPE_CHECKING:
    from rich.console import Console

    from proxima.demo.runner import Demo
    from proxima.settings import Settings

DEFAULT_CONFIG = shipped_path(DEMO_CONFIG)
SIM_CONFIG = shipped_path(SIM_DEMO_CONFIG)


def register(app: typer.Typer) -> None:
    """Add `proxima demo` to the `proxima` app."""
    app.command("demo")(demo)


def demo(
    config: Annotated[
        Path | None,
        typer.Option(help="TOML settings (the console's format; default config/demo.toml)"),
    ] = None,
    sim: Annotated[
        bool,
        typer.Option("--sim", help="the closed-loop simulator: config/demo-sim.toml (docs/sim.md)"),
    ] = False,
    port: Annotated[int | None, typer.Option(help="console HTTP port (0: any free)")] = None,
    view_port: Annotated[
        int | None, typer.Option(help="viser's own port on 127.0.0.1 (0: any free)")
    ] = None,
    db: Annotated[Path | None, typer.Option(help="SQLite database of the console")] = None,
    checkpoint: Annotated[Path | None, typer.Option(help="gesture model")] = None,
    view: Annotated[bool, typer.Option(help="serve the 3D view (viser)")] = True,
    regenerate: Annotated[
        bool, typer.Option(help="stitch the replayed streams again even if they exist")
    ] = False,
    data: Annotated[str | None, typer.Option(help="LASER data folder")] = None,
) -> None:
    """Start the whole system on its embedded default: a simulated drone per configured
    udpin:127.0.0.1 drone, one replayed camera stream per drone playing the demo script
    in a loop, the console and the 3D view; with --sim, each drone's camera sees the
    simulated operator instead. Ctrl-C (or SIGTERM, SIGHUP) stops every part."""
    import os

    from rich.console import Console

    from proxima.api.server import StopSignals
    from proxima.demo.runner import Demo
    from proxima.demo.streams import DemoStreamError, ensure_replays
    from proxima.gesture.clip import DataError
    from proxima.scenario.rig import ScenarioError
    from proxima.settings import Settings, SettingsError

    out = Console(soft_wrap=True, highlight=False)
    err = Console(stderr=True, soft_wrap=True)
    if sim and config is not None:
        err.print("[red]error:[/red] give --sim or --config, not both")
        raise typer.Exit(2)
    config = config or (SIM_CONFIG if sim else DEFAULT_CONFIG)
    try:
        settings = Settings.load(config)
    except SettingsError as exc:
        err.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    server: dict[str, object] = {"viser_enabled": view}
    if port is not None:
        server["port"] = port
    if view_port is not None:
        server["viser_port"] = view_port
    if db is not None:
        server["db_path"] = db
    update: dict[str, object] = {"server": settings.server.model_copy(update=server)}
    if checkpoint is not None:
        if not checkpoint.is_file():
            err.print(f"[red]error:[/red] {checkpoint}: no such checkpoint")
            raise typer.Exit(2)
        update["engine"] = settings.engine.model_copy(update={"checkpoint": checkpoint})
    settings = settings.model_copy(update=update)
    log_dir = Path(settings.server.db_path).parent

    try:
        with err.status("stitching the replayed camera streams ..."):
            files = ensure_replays(settings, data=data, regenerate=regenerate)
    except (DemoStreamError, DataError, ScenarioError) as exc:
        err.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    for f in files:
        made = "stitched now" if f.generated else "existing"
        out.print(f"stream {f.stream}: replay {f.path} (view {f.view or '?'}, {made})")
    for s in settings.streams:
        if s.kind == "sim":
            out.print(f"stream {s.name}: {s.uri} (simulated camera of drone {s.drone})")

    runner = Demo(settings, log_dir, say=lambda text: out.print(text))
    code = 0
    # SIGINT, SIGTERM and SIGHUP only ask the demo to stop, until everything is stopped.
    with StopSignals(lambda _signum: runner.stop_requested.set()):
        try:
            runner.start()
            if not runner.stop_requested.is_set():
                _announce(out, settings, runner, os.environ)
                runner.wait()
        except Exception as exc:
            err.print(f"[red]error:[/red] {type(exc).__name__}: {exc}")
            code = 1
        finally:
            out.print("stopping: engine, console, 3D view, drone links, simulators ...")
            codes = runner.stop()
            shown = ", ".join(f"{name} exit {c}" for name, c in codes.items()) or "none"
            out.print(f"stopped (simulators: {shown}).")
    raise typer.Exit(code)


def _announce(out: Console, settings: Settings, runner: Demo, env: Mapping[str, str]) -> None:
    """Print where everything is and how to log in."""
    rt = runner.runtime
    url = runner.server.url
    say = out.print
    say("")
    say(f"Proxima demo is running ({len(runner.sims)} simulated drones).")
    say(f"  console:  {url}/")
    if rt.view is not None:
        say(f"  3D view:  {url}/viser/ (through the console, same login)")
    say(f"  health:   {url}/api/health")
    user = env.get("PROXIMA_ADMIN_USER")
    if user:
        say(f"  log in:   user {user!r}, the password in PROXIMA_ADMIN_PASSWORD (first start)")
    else:
        say(
            "  log in:   user 'admin' with the one-time password printed above at first "
            f"start (database {settings.server.db_path}); set PROXIMA_ADMIN_USER and "
            "PROXIMA_ADMIN_PASSWORD before the first start to choose them"
        )
    for note in rt.notes:
        say(f"  note:     {note}")
    say("Ctrl-C stops every part.")
