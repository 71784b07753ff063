"""`proxima demo --sim`: the closed-loop demo's config, and the demo itself coming up on
it, with the main drone's simulated camera arming gesture control."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest
from test_demo import DemoProcess, assert_everything_up, assert_stopped, get, login

from proxima.demo.cli import SIM_CONFIG
from proxima.demo.runner import simulated_drones
from proxima.scenario.fleet import free_udp_port
from proxima.settings import Settings
from proxima.sim.config import load_scene_config
from proxima.sim.uri import parse_sim_uri

REPO = Path(__file__).resolve().parents[2]


def test_the_sim_config_gives_every_drone_a_simulated_camera() -> None:
    settings = Settings.load(SIM_CONFIG)
    assert [name for name, _p, _s in simulated_drones(settings)] == ["main", "left", "right"]
    for stream in settings.streams:
        uri = parse_sim_uri(stream.uri)
        assert stream.kind == "sim" and uri.drone == stream.drone
        assert (REPO / uri.scene).is_file()
        load_scene_config(REPO / uri.scene)
    assert {d.heading for d in settings.drones} == {"face_operator"}
    assert settings.drones[0].camera.pitch_deg == -16.0


def sim_config(tmp: Path) -> Path:
    text = SIM_CONFIG.read_text().replace("runs/demo-sim/", f"{tmp}/runs/")
    text = text.replace("sim:config/", f"sim:{REPO}/config/")
    for port in ("14550", "14551", "14552"):
        text = text.replace(f"udpin:127.0.0.1:{port}", f"udpin:127.0.0.1:{free_udp_port()}")
    path = tmp / "demo-sim.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_the_sim_demo_arms_from_the_main_drones_camera(tmp_path: Path, checkpoint: Path) -> None:
    demo = DemoProcess(sim_config(tmp_path), checkpoint)
    try:
        base, sims = assert_everything_up(demo)
        assert "turning left, main, right to face the operator" in demo.output
        token = login(base)
        _, body = get(f"{base}/api/streams", token)
        assert '"sim"' in body.decode()
        deadline = time.monotonic() + 90
        armed = []
        while not armed and time.monotonic() < deadline:
            _, body = get(f"{base}/api/commands", token)
            rows = json.loads(body)
            rows = rows if isinstance(rows, list) else rows.get("commands", [])
            armed = [r for r in rows if r["action"] == "arm_control" and r["stream"] == "front"]
            time.sleep(1.0)
        assert armed, demo.output
        _, body = get(f"{base}/api/drones", token)
        drones = {d["name"]: d for d in json.loads(body)}
        assert drones["main"]["driving"] and drones["main"]["state"]["gesture_control"]
        demo.proc.send_signal(signal.SIGINT)
        assert_stopped(demo, sims)
    finally:
        demo.kill()
