"""`proxima train`, `proxima ensemble join|split` and `proxima data fetch` (scoring a model
is `proxima.evaluation.cli`)."""

from __future__ import annotations

import math
import shlex
import sys
from pathlib import Path
from typing import Annotated, NoReturn

import typer

DataOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--data",
        help="Data folder (LASER CSVs or UAV-Gesture), the name laser / uav-gesture, "
        "synth:DIR, or samples:DB (the console's kept samples in its database DB); "
        "repeat to combine. Default: $PROXIMA_DATA, ../shared, the cache, or a download.",
    ),
]
SplitOpt = Annotated[
    str,
    typer.Option(
        help="temporal | cross-view:f|l|r | all | uav-gesture:1|2|3 | calibrate:SPLIT:SECONDS "
        "(SPLIT's training part plus the first SECONDS of each held-out clip train; the "
        "rest of each held-out clip, after a one-window gap, tests)"
    ),
]


def _fail(exc: Exception) -> NoReturn:
    typer.secho(f"error: {exc}", fg="red", err=True)
    raise typer.Exit(2)


def train(
    out: Annotated[Path, typer.Option(help="Where to write the checkpoint (.pt).")],
    data: DataOpt = None,
    model: Annotated[str, typer.Option(help="tcn (default) or paper-lstm.")] = "tcn",
    split: SplitOpt = "temporal",
    pipeline: Annotated[
        str | None,
        typer.Option(help="paper, body, body-image or body-smooth-z (default: the model's)."),
    ] = None,
    epochs: int = 60,
    patience: int = 15,
    stride: Annotated[int, typer.Option(help="Frames between training windows.")] = 4,
    window: Annotated[
        int, typer.Option(help="Frames a window holds, 15-60; the engine reads it from the model.")
    ] = 60,
    max_gap: Annotated[
        int, typer.Option(help="Longest gap (missing frames) a window may span.")
    ] = 5,
    seed: int = 0,
    threads: Annotated[int, typer.Option(help="Torch threads.")] = 2,
    yaw: Annotated[float, typer.Option(help="Extra yaw augmentation, degrees.")] = 30.0,
    mirror: Annotated[bool, typer.Option(help="Left-right mirroring augmentation.")] = True,
    time_warp: Annotated[
        float | None,
        typer.Option(help="Time-warp augmentation: +- change of speed; 0 = off. [default: 0.2]"),
    ] = None,
    transitions: Annotated[
        float, typer.Option(help="Share of windows turned into gesture onsets (e.g. 0.3).")
    ] = 0.0,
    trim_idle: Annotated[
        bool,
        typer.Option(
            help="Start moving gestures' training clips where at most half a window of "
            "the operator's opening rest is left."
        ),
    ] = True,
    augment: Annotated[
        str,
        typer.Option(
            help="capture: each epoch's windows redrawn through the capture model (clean, "
            "field 1, field 2) and the live One Euro filter; none: the recordings as they are."
        ),
    ] = "capture",
    capture_mix: Annotated[
        str | None,
        typer.Option(
            help="With --augment capture: the conditions windows are drawn through, "
            "CONDITION:LEVEL:SHARE,... [default: clean:1:0.2,field:1:0.4,field:2:0.4]"
        ),
    ] = None,
    window_clock: Annotated[
        str,
        typer.Option(
            help="With --augment capture: poses (a window is the last poses received, at "
            "any camera rate), time (camera rates under 30 fps resampled to 30 per second, "
            "as the engine's window_clock = time) or mixed (half of such windows each way; "
            "the engine then resamples)."
        ),
    ] = "poses",
    thumb_pair: Annotated[
        str,
        typer.Option(
            help="label: every window taught its label; either: all_clear / not_clear windows "
            "that do not see the right hand (all of UAV-Gesture's) taught only 'one of the two'."
        ),
    ] = "label",
    calibration_share: Annotated[
        float | None,
        typer.Option(
            help="With a calibrate:SPLIT:SECONDS split: the calibration clips' share of each "
            "epoch (repeated to make it; 0 < share < 1). [default: 0.5]"
        ),
    ] = None,
    refit: Annotated[
        bool,
        typer.Option(
            help="After early stopping, retrain on the whole training part "
            "(validation tails included) for the chosen epochs."
        ),
    ] = False,
    init: Annotated[
        Path | None,
        typer.Option(
            help="A checkpoint to start from. With a calibrate:SPLIT:SECONDS split: fine-tune "
            "this checkpoint of SPLIT (trained with --split SPLIT) for --epochs; with any other "
            "split: start from its weights and train as usual (e.g. synthetic pretraining)."
        ),
    ] = None,
) -> None:
    """Train a gesture model on a split's training part and save one self-contained file."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.gesture.clip import DataError
    from proxima.gesture.train import EpochLog, TrainConfig
    from proxima.gesture.workflow import train_model

    cfg = TrainConfig(epochs=epochs, patience=patience, stride=stride, window=window,
                      max_gap=max_gap, seed=seed, threads=threads, yaw_deg=yaw, mirror=mirror,
                      transitions=transitions, refit=refit, augment=augment,
                      trim_idle=trim_idle, window_clock=window_clock,
                      thumb_pair=thumb_pair)  # fmt: skip
    if time_warp is not None:
        cfg.time_warp = time_warp
    if calibration_share is not None:
        cfg.calibration_share = calibration_share
    if capture_mix is not None:
        from proxima.gesture.robust import parse_mix

        try:
            cfg.capture_mix = parse_mix(capture_mix)
        except ValueError as exc:
            _fail(exc)
    command = "proxima " + shlex.join(sys.argv[1:])
    with Progress(
        TextColumn("[bold]train[/]"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
        TextColumn("{task.description}"), TimeElapsedColumn(),
    ) as progress:  # fmt: skip
        task = progress.add_task("loading data", total=epochs)

        def on_start(n_fit: int, n_val: int, skipped: int) -> None:
            progress.console.print(
                f"{n_fit} training windows, {n_val} validation windows, "
                f"{skipped} skipped (would span a gap of more than {max_gap} frames)"
            )

        def on_epoch(log: EpochLog) -> None:
            text = f"loss {log.train_loss:.3f}"
            if not math.isnan(log.val_loss):  # the refit has no validation
                text += f" val {log.val_loss:.3f} acc {log.val_accuracy:.3f}"
            progress.update(task, completed=log.epoch, description=text)

        def on_refit(n_windows: int, n_epochs: int) -> None:
            progress.console.print(
                f"refit: a fresh model on the whole training part ({n_windows} windows) "
                f"for the {n_epochs} epochs early stopping chose"
            )
            progress.reset(task, total=n_epochs, description="refit")

        try:
            result = train_model(
                data,
                model,
                split,
                out,
                cfg,
                pipeline,
                command,
                on_epoch,
                on_start,
                on_refit,
                init,
            )
        except (DataError, ValueError, FileNotFoundError) as exc:
            _fail(exc)
    if init is not None and split.startswith("calibrate:"):  # no validation: every epoch ran
        typer.echo(
            f"saved {result.checkpoint}: fine-tuned {init} for {len(result.history)} epochs "
            f"(last loss {result.history[-1].train_loss:.3f}), {result.seconds:.0f} s"
        )
        return
    best = min(result.history, key=lambda h: h.val_loss)
    typer.echo(
        f"saved {result.checkpoint} ({result.checkpoint.stat().st_size / 1024:.0f} KiB): "
        f"{len(result.history)} epochs, best val loss {best.val_loss:.3f} "
        f"(acc {best.val_accuracy:.3f}) at epoch {best.epoch}"
        + (f", refit {len(result.refit_history)} epochs" if result.refit_history else "")
        + f", {result.seconds:.0f} s"
    )


def fetch(
    name: Annotated[str, typer.Argument(help="laser or uav-gesture")] = "laser",
    dest: Annotated[Path | None, typer.Option(help="Folder (default: the user cache).")] = None,
) -> None:
    """Download a data set from its pinned upstream commit, verified by SHA-256."""
    from proxima.gesture.clip import DataError
    from proxima.gesture.data_source import DATASETS, download_dataset

    if name not in DATASETS:
        _fail(ValueError(f"unknown data set {name!r}; choose from {sorted(DATASETS)}"))
    try:
        path = download_dataset(name, dest)
    except DataError as exc:
        _fail(exc)
    typer.echo(f"{name}: {path}")


def join(
    members: Annotated[list[Path], typer.Argument(help="one-model checkpoints (two or more)")],
    out: Annotated[Path, typer.Option(help="the ensemble file to write")],
) -> None:
    """Join one-model checkpoints into one ensemble file: the mean of their calibrated
    probabilities (what the shipped model is). Each member keeps its own metadata."""
    from proxima.gesture.classifier import GestureClassifier
    from proxima.gesture.ensemble import save_ensemble

    try:
        models = [GestureClassifier.load(m) for m in members]
        path = save_ensemble(out, models, {
            "command": shlex.join(["proxima", *sys.argv[1:]]),
            "members": [str(m) for m in members],
        })  # fmt: skip
    except (FileNotFoundError, ValueError) as exc:
        _fail(exc)
    typer.echo(f"saved {path} ({path.stat().st_size / 1024:.0f} KiB): {len(models)} members")


def split(
    ensemble: Annotated[Path, typer.Argument(help="an ensemble file")],
    out_dir: Annotated[Path, typer.Option(help="folder for the members' files")],
) -> None:
    """Write an ensemble file's members as one-model checkpoints (STEM-m0.pt, STEM-m1.pt,
    ...), e.g. to start a training or a federated run from one of them."""
    from proxima.gesture.classifier import write_blob
    from proxima.gesture.ensemble import EnsembleClassifier, load_checkpoint

    try:
        clf = load_checkpoint(ensemble)
    except (FileNotFoundError, ValueError) as exc:
        _fail(exc)
    if not isinstance(clf, EnsembleClassifier):
        _fail(ValueError(f"{ensemble}: one model, not an ensemble"))
    for i, m in enumerate(clf.members):
        path = write_blob(out_dir / f"{ensemble.stem}-m{i}.pt", m.blob())
        typer.echo(f"saved {path}")


def register(app: typer.Typer) -> None:
    app.command()(train)
    ensemble_app = typer.Typer(
        help="Ensembles: several models in one file, their probabilities averaged.",
        no_args_is_help=True,
    )
    ensemble_app.command()(join)
    ensemble_app.command()(split)
    app.add_typer(ensemble_app, name="ensemble")
    data_app = typer.Typer(help="Data sets: fetch them for offline use.", no_args_is_help=True)
    data_app.command()(fetch)
    app.add_typer(data_app, name="data")
