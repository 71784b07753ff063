"""The built wheel works outside the repository: it is built from a copy of the checkout,
installed into a fresh virtual environment, and its `proxima` command is run from a
temporary directory with no checkout above it (help, `recognize` on a LASER clip with
the shipped model, `sim-drone` answering a ground station, `serve` with the shipped
console).

Only Proxima comes from the wheel. Its third-party dependencies are the ones of the
environment running the tests: the new environment sees that one's site-packages through
a `.pth` line (installing torch, mediapipe and Flower afresh takes minutes), the wheel
is installed with `--no-deps`, and `pip check` confirms that what the wheel declares is
satisfied there.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import sysconfig
import time
import urllib.request
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
STATIC = REPO / "static"
CLIP = "DJI_0146_have_command_f.MP4.csv"  # have_command, front view
ADMIN = ("wheel-admin", "wheel-test-password-7")


@dataclass(frozen=True)
class Installed:
    wheel: Path
    venv: Path
    home: Path  # the working directory the commands run in, outside any checkout
    env: dict[str, str]

    @property
    def proxima(self) -> str:
        return str(self.venv / "bin" / "proxima")

    def run(self, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [self.proxima, *args],
            cwd=self.home,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )

    def start(self, *args: str) -> subprocess.Popen[str]:
        return subprocess.Popen(
            [self.proxima, *args],
            cwd=self.home,
            env=self.env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )


def _git_status() -> str:
    return subprocess.run(
        ["git", "-C", str(REPO), "status", "--porcelain"], capture_output=True, text=True
    ).stdout


def _copy_checkout(dest: Path) -> None:
    """The files a clone has (tracked, or new and not ignored), plus the built console."""
    listed = subprocess.run(
        ["git", "-C", str(REPO), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        capture_output=True,
        check=True,
    ).stdout.decode()
    for rel in filter(None, listed.split("\0")):
        src = REPO / rel
        if src.is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
    shutil.copytree(STATIC, dest / "static")


def _stop(proc: subprocess.Popen[str]) -> str:
    """Stop a started command by its PID; its output."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.stdout.read() if proc.stdout else ""


def _free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Installed]:
    assert (STATIC / "index.html").is_file(), (
        f"{STATIC} is not built: `make frontend` (the wheel ships the console)"
    )
    before = _git_status()
    root = tmp_path_factory.mktemp("wheel")
    src, dist, venv, home = root / "src", root / "dist", root / "venv", root / "home"
    _copy_checkout(src)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
         "--no-index", "-q", "-w", str(dist), str(src)],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    (wheel,) = dist.glob("proxima-*.whl")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True, text=True, check=True,
    ).stdout.strip()  # fmt: skip
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (Path(purelib) / "_proxima_test_deps.pth").write_text("\n".join(sorted(deps)) + "\n")
    subprocess.run(
        [str(python), "-m", "pip", "install", "--no-deps", "--ignore-installed", "--no-index",
         "-q", str(wheel)],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PROXIMA_", "PYTHON"))}
    env.pop("VIRTUAL_ENV", None)
    env.update(
        PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}",
        XDG_CACHE_HOME=str(root / "cache"),
        PROXIMA_OFFLINE="1",
        PYTHONUNBUFFERED="1",
    )
    yield Installed(wheel, venv, home, env)
    assert _git_status() == before, "building and running the wheel changed the checkout"


def test_the_wheel_carries_the_shipped_files(installed: Installed) -> None:
    names = set(zipfile.ZipFile(installed.wheel).namelist())
    shipped = {
        "proxima/_shipped/models/gesture-default.pt",
        "proxima/_shipped/models/gesture-default.md",
        "proxima/_shipped/models/synth-only-1560.pt",
        "proxima/_shipped/config/demo.toml",
        "proxima/_shipped/config/demo-sim.toml",
        "proxima/_shipped/config/scenes/demo.toml",
        "proxima/_shipped/static/index.html",
        "proxima/drone/mapping.toml",
        "proxima/federated/flower-app/pyproject.toml",
        "proxima/gesture/checksums/laser-uav-gesture.sha256",
        "proxima/store/migrations/script.py.mako",
        "proxima/py.typed",
    }
    assert shipped <= names, sorted(shipped - names)
    assert not [n for n in names if n.startswith("proxima/_shipped/static/.")]
    # The package is imported from the new environment, not from a checkout, and its
    # defaults (model, demo settings, console) are the copies inside it.
    probe = (
        "import proxima, proxima.shipped as s\n"
        "from proxima.demo.cli import DEFAULT_CONFIG\n"
        "from proxima.gesture.classifier import default_checkpoint\n"
        "from proxima.settings import Settings\n"
        "print(s.checkout_root())\n"
        "assert len(Settings.load(DEFAULT_CONFIG).drones) == 3  # the demo's settings load\n"
        "for p in (proxima.__file__, default_checkpoint(), DEFAULT_CONFIG,\n"
        "          Settings().static_dir() / 'index.html', Settings().training.start_path()):\n"
        "    print(p)\n"
    )
    out = subprocess.run(
        [str(installed.venv / "bin" / "python"), "-c", probe],
        cwd=installed.home, env=installed.env, capture_output=True, text=True, check=True,
    ).stdout.split()  # fmt: skip
    assert out[0] == "None", out
    for path in map(Path, out[1:]):
        assert path.is_relative_to(installed.venv) and path.is_file(), path
    # What the wheel requires is installed.
    check = subprocess.run(
        [str(installed.venv / "bin" / "python"), "-m", "pip", "check"],
        cwd=installed.home, env=installed.env, capture_output=True, text=True,
    )  # fmt: skip
    assert check.returncode == 0, check.stdout + check.stderr


