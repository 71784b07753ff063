"""The `proxima` command. Each subsystem registers its own subcommands from a small
`commands.py` that imports heavy libraries (torch, mediapipe, flwr) only inside the
command bodies, so `proxima --help` stays fast."""

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
    from proxima.gesture import commands as gesture_commands

    gesture_commands.register(app)
    from proxima.synth import cli as synth_cli

    synth_cli.register(app)
    from proxima.engine import commands as engine_commands

    engine_commands.register(app)
    from proxima.drone import commands as drone_commands

    drone_commands.register(app)
    from proxima.api import commands as api_commands

    api_commands.register(app)
    from proxima.federated import commands as federated_commands

    federated_commands.register(app)
    from proxima.scenario import commands as scenario_commands

    scenario_commands.register(app)
    from proxima.demo import commands as demo_commands

    demo_commands.register(app)


_register_all()

if __name__ == "__main__":
    app()
