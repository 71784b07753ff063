"""`proxima recognize`: run one stream, write every event as JSON lines."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    from proxima.engine.record import SessionRecorder
    from proxima.engine.runner import Engine


def register(app: typer.Typer) -> None:
    """Add the engine's commands to the `proxima` app."""
    app.command("recognize")(recognize)


def _recorder(
    engine: Engine, folder: Path, fps: float | None, source: str, checkpoint: Path | None
) -> SessionRecorder:
    """The session recorder of `--record` (a replay records at its own rate)."""
    from proxima.engine.record import SessionRecorder
    from proxima.ingest import DEFAULT_REPLAY_FPS, parse_replay_uri

    if fps is None:
        fps = DEFAULT_REPLAY_FPS
        if source.startswith("replay:"):
            fps = parse_replay_uri(source.removeprefix("replay:"))[1]
    info = {"command": "proxima recognize", "source": source, "checkpoint": checkpoint}
    return SessionRecorder(engine, folder, fps, info)


def recognize(
    source: Annotated[
        str,
        typer.Option(
            help="webcam:N, file:PATH, rtsp://HOST/PATH, replay:PATH[@FPS] or "
            "sim:SCENE[?KEY=VALUE&...] (docs/sim.md)"
        ),
    ],
    events: Annotated[Path, typer.Option(help="write every event here, one JSON per line")],
    checkpoint: Annotated[
        Path | None, typer.Option(help="gesture model (default: the shipped gesture-default.pt)")
    ] = None,
    name: Annotated[str, typer.Option(help="stream name in the events")] = "main",
    drone: Annotated[str, typer.Option(help="drone the commands go to (default: NAME)")] = "",
    realtime: Annotated[
        bool, typer.Option(help="pace file/replay sources to their timestamps")
    ] = False,
    stride: Annotated[int | None, typer.Option(help="classify every N frames")] = None,
    threshold: Annotated[float | None, typer.Option(help="filtered confidence needed")] = None,
    debounce_s: Annotated[float | None, typer.Option(help="least seconds between commands")] = None,
    idle_disarm_s: Annotated[float | None, typer.Option(help="disarm after idle seconds")] = None,
    pose_every: Annotated[int, typer.Option(help="write a pose event every N frames")] = 1,
    pose_model: Annotated[Path | None, typer.Option(help="MediaPipe pose model")] = None,
    record: Annotated[
        Path | None,
        typer.Option(
            help="record the session here: the operator's poses as a replay CSV "
            "(NAME.csv), the events (events.jsonl) and session.json with its replay URI"
        ),
    ] = None,
    record_fps: Annotated[
        float | None,
        typer.Option(help="frame rate of the recording (default: a replay's own, else 30)"),
    ] = None,
) -> None:
    """Recognise gestures in one stream until it ends (or Ctrl-C) and write every event
    (pose, gesture, action, arming, handover, command, stream) as JSON lines, with `t` in
    stream seconds. Commands are what would be sent to the drone; nothing is sent.
    With --record DIR the session can be replayed: `--source replay:DIR/NAME.csv@FPS`."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.control import ControlSettings
    from proxima.engine.config import EngineSettings, StreamSpec
    from proxima.engine.jsonl import JsonlWriter
    from proxima.engine.runner import Engine
    from proxima.events import CommandEvent, EventBus

    console = Console(stderr=True, soft_wrap=True)
    overrides = {"threshold": threshold, "debounce_s": debounce_s, "idle_disarm_s": idle_disarm_s}
    try:
        given = {k: v for k, v in overrides.items() if v is not None}
        control = ControlSettings.model_validate(given)
        fields = {"checkpoint": checkpoint, "pose_every": pose_every, "pose_model": pose_model}
        if stride is not None:
            fields["stride"] = stride
        settings = EngineSettings.model_validate(fields)
        spec = StreamSpec(name=name, uri=source, drone=drone)
    except ValueError as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    bus = EventBus()
    commands: list[CommandEvent] = []
    bus.add_listener(lambda e: commands.append(e) if isinstance(e, CommandEvent) else None)
    engine = Engine([spec], bus, control=control, settings=settings, realtime=realtime)
    recorder = None
    try:
        writer = JsonlWriter(events, bus)
        if record is not None:
            recorder = _recorder(engine, record, record_fps, source, checkpoint)
    except (OSError, ValueError) as exc:
        console.print(f"[red]error:[/red] cannot write {record or events}: {exc}")
        raise typer.Exit(2) from None
    stats = engine.stats[name]
    interrupted = False
    with writer:
        try:
            engine.start()
        except (FileNotFoundError, ValueError) as exc:
            console.print(f"[red]error:[/red] {exc}")
            raise typer.Exit(2) from None
        columns = (
            TextColumn("{task.description}"),
            BarColumn(),
            TextColumn("{task.fields[info]}"),
            TimeElapsedColumn(),
        )
        with Progress(*columns, console=console) as progress:
            task = progress.add_task(f"recognize {name}", total=None, info="")

            def show(total: int | None) -> None:
                info = f"t={stats.last_t:.1f}s commands={len(commands)}"
                progress.update(task, total=total, completed=stats.frames, info=info)

            try:
                while not engine.wait(0.2):
                    show(stats.total_frames)
            except KeyboardInterrupt:
                interrupted = True
                engine.stop()
            show(stats.total_frames or stats.frames)
    console.print(
        f"{stats.frames} frames, {stats.classifications} classifications, "
        f"{writer.written} events -> {events}"
    )
    if recorder is not None:
        session = recorder.close()
        rec = recorder.recorders[name]
        console.print(f"recorded {rec.frames} poses -> {rec.path} (replay:{rec.path}@{rec.fps:g}); "
                      f"{session}")  # fmt: skip
    for c in commands:
        console.print(f"  t={c.t:8.2f}s  {c.command:<15} -> {c.drone} (seen by {c.stream or '-'})")
    if stats.error:
        console.print(f"[red]error:[/red] {stats.error}")
        raise typer.Exit(1)
    if interrupted:
        raise typer.Exit(130)