def test_help_lists_the_commands(installed: Installed) -> None:
    proc = installed.run("--help")
    assert proc.returncode == 0, proc.stderr
    for command in ("recognize", "serve", "sim-drone", "demo", "train"):
        assert command in proc.stdout
    demo = installed.run("demo", "--help")
    assert demo.returncode == 0, demo.stderr


def test_recognize_a_laser_clip_with_the_shipped_model(installed: Installed, laser_dir) -> None:
    from proxima.ingest.landmark_csv import read_landmark_csv

    clip = laser_dir / CLIP
    events = installed.home / "events.jsonl"
    proc = installed.run("recognize", "--source", f"replay:{clip}@30", "--events", str(events))
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(line) for line in events.read_text().splitlines()]
    poses = [e for e in lines if e["type"] == "pose"]
    assert len(poses) == len(read_landmark_csv(clip))
    gestures = [e["gesture"] for e in lines if e["type"] == "gesture"]
    assert gestures and gestures.count("have_command") > len(gestures) / 2
    commands = [e for e in lines if e["type"] == "command"]
    assert commands[0]["command"] == "have_command" and commands[0]["drone"] == "main"


def test_sim_drone_answers_a_ground_station(installed: Installed) -> None:
    from pymavlink import mavutil

    port = _free_port(socket.SOCK_DGRAM)
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=250)
    sim = installed.start("sim-drone", "--port", str(port), "--sysid", "7")
    try:
        hb = gcs.wait_heartbeat(timeout=30)
        assert hb is not None and gcs.target_system == 7, _stop(sim)
        m = mavutil.mavlink
        # A second station's heartbeat, sent where the simulator speaks from, is answered.
        (sim_addr,) = gcs.clients
        second = mavutil.mavlink_connection(f"udpout:{sim_addr[0]}:{sim_addr[1]}")
        try:
            second.mav.heartbeat_send(m.MAV_TYPE_GCS, m.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            assert second.wait_heartbeat(timeout=5) is not None
        finally:
            second.close()
        modes = {name: number for number, name in mavutil.mode_mapping_acm.items()}
        gcs.mav.command_long_send(
            7, 1, m.MAV_CMD_DO_SET_MODE, 0, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            modes["GUIDED"], 0, 0, 0, 0, 0,
        )  # fmt: skip
        ack = gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=5)
        assert ack is not None and ack.command == m.MAV_CMD_DO_SET_MODE
        assert ack.result == m.MAV_RESULT_ACCEPTED
    finally:
        gcs.close()
        _stop(sim)


def _get(url: str) -> tuple[int, bytes]:
    with urllib.request.urlopen(url, timeout=5) as resp:
        return resp.status, resp.read()


def test_serve_answers_with_the_shipped_console(installed: Installed) -> None:
    port = _free_port(socket.SOCK_STREAM)
    env = {**installed.env, "PROXIMA_ADMIN_USER": ADMIN[0], "PROXIMA_ADMIN_PASSWORD": ADMIN[1]}
    server = subprocess.Popen(
        [installed.proxima, "serve", "--port", str(port), "--db", "runs/console.db", "--no-view"],
        cwd=installed.home, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                status, health = _get(f"{base}/api/health")
                break
            except OSError:
                assert server.poll() is None, _stop(server)
                assert time.monotonic() < deadline, "serve did not answer in 60 s"
                time.sleep(0.5)
        assert status == 200 and json.loads(health)["status"] == "ok"
        status, index = _get(f"{base}/")
        assert status == 200 and index == (STATIC / "index.html").read_bytes()
        assets = re.findall(r'(?:src|href)="\./(assets/[^"]+)"', index.decode())
        assert assets, index[:500]
        for asset in assets:
            status, body = _get(f"{base}/{asset}")
            assert status == 200 and body == (STATIC / asset).read_bytes(), asset
    finally:
        _stop(server)
    assert (installed.home / "runs" / "console.db").is_file()
