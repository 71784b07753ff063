"""`proxima serve` as a real process: it migrates the database, creates the supervisor
from the environment, answers on 127.0.0.1 and stops cleanly on SIGINT."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

REPO = Path(__file__).resolve().parents[2]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_serve_process(tmp_path: Path) -> None:
    port = _free_port()
    env = {
        **os.environ,
        "PROXIMA_ADMIN_USER": "chief",
        "PROXIMA_ADMIN_PASSWORD": "correct-horse-battery",
        "PROXIMA_SERVER__DB_PATH": str(tmp_path / "serve.db"),
        "PROXIMA_SERVER__VISER_ENABLED": "false",
    }
    env.pop("PROXIMA_CONFIG", None)
    proc = subprocess.Popen(
        [sys.executable, "-m", "proxima.cli", "serve", "--port", str(port)],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        url = f"http://127.0.0.1:{port}"
        deadline = time.monotonic() + 60
        while True:
            try:
                if httpx.get(f"{url}/api/health", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            assert proc.poll() is None, proc.stdout.read() if proc.stdout else ""
            assert time.monotonic() < deadline, "serve did not come up"
            time.sleep(0.2)
        assert httpx.get(f"{url}/api/streams").status_code == 401
        r = httpx.post(
            f"{url}/api/auth/login", json={"username": "chief", "password": "correct-horse-battery"}
        )
        assert r.status_code == 200
        headers = {"Authorization": f"Bearer {r.json()['token']}"}
        assert httpx.get(f"{url}/api/streams", headers=headers).json() == []
        page = httpx.get(f"{url}/")
        if (REPO / "static" / "index.html").is_file():
            assert page.status_code == 200 and "Proxima console" in page.text
        else:
            assert page.status_code == 503 and "make frontend" in page.text
        # Only loopback: the port is not open on another local address.
        with socket.socket() as s:
            s.settimeout(1)
            other = socket.gethostbyname(socket.gethostname())
            if not other.startswith("127."):
                assert s.connect_ex((other, port)) != 0
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
    assert proc.returncode in (0, 130, -signal.SIGINT), out
    assert f"http://127.0.0.1:{port}/" in out
    assert (tmp_path / "serve.db").is_file()
