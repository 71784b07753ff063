"""`proxima demo` as a user runs it: a real process tree (three `proxima sim-drone`
processes, replayed streams, the console, the 3D view) from the shipped default config
(with free ports), the console answering, the 3D view behind its login, and SIGINT,
SIGTERM and SIGHUP leaving no process (also with a one-drone config)."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import tomllib
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from proxima.demo.cli import DEFAULT_CONFIG
from proxima.demo.runner import simulated_drones
from proxima.demo.streams import DemoStreamError, ensure_replays, replay_files
from proxima.scenario.fleet import free_udp_port, pid_alive
from proxima.settings import Settings

PROXIMA = str(Path(sys.executable).with_name("proxima"))
ADMIN = ("chief", "a long passphrase for tests")
READY = "Ctrl-C stops every part."


def test_default_config_is_three_simulated_drones_with_a_camera_each() -> None:
    settings = Settings.load(DEFAULT_CONFIG)
    assert [s.name for s in settings.streams] == ["front", "left", "right"]
    assert [name for name, _port, _sysid in simulated_drones(settings)] == ["main", "left", "right"]
    assert {s.drone for s in settings.streams} == {d.name for d in settings.drones}
    views = {f.stream: f.view for f in replay_files(settings)}
    assert views == {"front": "f", "left": "l", "right": "r"}
    assert settings.server.host == "127.0.0.1" and settings.server.viser_host == "127.0.0.1"


def test_a_missing_replay_without_a_view_is_refused(tmp_path: Path) -> None:
    settings = Settings(
        streams=[{"name": "a", "uri": f"replay:{tmp_path}/nothing.csv@30", "drone": "x"}]
    )
    with pytest.raises(DemoStreamError, match=r"a \(.*nothing.csv\)"):
        ensure_replays(settings)


def demo_config(tmp: Path) -> Path:
    """The shipped config with free UDP ports and files under `tmp`."""
    text = DEFAULT_CONFIG.read_text().replace("runs/demo/", f"{tmp}/runs/")
    for port in ("14550", "14551", "14552"):
        text = text.replace(f"udpin:127.0.0.1:{port}", f"udpin:127.0.0.1:{free_udp_port()}")
    path = tmp / "demo.toml"
    path.write_text(text)
    tomllib.loads(text)
    return path


class DemoProcess:
    """`proxima demo` in a subprocess, its output collected on a thread."""

    def __init__(self, config: Path, checkpoint: Path) -> None:
        env = {
            **os.environ,
            "PROXIMA_ADMIN_USER": ADMIN[0],
            "PROXIMA_ADMIN_PASSWORD": ADMIN[1],
            "OMP_NUM_THREADS": "1",
        }
        args = [PROXIMA, "demo", "--config", str(config), "--port", "0", "--view-port", "0"]
        args += ["--checkpoint", str(checkpoint)]
        self.proc = subprocess.Popen(
            args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
        )
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))

    @property
    def output(self) -> str:
        return "\n".join(self.lines)

    def wait_ready(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while READY not in self.output:
            assert self.proc.poll() is None, f"demo exited early:\n{self.output}"
            assert time.monotonic() < deadline, f"demo not ready in {timeout} s:\n{self.output}"
            time.sleep(0.2)

    def url(self, what: str) -> str:
        m = re.search(rf"{what}:\s+(http://127\.0\.0\.1:\d+)", self.output)
        assert m, self.output
        return m[1]

    def sim_pids(self) -> dict[str, int]:
        return {m[1]: int(m[2]) for m in re.finditer(r"sim-drone (\w+): .* pid (\d+)", self.output)}

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


def children(pid: int) -> set[int]:
    out: set[int] = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        out |= {int(p) for p in text}
    return out


def get(url: str, token: str | None = None) -> tuple[int, bytes]:
    req = urllib.request.Request(url)
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    with urllib.request.urlopen(req, timeout=10) as resp:
        return resp.status, resp.read()


def login(base: str) -> str:
    body = json.dumps({"username": ADMIN[0], "password": ADMIN[1]}).encode()
    req = urllib.request.Request(
        f"{base}/api/auth/login", data=body, headers={"content-type": "application/json"}
    )
    with urllib.request.urlopen(req, timeout=10) as resp:
        return json.loads(resp.read())["token"]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("demo")


@pytest.fixture
def demo(workdir: Path, checkpoint: Path) -> Iterator[DemoProcess]:
    process = DemoProcess(demo_config(workdir), checkpoint)
    yield process
    process.kill()  # only if a test left it running
    for pid in process.sim_pids().values():
        if pid_alive(pid):
            os.kill(pid, signal.SIGKILL)


def assert_everything_up(d: DemoProcess) -> tuple[str, dict[str, int]]:
    d.wait_ready(150)
    sims = d.sim_pids()
    assert set(sims) == {"main", "left", "right"}, d.output
    assert set(sims.values()) <= children(d.proc.pid)
    for pid in sims.values():
        assert b"sim-drone" in Path(f"/proc/{pid}/cmdline").read_bytes()
    base = d.url("console")
    status, body = get(f"{base}/api/health")
    assert status == 200 and json.loads(body)["status"] == "ok"
    assert_view_behind_login(d)
    return base, sims


def assert_view_behind_login(d: DemoProcess) -> None:
    """The 3D view is the console's /viser/: refused without a session, viser's page with
    the cookie a login sets."""
    view = d.url("3D view") + "/viser/"
    assert view.startswith(d.url("console"))
    with pytest.raises(urllib.error.HTTPError) as refused:
        get(view)
    assert refused.value.code == 401
    token = login(d.url("console"))
    req = urllib.request.Request(view, headers={"Cookie": f"proxima_view={token}"})
    with urllib.request.urlopen(req, timeout=10) as resp:
        assert resp.status == 200 and b"<html" in resp.read().lower()


def assert_stopped(d: DemoProcess, sims: dict[str, int]) -> None:
    assert d.proc.wait(30) == 0, d.output
    assert "stopped (simulators: main exit 0, left exit 0, right exit 0)" in d.output
    assert not [p for p in sims.values() if pid_alive(p)]


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_demo_comes_up_and_ctrl_c_stops_every_process(demo: DemoProcess) -> None:
    base, sims = assert_everything_up(demo)
    # The console sees the three drones over their MAVLink links, hovering.
    token = login(base)
    _, body = get(f"{base}/api/drones", token)
    drones = json.loads(body)
    drones = drones if isinstance(drones, list) else drones.get("drones", [])
    assert {d["name"] for d in drones} == {"main", "left", "right"}
    # The replayed streams reach the console.
    _, body = get(f"{base}/api/streams", token)
    assert "front" in body.decode() and "right" in body.decode()
    demo.proc.send_signal(signal.SIGINT)
    assert_stopped(demo, sims)


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_demo_stops_on_sigterm(demo: DemoProcess) -> None:
    _, sims = assert_everything_up(demo)
    assert "(view f, existing)" in demo.output  # the first test's streams were reused
    demo.proc.send_signal(signal.SIGTERM)
    assert_stopped(demo, sims)


def small_config(tmp: Path) -> Path:
    """One simulated drone and one stream replaying a LASER clip as it is."""
    from proxima.gesture.data_source import resolve_laser_dir

    clip = sorted(Path(resolve_laser_dir(None)).glob("DJI_*_hover_f.MP4.csv"))[0]
    path = tmp / "small.toml"
    path.write_text(
        "[[streams]]\n"
        'name = "front"\n'
        f'uri = "replay:{clip}@30"\n'
        'drone = "main"\n'
        "[[drones]]\n"
        'name = "main"\n'
        f'connection = "udpin:127.0.0.1:{free_udp_port()}"\n'
        "[server]\n"
        f'db_path = "{tmp / "runs" / "small.db"}"\n'
    )
    return path


def descendants(pid: int) -> list[psutil.Process]:
    return psutil.Process(pid).children(recursive=True)


@pytest.mark.slow
@pytest.mark.timeout(240)
# SIGINT and SIGTERM end the full demo above; SIGHUP (a closed terminal), whose default
# action would kill the demo before it stops anything, here.
@pytest.mark.parametrize("sig", [signal.SIGHUP], ids=lambda s: s.name)
def test_a_small_demo_stops_every_child_on_a_signal(
    sig: signal.Signals, tmp_path: Path, checkpoint: Path
) -> None:
    d = DemoProcess(small_config(tmp_path), checkpoint)
    before: list[psutil.Process] = []
    try:
        d.wait_ready(150)
        assert set(d.sim_pids()) == {"main"}, d.output
        before = descendants(d.proc.pid)
        assert {p.pid for p in before} >= set(d.sim_pids().values())
        console_port = int(d.url("console").rsplit(":", 1)[1])
        signalled = time.monotonic()
        d.proc.send_signal(sig)
        assert d.proc.wait(30) == 0, d.output
        _, alive = psutil.wait_procs(before, timeout=5)
        took = time.monotonic() - signalled
    finally:
        d.kill()
        for p in before:
            if p.is_running():
                p.kill()
    assert not alive, f"left running after {sig.name}: {alive}"
    assert "stopped (simulators: main exit 0)" in d.output
    with socket.socket() as s:  # the console (and the 3D view behind it) is gone too
        assert s.connect_ex(("127.0.0.1", console_port)) != 0
    print(f"\n{sig.name}: demo and {len(before)} children gone {took:.1f} s after the signal")
