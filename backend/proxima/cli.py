"""The `proxima` command. Each subsystem registers its own subcommands from a small CLI
module (`cli.py`; the drone package's is still `commands.py`) that imports heavy libraries
(torch, mediapipe, flwr) only inside the command bodies, so `proxima --help` stays fast."""

from __future__ import annotations

import typer

app = typer.Typer(
    help="Proxima: command several drones by whole-body gestures.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _register_all() -> None:
    # One line per subsystem; order is the order in `--help`.
    from proxima.gesture import cli as gesture_cli

    gesture_cli.register(app)
    from proxima.synth import cli as synth_cli

    synth_cli.register(app)
    from proxima.evaluation import cli as evaluation_cli

    evaluation_cli.register(app)
    from proxima.engine import cli as engine_cli

    engine_cli.register(app)
    from proxima.drone import cli as drone_cli

    drone_cli.register(app)
    from proxima.api import cli as api_cli

    api_cli.register(app)
    from proxima.federated import cli as federated_cli

    federated_cli.register(app)
    from proxima.scenario import cli as scenario_cli

    scenario_cli.register(app)
    from proxima.demo import cli as demo_cli

    demo_cli.register(app)


_register_all()

if __name__ == "__main__":
    app()
