"""`proxima evaluate` (a checkpoint on a split's test windows), `proxima protocols`
(train and score once per protocol), `proxima model-card` and `proxima stitch` (replay
streams from dataset clips, with a ground-truth script), `proxima robustness` (a
checkpoint under the capture model: windows and live streams)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from proxima.gesture.cli import DataOpt, SplitOpt


def register(app: typer.Typer) -> None:
    """Add the evaluation's commands to the `proxima` app."""
    app.command()(evaluate)
    app.command()(protocols)
    app.command()(robustness)
    app.command("model-card")(model_card)
    app.command("stitch")(stitch)


def _fail(exc: Exception) -> NoReturn:
    typer.secho(f"error: {exc}", fg="red", err=True)
    raise typer.Exit(2)


def evaluate(
    checkpoint: Annotated[
        Path,
        typer.Option(
            help="Checkpoint from `proxima train`; comma-joined paths score their ensemble."
        ),
    ],
    json_out: Annotated[Path, typer.Option("--json", help="Where to write the metrics JSON.")],
    data: DataOpt = None,
    split: SplitOpt = "temporal",
    stride: Annotated[int, typer.Option(help="Frames between test windows.")] = 3,
) -> None:
    """Score a checkpoint on a split's test part: a metrics JSON and a confusion PNG."""
    from proxima.evaluation.metrics import evaluate_checkpoint
    from proxima.evaluation.plots import plot_confusion
    from proxima.gesture.clip import DataError

    try:
        result = evaluate_checkpoint(checkpoint, data, split, stride)
    except (DataError, ValueError, FileNotFoundError) as exc:
        _fail(exc)
    json_out.parent.mkdir(parents=True, exist_ok=True)
    json_out.write_text(json.dumps(result, indent=1))
    members = result["model"].count("+") + 1  # an ensemble's model is "tcn+tcn+..."
    name = checkpoint.name if members == 1 else f"ensemble of {members}"
    png = plot_confusion(
        result["confusion"], json_out.with_suffix(".png"),
        f"{name} on {split}: accuracy {result['accuracy']:.3f}",
    )  # fmt: skip
    views = ", ".join(f"{v} {r['accuracy']:.3f}" for v, r in result["per_view"].items())
    typer.echo(
        f"{split}: accuracy {result['accuracy']:.3f} (per view: {views}), macro F1 "
        f"{result['macro_f1']:.3f}, clip accuracy {result['clip_accuracy']:.3f} "
        f"({result['windows']} windows, {result['clips']} clips) -> {json_out}, {png}"
    )


