"""`proxima sim-drone` and `proxima drone-cmd` as a user runs them."""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from conftest import Connect, StartSim


def test_sim_drone_stops_cleanly_on_ctrl_c(start_sim: StartSim, connect: Connect) -> None:
    # (SIGTERM is checked on every simulator by the start_sim fixture's teardown.)
    sim = start_sim(sysid=5)
    connect(sim)  # it really runs: a link hears it
    assert sim.stop(signal.SIGINT) == 0
    out = sim.proc.stdout.read()
    assert f"udpin:127.0.0.1:{sim.port}" in out and "stopped" in out
    assert "Traceback" not in sim.proc.stderr.read()


def test_sim_drone_rejects_bad_options(proxima_cli: str) -> None:
    run = subprocess.run(
        [proxima_cli, "sim-drone", "--sysid", "300"], capture_output=True, text=True, timeout=30
    )
    assert run.returncode == 2 and "--sysid must be 1..255" in run.stderr


def test_drone_cmd_takes_off_and_logs_a_gesture(
    start_sim: StartSim, udp_port: int, proxima_cli: str, tmp_path: Path
) -> None:
    gcs = udp_port
    start_sim("--out-port", str(gcs), sysid=4)
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
