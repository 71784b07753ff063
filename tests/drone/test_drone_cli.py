"""`proxima sim-drone` and `proxima drone-cmd` as a user runs them."""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from typer.testing import CliRunner

from proxima.drone.cli import register

if TYPE_CHECKING:
    from conftest import StartSim


def test_sim_drone_rejects_bad_options() -> None:
    app = typer.Typer()
    register(app)  # the same command functions `proxima` registers
    runner = CliRunner()
    for args, message in (
        (["--sysid", "300"], "--sysid must be 1..255"),
        (["--home", "50.1,14.4"], "--home must be LAT,LON,ALT"),
        (["--autopilot", "betaflight"], "--autopilot must be ardupilot or px4"),
        (["--loss", "1.5"], "--loss must be in [0, 1)"),
    ):
        result = runner.invoke(app, ["sim-drone", *args])
        assert result.exit_code == 2, args
        assert message in " ".join(result.output.split()), result.output


def test_drone_cmd_flies_and_sim_drone_stops_on_ctrl_c(
    start_sim: StartSim, udp_port: int, proxima_cli: str, tmp_path: Path
) -> None:
    gcs = udp_port
    sim = start_sim("--out-port", str(gcs), sysid=4)
    connection = f"udpin:127.0.0.1:{gcs}"  # the simulator's second ground-station port
    base = [proxima_cli, "drone-cmd", "--connect", connection, "--json"]
    run = subprocess.run([*base, "takeoff", "1.5"], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["ack"] == "accepted" and out["outcome"] == "reached"
    assert out["telemetry"]["system_id"] == 4 and out["telemetry"]["landed"] == "in_air"

    db = tmp_path / "log.db"
    run = subprocess.run(
        [*base, "--db", str(db), "gesture", "move_upward"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["status"] == "sent" and out["outcome"] == "reached"
    assert abs(out["telemetry"]["position"][2] + 2.5) < 0.25
    con = sqlite3.connect(db)
    rows = con.execute("SELECT source, command, action, status FROM command_log").fetchall()
    con.close()
    assert rows == [("cli", "move_upward", "move", "sent")]

    # Ctrl-C stops the simulator cleanly (SIGTERM is checked on every simulator by the
    # start_sim fixture's teardown).
    assert sim.stop(signal.SIGINT) == 0
    stdout = sim.proc.stdout.read()
    assert f"udpin:127.0.0.1:{sim.port}" in stdout and "stopped" in stdout
    assert "Traceback" not in sim.proc.stderr.read()