def robustness(
    checkpoint: Annotated[
        Path,
        typer.Option(
            help="Checkpoint from `proxima train`; comma-joined paths score their ensemble."
        ),
    ],
    json_out: Annotated[
        Path, typer.Option("--json", help="Where to write the results (the PNG goes beside).")
    ],
    data: DataOpt = None,
    split: SplitOpt = "temporal",
    condition: Annotated[
        list[str] | None,
        typer.Option(help="Capture condition to run (repeat; default: every effect and field)."),
    ] = None,
    repeats: Annotated[int, typer.Option(help="Capture draws per clip and condition.")] = 3,
    stride: Annotated[int, typer.Option(help="Received poses between test windows.")] = 3,
    limit: Annotated[
        int | None, typer.Option(help="At most this many windows per condition (evenly spaced).")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of every capture draw.")] = 0,
    live: Annotated[
        bool, typer.Option(help="Also the live check: stitched streams through the engine.")
    ] = True,
    live_streams: Annotated[int, typer.Option(help="Stitched held-out streams.")] = 36,
    live_segments: Annotated[int, typer.Option(help="Gestures per stream.")] = 20,
    live_level: Annotated[int, typer.Option(help="Level of the field condition (1-3).")] = 1,
    window_clock: Annotated[
        str,
        typer.Option(
            help="The engine's window clock, for windows and the live check: model (the "
            "engine's default: the checkpoint's training clock), poses or time."
        ),
    ] = "model",
) -> None:
    """A checkpoint under the capture model (docs/robustness.md): window accuracy and
    macro F1 clean, under each capture effect at three levels and under `field`; and
    stitched held-out streams through the real engine, clean and under `field`: command
    precision, recall, wrong commands per hour, p95 onset-to-command. Writes the JSON
    and a PNG of accuracy against level beside it."""
    import torch
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.engine.config import EngineSettings
    from proxima.evaluation.plots import plot_robustness
    from proxima.evaluation.robustness import (
        CONDITION_NAMES,
        RobustnessConfig,
        RobustnessError,
        markdown_table,
        run_robustness,
    )
    from proxima.gesture.clip import DataError

    torch.set_num_threads(1)
    try:
        config = RobustnessConfig(
            conditions=tuple(condition or CONDITION_NAMES), repeats=repeats, stride=stride,
            limit=limit, seed=seed, live=live, live_streams=live_streams,
            live_segments=live_segments, live_level=live_level,
            engine=EngineSettings(window_clock=window_clock),  # type: ignore[arg-type]
        )  # fmt: skip
    except (RobustnessError, ValueError) as exc:
        _fail(exc)
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TimeElapsedColumn())  # fmt: skip
    with Progress(*columns) as progress:
        task = progress.add_task("robustness", total=config.steps())

        def step(what: str, n: int) -> None:
            progress.update(task, advance=n, description=what)

        try:
            result = run_robustness(checkpoint, data, split, config, step)
        except (DataError, RobustnessError, ValueError, FileNotFoundError) as exc:
            _fail(exc)
    args = [f"--checkpoint {checkpoint}", *[f"--data {d}" for d in data or []],
            f"--split {split}", f"--json {json_out}"]  # fmt: skip
    args += [f"--condition {c}" for c in condition or []]
    defaults = {"repeats": 3, "stride": 3, "limit": None, "seed": 0, "live_streams": 36,
                "live_segments": 20, "live_level": 1, "window_clock": "model"}  # fmt: skip
    given = {"repeats": repeats, "stride": stride, "limit": limit, "seed": seed,
             "live_streams": live_streams, "live_segments": live_segments,
             "live_level": live_level, "window_clock": window_clock}  # fmt: skip
    args += [f"--{k.replace('_', '-')} {v}" for k, v in given.items() if v != defaults[k]]
    if not live:
        args.append("--no-live")
    result = {"command": "proxima robustness " + " ".join(args), **result}
    json_out.parent.mkdir(parents=True, exist_ok=True)
    json_out.write_text(json.dumps(result, indent=1) + "\n")
    png = plot_robustness(
        result, json_out.with_suffix(".png"),
        f"{checkpoint.name} on {split}: window accuracy under the capture model",
    )  # fmt: skip
    typer.echo(markdown_table(result))
    typer.echo(f"-> {json_out}, {png} ({result['wall_s']} s)")


def protocols(
    json_out: Annotated[Path, typer.Option("--json", help="Where to write the results.")],
    data: DataOpt = None,
    split: Annotated[
        list[str] | None, typer.Option("--split", help="Repeatable; default: all protocols.")
    ] = None,
    eval_data: Annotated[
        list[str] | None,
        typer.Option(help="Score temporal/cross-view on this data only (e.g. laser)."),
    ] = None,
    model: str = "tcn",
    epochs: int = 60,
    stride: int = 4,
    seed: int = 0,
    threads: int = 2,
    time_warp: Annotated[float | None, typer.Option(help="As for train.")] = None,
    transitions: Annotated[float, typer.Option(help="As for train.")] = 0.0,
    mirror: Annotated[bool, typer.Option(help="As for train.")] = True,
    refit: Annotated[bool, typer.Option(help="As for train.")] = False,
) -> None:
    """Train and score a model on each evaluation protocol; print the results table."""
    from rich.progress import Progress

    from proxima.evaluation.protocols import (
        LASER_PROTOCOLS,
        UAV_PROTOCOLS,
        results_table,
        run_protocols,
        save_results,
    )
    from proxima.gesture.train import TrainConfig

    splits = split or [*LASER_PROTOCOLS, *UAV_PROTOCOLS]
    cfg = TrainConfig(epochs=epochs, stride=stride, seed=seed, threads=threads,
                      transitions=transitions, mirror=mirror, refit=refit)  # fmt: skip
    if time_warp is not None:
        cfg.time_warp = time_warp
    rows_so_far: list[dict] = []
    with Progress() as progress:
        task = progress.add_task("protocols", total=len(splits))

        def done(row: dict) -> None:
            rows_so_far.append(row)
            save_results(rows_so_far, json_out)  # keep finished rows if a later one fails
            progress.console.print(
                f"{row['split']}: accuracy {row['accuracy']:.3f}, clip {row['clip_accuracy']:.3f}"
            )
            progress.advance(task)

        rows = run_protocols(splits, model, data, cfg, eval_data, done)
    save_results(rows, json_out)
    typer.echo(results_table(rows))


