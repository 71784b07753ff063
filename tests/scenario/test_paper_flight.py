"""`proxima scenario paper-flight` end to end, headless: stitched replays through the
live engine, the arbiter and the drone controller over MAVLink to two real
`proxima sim-drone` processes; the verdict, the JSON fields and the PNG are asserted."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

PROXIMA = str(Path(sys.executable).with_name("proxima"))


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_paper_flight_passes(tmp_path: Path, checkpoint: Path) -> None:
    out = tmp_path / "paper-flight.json"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    proc = subprocess.run(
        [
            PROXIMA,
            "scenario",
            "paper-flight",
            "--json",
            str(out),
            "--checkpoint",
            str(checkpoint),
            "--work",
            str(tmp_path / "work"),
        ],
        capture_output=True,
        text=True,
        timeout=220,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    result = json.loads(out.read_text())

    # The contract's fields.
    assert {"timeline", "drones", "verdict"} <= result.keys()
    verdict = result["verdict"]
    assert verdict["passed"] is True, verdict
    assert isinstance(verdict["reasons"], list) and verdict["reasons"]
    assert not any(r.startswith("FAILED") for r in verdict["reasons"])
    reasons = "\n".join(verdict["reasons"])
    assert "main landed and disarmed" in reasons
    assert "exactly one handover: main->secondary (operator_partly_visible)" in reasons
    assert "no command before arming" in reasons
    assert (
        "gesture commands as performed: have_command@main, move_to_left@main, "
        "have_command@secondary, move_to_right@secondary, land@secondary" in reasons
    )

    # The PNG beside the JSON.
    png = out.with_suffix(".png")
    assert result["plot"] == str(png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000

    # The timeline: every kind present, in stream time, in the order the paper describes.
    timeline = result["timeline"]
    kinds = {e["kind"] for e in timeline}
    assert {"gesture", "handover", "arming", "command", "ack", "outcome", "view"} <= kinds
    times = [e["t"] for e in timeline if e["t"] is not None]
    assert times == sorted(times)
    commands = [e for e in timeline if e["kind"] == "command" and e["stream"]]
    assert all(c["drone"] == "main" for c in commands)
    handover = next(e for e in timeline if e["kind"] == "handover" and e["from_stream"] == "main")
    lost = next(
        e for e in timeline if e["kind"] == "view" and e["stream"] == "main" and not e["framed"]
    )
    left = next(c for c in commands if c["command"] == "move_to_left")
    land = next(c for c in commands if c["command"] == "land")
    # The main drone moved, its camera lost the feet, then the secondary took over.
    assert left["t"] < lost["t"] < handover["t"] < land["t"]
    assert handover["to_stream"] == "secondary"
    landed = [e for e in timeline if e["kind"] == "outcome" and e["outcome"] == "landed"]
    assert len(landed) == 1 and landed[0]["command"] == "land"
    acks = {(a["command"], a["status"]) for a in timeline if a["kind"] == "ack" and a["stream"]}
    assert ("move_to_left", "sent") in acks and ("land", "sent") in acks

    # Each drone's final state: main on the ground where it started, secondary hovering.
    main, secondary = result["drones"]["main"], result["drones"]["secondary"]
    assert main["landed"] == "on_ground" and main["armed"] is False
    assert abs(main["position_ned"][0]) < 0.3 and abs(main["position_ned"][1]) < 0.3
    assert secondary["landed"] == "in_air" and abs(secondary["altitude_m"] - 2.0) < 0.2
    assert result["simulator_exit_codes"] == {"main": 0, "secondary": 0}
    # Replay ran faster than real time: only the drones' motion was paced.
    assert result["timing"]["realtime_stream_s"] < result["timing"]["stream_s"] / 2
