"""`proxima sim-drone` (a simulated MAVLink quadcopter) and `proxima drone-cmd` (one
command to a vehicle from the shell). pymavlink is imported inside the command bodies."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    from rich.console import Console

    from proxima.drone.link import CommandResult, Telemetry
    from proxima.drone.mavlink import MavlinkLink

DRONE_ACTIONS = (
    "status",
    "guided",
    "mode",
    "arm",
    "disarm",
    "takeoff",
    "goto",
    "hold",
    "speed",
    "land",
    "gesture",
)


def register(app: typer.Typer) -> None:
    app.command("sim-drone")(sim_drone)
    app.command("drone-cmd")(drone_cmd)


def sim_drone(
    port: Annotated[
        int,
        typer.Option(
            help="UDP port on 127.0.0.1 where the ground station "
            "listens (it connects with udpin:127.0.0.1:PORT)"
        ),
    ] = 14550,
    sysid: Annotated[int, typer.Option(help="MAVLink system id, 1..255")] = 1,
    autopilot: Annotated[
        str, typer.Option(help="ardupilot (ArduCopter-like) or px4")
    ] = "ardupilot",
    out_port: Annotated[
        list[int] | None, typer.Option(help="another ground-station port (repeatable)")
    ] = None,
    rate: Annotated[float, typer.Option(help="telemetry rate in Hz")] = 10.0,
    max_speed: Annotated[float, typer.Option(help="horizontal speed limit, m/s")] = 5.0,
    max_accel: Annotated[float, typer.Option(help="acceleration limit, m/s^2")] = 2.5,
    max_climb: Annotated[float, typer.Option(help="climb rate limit, m/s")] = 2.5,
    land_speed: Annotated[float, typer.Option(help="descent speed in LAND, m/s")] = 0.5,
    home: Annotated[str, typer.Option(help="home LAT,LON,ALT_AMSL")] = "50.0755,14.4378,300",
    battery: Annotated[float, typer.Option(help="battery at start, percent")] = 100.0,
    loss: Annotated[float, typer.Option(help="drop this fraction of incoming packets")] = 0.0,
    seed: Annotated[int, typer.Option(help="random seed of --loss")] = 0,
) -> None:
    """Run a simulated ArduCopter-like quadcopter speaking MAVLink 2 over UDP until
    Ctrl-C or SIGTERM. Several can run side by side with their own --port and --sysid."""
    import signal
    import threading

    from proxima.drone.sim import SimConfig, VehicleServer

    if not 1 <= port <= 65535:
        raise typer.BadParameter(f"--port must be 1..65535, got {port}")
    if not 1 <= sysid <= 255:
        raise typer.BadParameter(f"--sysid must be 1..255, got {sysid}")
    if autopilot not in ("ardupilot", "px4"):
        raise typer.BadParameter(f"--autopilot must be ardupilot or px4, got {autopilot!r}")
    for name, value in (
        ("--rate", rate),
        ("--max-speed", max_speed),
        ("--max-accel", max_accel),
        ("--max-climb", max_climb),
        ("--land-speed", land_speed),
    ):
        if not value > 0:
            raise typer.BadParameter(f"{name} must be positive, got {value}")
    if not 0.0 <= loss < 1.0:
        raise typer.BadParameter(f"--loss must be in [0, 1), got {loss}")
    try:
        lat, lon, alt = (float(x) for x in home.split(","))
    except ValueError:
        msg = f"--home must be LAT,LON,ALT (three numbers), got {home!r}"
        raise typer.BadParameter(msg) from None
    cfg = SimConfig(
        port=port,
        sysid=sysid,
        autopilot=autopilot,
        out_ports=tuple(out_port or ()),
        rate_hz=rate,
        max_speed=max_speed,
        max_accel=max_accel,
        max_climb=max_climb,
        land_speed=land_speed,
        home=(lat, lon, alt),
        battery_pct=battery,
        loss=loss,
        seed=seed,
    )
    vehicle = VehicleServer(cfg)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    typer.echo(
        f"sim-drone sysid {sysid} ({autopilot}) sending to 127.0.0.1:{port}; "
        f"connect with udpin:127.0.0.1:{port}. Ctrl-C stops."
    )
    vehicle.run(stop)
    typer.echo(f"sim-drone sysid {sysid} stopped")


def drone_cmd(
    action: Annotated[str, typer.Argument(help=f"one of: {', '.join(DRONE_ACTIONS)}")],
    args: Annotated[list[str] | None, typer.Argument(help="the action's values")] = None,
    connect: Annotated[str, typer.Option(help="MAVLink connection string")] = (
        "udpin:127.0.0.1:14550"
    ),
    name: Annotated[str, typer.Option(help="the drone's name in logs and events")] = "drone",
    timeout: Annotated[float, typer.Option(help="seconds to wait for the vehicle")] = 10.0,
    db: Annotated[Path | None, typer.Option(help="SQLite command log to write")] = None,
    mapping: Annotated[Path | None, typer.Option(help="gesture mapping TOML")] = None,
    wait: Annotated[bool, typer.Option(help="wait for the outcome (altitude, arrival)")] = True,
    json_out: Annotated[bool, typer.Option("--json", help="print the result as JSON")] = False,
) -> None:
    """Send one command to a vehicle and print what it answered.

    Actions: status, guided, mode NAME, arm, disarm, disarm force, takeoff ALT,
    goto N E D, hold, speed M_S, land, gesture NAME (through the gesture mapping and the
    safety rules, with gesture control armed by you: the person typing is the operator).
    """
    from rich.console import Console

    from proxima.drone.link import LinkError
    from proxima.drone.mavlink import MavlinkLink

    console = Console(stderr=True)
    values = list(args or [])
    if action not in DRONE_ACTIONS:
        raise typer.BadParameter(f"unknown action {action!r}; one of {', '.join(DRONE_ACTIONS)}")
    numbers = _numbers(action, values)
    link = MavlinkLink(connect, name)
    try:
        with console.status(f"waiting for a heartbeat on {connect} ..."):
            link.connect(timeout)
        link.wait_for(lambda t: t.position is not None and t.landed != "unknown", 2.0)
        out: dict = {}
        if action == "status":
            pass
        elif action == "gesture":
            out = _gesture(link, name, values[0], mapping, db, wait, console)
        else:
            result: CommandResult = _direct(link, action, values, numbers)
            out = result.to_dict()
            if result.ok and wait and action in ("takeoff", "goto", "land"):
                out["outcome"] = _wait_outcome(link, action, numbers, console)
        tel = link.telemetry()
        out["telemetry"] = _telemetry_dict(tel)
        if json_out:
            typer.echo(json.dumps(out, default=str))
        else:
            _print(console, action, out)
        ok = out.get("ok", True) and out.get("status", "sent") in ("sent", "done")
        raise typer.Exit(0 if ok else 1)
    except LinkError as exc:
        console.print(f"[red]{exc}[/red]")
        raise typer.Exit(1) from None
    finally:
        link.close()


def _numbers(action: str, values: list[str]) -> list[float]:
    need = {"takeoff": 1, "goto": 3, "speed": 1, "mode": 1, "gesture": 1}
    want = need.get(action, 0)
    if action == "disarm" and values not in ([], ["force"]):
        raise typer.BadParameter("disarm takes nothing or 'force'")
    if action in need and len(values) != want:
        raise typer.BadParameter(f"{action} needs {want} value(s), got {values}")
    if action in ("mode", "gesture", "disarm"):
        return []
    try:
        return [float(v) for v in values]
    except ValueError:
        raise typer.BadParameter(f"{action} needs numbers, got {values}") from None


def _direct(
    link: MavlinkLink, action: str, values: list[str], numbers: list[float]
) -> CommandResult:
    if action == "guided":
        return link.enter_guided()
    if action == "mode":
        return link.set_mode(values[0])
    if action == "arm":
        return link.arm()
    if action == "disarm":
        return link.disarm(force=values == ["force"])
    if action == "takeoff":
        return link.takeoff(numbers[0])
    if action == "goto":
        north, east, down = numbers
        return link.goto_local(north, east, down)
    if action == "hold":
        return link.hold()
    if action == "speed":
        return link.change_speed(numbers[0])
    return link.land()


def _wait_outcome(link: MavlinkLink, action: str, numbers: list[float], console: Console) -> str:
    """Follow the vehicle with a progress bar until the action's outcome is known."""
    import time

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.types import LinkState

    tel = link.telemetry()
    height = (tel.altitude if tel else None) or 0.0
    if action == "land":
        total, limit, outcome = max(height, 0.1), 60.0 + height / 0.3, "landed"
    elif action == "takeoff":
        total, limit, outcome = numbers[0], 30.0 + numbers[0], "reached"
    else:
        target = (numbers[0], numbers[1], numbers[2])
        first = tel.distance_to(target) if tel else 0.0
        total, limit, outcome = max(first, 0.1), 30.0 + first, "reached"

    def progress(t: Telemetry) -> tuple[float, bool]:
        if action == "land":
            return height - (t.altitude or 0.0), not t.armed and t.landed == "on_ground"
        if action == "takeoff":
            alt = t.altitude or 0.0
            return alt, t.landed == "in_air" and abs(alt - numbers[0]) < 0.15
        dist = t.distance_to(target)
        return total - dist, dist < 0.2

    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.completed:.1f}/{task.total:.1f} m"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(action, total=total)
        deadline = time.monotonic() + limit
        while time.monotonic() < deadline:
            t = link.telemetry()
            if t is not None:
                done, finished = progress(t)
                bar.update(task, completed=max(0.0, min(total, done)))
                if finished:
                    return outcome
            if link.state == LinkState.LOST:
                return "link_lost"
            time.sleep(0.05)
    return f"not_{outcome}"