def model_card(
    checkpoint: Annotated[Path, typer.Option(help="The checkpoint to describe.")],
    out: Annotated[Path, typer.Option(help="Markdown file to write.")],
    results: Annotated[
        list[Path] | None, typer.Option(help="Protocol results JSON (repeatable).")
    ] = None,
    notes: Annotated[Path | None, typer.Option(help="Markdown to append.")] = None,
) -> None:
    """Write a model card (Markdown) for a checkpoint from its metadata and results."""
    from proxima.evaluation.model_card import render_model_card

    rows = [row for f in results or [] for row in json.loads(f.read_text())]
    text = render_model_card(checkpoint, rows, notes.read_text() if notes else "")
    out.write_text(text)
    typer.echo(f"wrote {out}")


def stitch(
    out: Annotated[Path, typer.Option(help="CSV to write (one per view: OUT.<view>.csv)")],
    script: Annotated[
        str, typer.Option(help="GESTURE:SECONDS,... e.g. have_command:5,move_to_left:6")
    ] = "",
    random_segments: Annotated[
        int, typer.Option("--random", help="instead of --script: N random gestures")
    ] = 0,
    min_s: Annotated[float, typer.Option(help="shortest random segment (s)")] = 3.0,
    max_s: Annotated[float, typer.Option(help="longest random segment (s)")] = 6.0,
    view: Annotated[list[str] | None, typer.Option(help="camera view f, l or r (repeat)")] = None,
    part: Annotated[
        str, typer.Option(help="test (temporal split's last 30%), train or all")
    ] = "test",
    transition_s: Annotated[float, typer.Option(help="seconds between two gestures")] = 0.5,
    fps: Annotated[float, typer.Option(help="frame rate of the stream")] = 30.0,
    blank: Annotated[
        list[str] | None,
        typer.Option(help="VIEW:KIND:START:END, KIND feet or drop (repeat), e.g. f:feet:20:35"),
    ] = None,
    seed: Annotated[int, typer.Option(help="random seed (segment offsets, random script)")] = 0,
    data: Annotated[str | None, typer.Option(help="LASER data folder")] = None,
) -> None:
    """Stitch LASER clips into a replay stream (landmark CSV) performing a gesture script,
    with smooth transitions, and write its ground truth beside it (OUT.truth.json)."""
    import numpy as np
    from rich.console import Console

    from proxima.evaluation.stitch import (
        Blank,
        StitchError,
        parse_blank,
        parse_plan,
        random_plan,
        stitch_views,
    )
    from proxima.gesture.clip import DataError
    from proxima.gesture.data_source import resolve_dataset
    from proxima.gesture.laser import load_laser_dir

    console = Console(stderr=True, soft_wrap=True)
    views = view or ["f"]
    try:
        if bool(script) == bool(random_segments):
            raise StitchError("give exactly one of --script and --random")
        plan = (
            parse_plan(script)
            if script
            else random_plan(np.random.default_rng(seed), random_segments, min_s, max_s)
        )
        blanks: dict[str, list[Blank]] = {}
        for spec in blank or []:
            v, sep, rest = spec.partition(":")
            kind, sep2, times = rest.partition(":")
            if not (sep and sep2) or v not in views:
                raise StitchError(f"blank {spec!r}: expected VIEW:KIND:START:END, VIEW in {views}")
            blanks.setdefault(v, []).append(parse_blank(times, kind))
        with console.status("loading clips"):
            clips = load_laser_dir(resolve_dataset(data))
        streams = stitch_views(clips, plan, views, part, transition_s, fps, blanks, seed)
    except (StitchError, DataError) as exc:
        console.print(f"[red]error:[/red] {exc}")
        raise typer.Exit(2) from None
    for v, stream in streams.items():
        path = out if len(views) == 1 else out.with_name(f"{out.stem}.{v}{out.suffix}")
        truth = stream.write(path)
        console.print(
            f"{path}: view {v}, {len(stream.segments)} gestures, {stream.duration_s:.1f} s, "
            f"{len(stream.frames)} frames; truth {truth}"
        )
