"""`proxima scenario paper-flight`, `sim-two-drones` and `sim-handover`: the paper's
flights reproduced end to end in simulation (the last in the closed-loop simulator),
each writing a JSON result and a flight-path PNG beside it. Exit code 0 when the verdict
passed, 1 when it failed, 2 when the scenario could not be set up."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

scenario_app = typer.Typer(
    help="Fly the paper's experiments end to end in simulation and judge them.",
    no_args_is_help=True,
)


def register(app: typer.Typer) -> None:
    """Add `proxima scenario ...` to the `proxima` app."""
    app.add_typer(scenario_app, name="scenario")


def _run(kind: str, build: Any, json_out: Path, title: str, checkpoint: Path | None) -> None:
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from proxima.scenario.result import write_result
    from proxima.scenario.rig import ScenarioError

    console = Console(stderr=True, soft_wrap=True)
    if checkpoint is not None and not checkpoint.is_file():
        console.print(f"[red]error:[/red] {checkpoint}: no such checkpoint")
        raise typer.Exit(2)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.fields[info]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=console) as bar:
        task = bar.add_task(kind, total=None, info="")

        def progress(phase: str, done: float, total: float | None) -> None:
            info = f"stream t={done:.1f}/{total:.1f}s" if total else ""
            bar.update(task, description=f"{kind}: {phase}", completed=done, total=total, info=info)

        try:
            result = build(progress)
        except ScenarioError as exc:
            console.print(f"[red]error:[/red] {exc}")
            raise typer.Exit(2) from None
    png = write_result(result, json_out, title)
    verdict = result["verdict"]
    for reason in verdict["reasons"]:
        style = "red" if reason.startswith("FAILED") else "green"
        console.print(f"  [{style}]{reason}[/{style}]")
    timing = result["timing"]
    console.print(
        f"{'PASSED' if verdict['passed'] else 'FAILED'}: {json_out} and {png} "
        f"({timing['stream_s']:.1f} s of stream, {timing['realtime_stream_s']:.1f} s of it "
        f"at real time, {timing['wall_s']:.1f} s wall)"
    )
    if not verdict["passed"]:
        raise typer.Exit(1)


@scenario_app.command("paper-flight")
def paper_flight(
    json_out: Annotated[Path, typer.Option("--json", help="write the result here (+ .png)")],
    checkpoint: Annotated[
        Path | None, typer.Option(help="gesture model (default: the shipped gesture-default.pt)")
    ] = None,
    data: Annotated[str | None, typer.Option(help="LASER data folder")] = None,
    seed: Annotated[
        int | None, typer.Option(help="clip offsets (default: first that frames the operator)")
    ] = None,
    part: Annotated[str, typer.Option(help="clip rows: all, test or train")] = "all",
    regain_s: Annotated[
        float, typer.Option(help="seconds the main camera must see the operator to drive")
    ] = 8.0,
    work: Annotated[
        Path | None, typer.Option(help="keep stitched CSVs, simulator logs, command log here")
    ] = None,
) -> None:
    """The paper's real-robot flight: hover, have_command, move_to_left; the main drone
    loses the operator's feet, the secondary's recognition takes over; have_command,
    move_to_right and land reach the main drone through it; it lands."""
    from proxima.scenario.paper_flight import PaperFlightConfig, run_paper_flight

    cfg = PaperFlightConfig(
        checkpoint=checkpoint, data=data, seed=seed, part=part, regain_s=regain_s, work_dir=work
    )
    _run(
        "paper-flight",
        lambda p: run_paper_flight(cfg, p),
        json_out,
        "Paper flight: handover from the main to the secondary drone",
        checkpoint,
    )


@scenario_app.command("sim-two-drones")
def sim_two_drones(
    json_out: Annotated[Path, typer.Option("--json", help="write the result here (+ .png)")],
    checkpoint: Annotated[
        Path | None, typer.Option(help="gesture model (default: the shipped gesture-default.pt)")
    ] = None,
    data: Annotated[str | None, typer.Option(help="LASER data folder")] = None,
    seed: Annotated[int, typer.Option(help="clip offsets of the stitched streams")] = 0,
    part: Annotated[str, typer.Option(help="clip rows: all, test or train")] = "all",
    work: Annotated[
        Path | None, typer.Option(help="keep stitched CSVs, simulator logs, command logs here")
    ] = None,
) -> None:
    """The paper's simulation experiment: two simulated drones, each commanded by
    recognised gestures from its own camera to its final position."""
    from proxima.scenario.two_drones import TwoDronesConfig, run_two_drones

    cfg = TwoDronesConfig(checkpoint=checkpoint, data=data, seed=seed, part=part, work_dir=work)
    _run(
        "sim-two-drones",
        lambda p: run_two_drones(cfg, p),
        json_out,
        "Two simulated drones commanded to their final positions",
        checkpoint,
    )


@scenario_app.command("sim-handover")
def sim_handover(
    json_out: Annotated[Path, typer.Option("--json", help="write the result here (+ .png)")],
    checkpoint: Annotated[
        Path | None, typer.Option(help="gesture model (default: models/gesture-default.pt)")
    ] = None,
    seed: Annotated[int, typer.Option(help="the scene: bodies, motion, noise")] = 2,
    altitude: Annotated[float, typer.Option(help="take-off altitude of both drones (m)")] = 2.5,
    pitch: Annotated[
        float, typer.Option(help="the main camera's pitch, degrees (down negative)")
    ] = -8.0,
    bystanders: Annotated[
        bool, typer.Option(help="a walker behind the operator and a signaller beside them")
    ] = True,
    noise: Annotated[
        float,
        typer.Option(
            min=0.0,
            max=4.0,
            help="the live pose path's jitter and visibility noise, x the measured",
        ),
    ] = 1.0,
    depth_noise: Annotated[
        float,
        typer.Option(
            min=0.0, max=8.0, help="z's jitter ratio, x the measured (off: see docs/sim.md)"
        ),
    ] = 0.0,
    regain_s: Annotated[
        float, typer.Option(help="seconds the main camera must see the operator to drive")
    ] = 8.0,
    work: Annotated[
        Path | None, typer.Option(help="keep simulator logs and the command log here")
    ] = None,
) -> None:
    """The paper's handover in the closed-loop simulator: the main drone climbs on
    move_upward, its camera loses the synthetic operator's feet by geometry, the
    secondary's camera takes over; have_command and land reach the main drone."""
    from proxima.scenario.sim_handover import SimHandoverConfig, run_sim_handover

    cfg = SimHandoverConfig(
        checkpoint=checkpoint,
        seed=seed,
        altitude_m=altitude,
        pitch_deg=pitch,
        bystanders=bystanders,
        jitter=noise,
        visibility_noise=noise,
        depth_jitter=depth_noise,
        regain_s=regain_s,
        work_dir=work,
    )
    _run(
        "sim-handover",
        lambda p: run_sim_handover(cfg, p),
        json_out,
        "Closed-loop handover: the main drone's climb takes the operator's feet out of view",
        checkpoint,
    )
