"""`proxima synth`: write a synthetic data set (LASER-format CSVs and a manifest)."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Annotated

import typer


def synth(
    out: Annotated[Path, typer.Option(help="Folder to write (new, empty, or see --overwrite).")],
    clips: Annotated[
        int, typer.Option(help="Clips in all, spread evenly over the 13 gestures.")
    ] = 130,
    seed: Annotated[int, typer.Option(help="Seed of every random draw.")] = 0,
    views: Annotated[
        list[str] | None,
        typer.Option(
            "--views",
            help="Camera view range NAME:AZIMUTH:ELEVATION[:DISTANCE] in degrees (and metres), "
            "each a value or LO..HI; azimuth from the operator's facing, clockwise (90 = the "
            "operator's right); repeat for several, used in turn per scene. Default: "
            "front:-20..20:5..20, right:55..85:5..20, left:-85..-55:5..20.",
        ),
    ] = None,
    fps: Annotated[float, typer.Option(help="Frames per second of the clips.")] = 30.0,
    resolution: Annotated[str, typer.Option(help="Image size WIDTHxHEIGHT.")] = "1920x1080",
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Replace a synthetic data set already in --out.")
    ] = False,
    seen_by: Annotated[
        str,
        typer.Option(
            help="Who reports the landmarks: 'geometry' (the exact projection, fast) or "
            "'mediapipe' (each frame rendered and passed through the real pose model, "
            "~40 ms a frame: its guesses for hidden limbs, its noise and misses).",
        ),
    ] = "geometry",
    pose_model: Annotated[
        Path | None, typer.Option(help="Pose model for --seen-by mediapipe (default: found).")
    ] = None,
    render_width: Annotated[
        int, typer.Option(help="Rendered picture width for --seen-by mediapipe.")
    ] = 640,
    max_frames: Annotated[
        int | None, typer.Option(help="Keep each clip's first N frames (default: all).")
    ] = None,
    sides: Annotated[
        str,
        typer.Option(
            help="For --seen-by mediapipe: 'mediapipe' keeps its labelling; 'exact' "
            "relabels the frames it reads as facing away (left and right swapped) by the "
            "exact projection.",
        ),
    ] = "mediapipe",
) -> None:
    """Make synthetic operators perform the 13 gestures before virtual cameras; write each
    clip as a LASER-format CSV, plus manifest.json (body, camera and gesture parameters).
    Train on them with `--data synth:DIR`."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.synth.dataset import generate
    from proxima.synth.views import DEFAULT_VIEWS, parse_view

    try:
        view_ranges = [parse_view(v) for v in views] if views else list(DEFAULT_VIEWS)
    except ValueError as exc:
        typer.secho(f"error: {exc}", fg="red", err=True)
        raise typer.Exit(2) from None
    width, _, height = resolution.lower().partition("x")
    if not (width.isdigit() and height.isdigit() and int(width) > 0 and int(height) > 0):
        typer.secho(
            f"error: --resolution {resolution!r}: expected WIDTHxHEIGHT, e.g. 1920x1080",
            fg="red",
            err=True,
        )
        raise typer.Exit(2)
    size = (int(width), int(height))
    from proxima.pose.model import PoseModelError
    from proxima.synth.dataset import GeometricSeer, Seer

    seer: Seer
    rendered = None  # the MediaPipe seer, whose relabelled frames are reported at the end
    try:
        if seen_by == "mediapipe":
            from proxima.synth.pose_model import PoseModelSeer

            seer = rendered = PoseModelSeer(pose_model, render_width, max_frames, fps, sides)
        elif seen_by == "geometry":
            seer = GeometricSeer(max_frames)
        else:
            raise ValueError(f"--seen-by {seen_by!r}: expected 'geometry' or 'mediapipe'")
    except (ValueError, PoseModelError) as exc:
        typer.secho(f"error: {exc}", fg="red", err=True)
        raise typer.Exit(2) from None
    command = "proxima " + shlex.join(sys.argv[1:])
    with Progress(
        TextColumn("[bold]synth[/]"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
    ) as progress:
        task = progress.add_task("", total=clips)

        def on_clip(k: int, gesture: str) -> None:
            progress.update(task, completed=k + 1, description=gesture)

        try:
            manifest = generate(
                out,
                clips,
                seed,
                view_ranges,
                fps,
                size,
                seer=seer,
                overwrite=overwrite,
                on_clip=on_clip,
                command=command,
            )
        except ValueError as exc:
            progress.stop()
            typer.secho(f"error: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
    entries = manifest["clip_list"]
    frames = sum(e["detected"] for e in entries)
    seconds = float(manifest["seconds"])
    typer.echo(
        f"wrote {len(entries)} clips ({frames} frames, {len(manifest['scenes'])} scenes) to "
        f"{out} in {seconds:.1f} s ({1000 * seconds / max(clips, 1):.0f} ms a clip); "
        f"train on them with --data synth:{out}"
    )
    if rendered is not None and rendered.swapped_frames:
        typer.echo(
            f"MediaPipe read the operator as facing away in {rendered.swapped_frames} frames: "
            "relabelled"
        )


def register(app: typer.Typer) -> None:
    app.command()(synth)
