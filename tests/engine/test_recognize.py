"""`proxima recognize` end to end: a stream stitched from held-out dataset clips, replayed
through the real engine in a subprocess, gives the expected commands as JSON lines."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from proxima.evaluation.stitch import stitch_views

# move_ahead and move_upward are performed while disarmed and must give no command.
SCRIPT = [
    ("move_ahead", 4.0),
    ("have_command", 4.0),
    ("move_to_left", 5.0),
    ("hover", 4.0),
    ("wave_off", 4.0),
    ("move_upward", 4.0),
    ("have_command", 4.0),
    ("land", 4.0),
]
EXPECTED = ["have_command", "move_to_left", "hover", "wave_off", "have_command", "land"]
TYPES = {"pose", "gesture", "action", "arming", "handover", "command", "stream"}


def recognize(*args: str | Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.run(
        [sys.executable, "-m", "proxima.cli", "recognize", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )


@pytest.fixture(scope="module")
def stitched(laser_clips, tmp_path_factory) -> tuple[Path, dict]:
    folder = tmp_path_factory.mktemp("recognize")
    stream = stitch_views(laser_clips, SCRIPT, views=("f",), part="test", seed=7)["f"]
    stream.write(folder / "front.csv")
    return folder / "front.csv", stream.truth()


@pytest.mark.slow
def test_commands_follow_the_script_and_never_come_before_arming(
    stitched, reference_checkpoint, tmp_path
) -> None:
    checkpoint = reference_checkpoint  # an exact script: the fixed model (conftest)
    csv, truth = stitched
    out = tmp_path / "events.jsonl"
    proc = recognize("--source", f"replay:{csv}", "--checkpoint", checkpoint, "--events", out)
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert all("t" in e and "type" in e for e in lines)
    assert {e["type"] for e in lines} == TYPES
    # Stream time from the frames: the last pose is at the stream's last frame.
    poses = [e for e in lines if e["type"] == "pose"]
    assert len(poses) == truth["frames"]
    assert poses[-1]["t"] == pytest.approx((truth["frames"] - 1) / 30, abs=0.5)

    commands = [e for e in lines if e["type"] == "command" and e["stream"]]
    assert [c["command"] for c in commands] == EXPECTED
    assert all(c["drone"] == "main" for c in commands)
    seg = truth["segments"]
    # Each command comes while its gesture is performed (or in the transition after it).
    starts = [s["onset_t"] for s in seg] + [1e9]
    performed = [s["gesture"] for s in seg]
    for c in commands:
        i = max(k for k in range(len(seg)) if starts[k] <= c["t"])
        assert performed[i] == c["command"], c
    # Nothing before the first have_command; nothing while disarmed after wave_off.
    assert commands[0]["t"] >= seg[1]["onset_t"]
    assert not [c for c in commands if seg[5]["onset_t"] <= c["t"] < seg[6]["onset_t"]]
    arming = [(e["armed"], e["reason"]) for e in lines if e["type"] == "arming"]
    assert arming[:3] == [(True, "have_command"), (False, "wave_off"), (True, "have_command")]
    # At the end of the replay nobody sees the operator: hover, then disarm.
    assert lines[-2]["type"] == "command" and lines[-2]["command"] == "hover"
    assert lines[-2]["stream"] == ""


def test_bad_inputs_give_clear_errors(checkpoint, tmp_path) -> None:
    from typer.testing import CliRunner

    from proxima.cli import app

    def run(*args: str | Path):
        return CliRunner().invoke(app, ["recognize", *map(str, args)])

    missing = run(
        "--source",
        f"replay:{tmp_path / 'nope.csv'}",
        "--checkpoint",
        checkpoint,
        "--events",
        tmp_path / "a.jsonl",
    )
    assert missing.exit_code == 1
    assert "nope.csv" in missing.output and "no such file" in missing.output
    bad = tmp_path / "bad.csv"
    bad.write_text(",counter_frame,i,x,y,z,visibility\n0,1,0,0.5,0.5,zero,1.0\n")
    wrong = run(
        "--source", f"replay:{bad}", "--checkpoint", checkpoint, "--events", tmp_path / "b.jsonl"
    )
    assert wrong.exit_code == 1
    assert "bad.csv:2" in wrong.output and "z is not a number" in wrong.output
    events = [json.loads(x) for x in (tmp_path / "b.jsonl").read_text().splitlines()]
    assert events[-1]["type"] == "stream" and events[-1]["state"] == "ended"
    assert "bad.csv:2" in events[-1]["detail"]
    nockpt = run(
        "--source",
        f"replay:{bad}",
        "--checkpoint",
        tmp_path / "x.pt",
        "--events",
        tmp_path / "c.jsonl",
    )
    assert nockpt.exit_code == 2 and "x.pt: no such checkpoint" in nockpt.output
    scheme = run(
        "--source", "ftp://x", "--checkpoint", checkpoint, "--events", tmp_path / "d.jsonl"
    )
    # Refused before any stream starts, as every bad argument is (StreamSpec checks it).
    assert scheme.exit_code == 2 and "'ftp://x' must start with one of" in scheme.output