def _gesture(
    link: MavlinkLink,
    name: str,
    gesture: str,
    mapping: Path | None,
    db: Path | None,
    wait: bool,
    console: Console,
) -> dict[str, Any]:
    """One gesture through the mapping and the safety rules, as the operator."""
    import time

    from proxima.drone.controller import DroneController
    from proxima.drone.mapping import load_mapping
    from proxima.events import CommandEvent
    from proxima.store.command_log import CommandLog

    log = CommandLog(db) if db is not None else None
    controller = DroneController({name: link}, mapping=load_mapping(mapping), log=log)
    try:
        controller.safety.arm_control(name)
        event = CommandEvent(t=time.time(), stream="cli", command=gesture, drone=name)
        outcome = controller.handle(event, source="cli")
        out: dict[str, Any] = {
            "status": outcome.status,
            "action": outcome.action,
            "reason": outcome.reason,
            "log_id": outcome.log_id,
            "target": outcome.target,
            "result": outcome.result.to_dict() if outcome.result else None,
        }
        target = outcome.target
        if wait and outcome.status == "sent" and target is not None:
            with console.status("flying to the target ..."):
                tel = link.wait_for(lambda t: t.distance_to(target) < 0.2, 30.0)
            out["outcome"] = "reached" if tel is not None else "not_reached"
        return out
    finally:
        controller.close()


def _telemetry_dict(tel: Telemetry | None) -> dict[str, Any] | None:
    if tel is None:
        return None
    return {
        "system_id": tel.system_id,
        "autopilot": tel.autopilot,
        "mode": tel.mode,
        "armed": tel.armed,
        "landed": tel.landed,
        "position": tel.position,
        "attitude": tel.attitude,
        "battery_pct": tel.battery_pct,
        "global_position": tel.global_position,
    }


def _print(console: Console, action: str, out: dict[str, Any]) -> None:
    from rich.table import Table

    table = Table(title=f"drone-cmd {action}", show_header=False)
    for key, value in out.items():
        if key == "telemetry" and isinstance(value, dict):
            for k, v in value.items():
                table.add_row(k, _fmt(v, 7 if k == "global_position" else 3))
        else:
            table.add_row(key, _fmt(value))
    console.print(table)


def _fmt(value: object, digits: int = 3) -> str:
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_fmt(v, digits) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)
