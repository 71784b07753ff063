"""`proxima scenario sim-handover` end to end, headless: the synthetic operator seen by
the cameras of two real `proxima sim-drone` processes flown over MAVLink; the main drone's
climb takes the operator's feet out of its view, the secondary takes over, land lands
the main drone. The verdict, the timeline's order and the PNG are asserted."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

PROXIMA = str(Path(sys.executable).with_name("proxima"))


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_sim_handover_passes(tmp_path: Path, checkpoint: Path) -> None:
    out = tmp_path / "sim-handover.json"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    proc = subprocess.run(
        [PROXIMA, "scenario", "sim-handover", "--json", str(out), "--checkpoint",
         str(checkpoint), "--work", str(tmp_path / "work")],
        capture_output=True, text=True, timeout=280, env=env,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-4000:]
    result = json.loads(out.read_text())
    verdict = result["verdict"]
    assert verdict["passed"] is True, verdict
    reasons = "\n".join(verdict["reasons"])
    assert "main landed and disarmed" in reasons
    assert "exactly one handover: main->secondary (operator_partly_visible)" in reasons
    assert (
        "gesture commands as performed: have_command@main, move_upward@main, "
        "have_command@secondary, land@secondary" in reasons
    )
    assert "main's camera framed the operator until move_upward" in reasons
    assert "secondary's camera saw the whole operator when it took over" in reasons
    assert out.with_suffix(".png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    timeline = result["timeline"]
    commands = [e for e in timeline if e["kind"] == "command" and e["stream"]]
    climb = next(c for c in commands if c["command"] == "move_upward")
    lost = next(
        e for e in timeline
        if e["kind"] == "view" and e["stream"] == "main" and e["sight"] == "partial"
    )  # fmt: skip
    handover = next(e for e in timeline if e["kind"] == "handover" and e["from_stream"] == "main")
    land = next(c for c in commands if c["command"] == "land")
    assert climb["t"] < lost["t"] < handover["t"] < land["t"]
    assert lost["camera_height_m"] > 2.8  # the camera climbed from 2.5 m
    landed = [e for e in timeline if e["kind"] == "outcome" and e["outcome"] == "landed"]
    assert landed and landed[0]["t"] > land["t"]
    # Both drones turned to face the operator before the flight (a yaw sent with a
    # position target): the main north, the secondary 45 degrees east of north.
    drones = result["drones"]
    assert drones["main"]["start_yaw_deg"] == pytest.approx(0.0, abs=1.0)
    assert drones["secondary"]["start_yaw_deg"] == pytest.approx(45.0, abs=1.0)
    assert result["settings"]["bystanders"] and result["simulator_exit_codes"] == {
        "main": 0, "secondary": 0}  # fmt: skip
