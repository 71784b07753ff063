"""Emergency stop through the API: two explicit steps, against a real simulated vehicle
(`proxima sim-drone` over MAVLink/UDP on 127.0.0.1)."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest
from api_helpers import ADMIN, VIEWER, Api

from proxima.api.runtime import build_runtime
from proxima.api.server import BackgroundServer
from proxima.settings import Settings
from proxima.store.users import Role, create_user

PROXIMA = str(Path(sys.executable).with_name("proxima"))


def test_without_a_drone_link_it_is_unavailable(api: Api) -> None:
    r = api.client.post("/api/drones/main/emergency-stop", headers=api.admin)
    assert r.status_code == 503 and "no drone link" in r.json()["detail"]
    assert api.client.post("/api/drones/ghost/emergency-stop", headers=api.admin).status_code == 404


@pytest.mark.slow
def test_two_steps_against_a_simulated_drone(tmp_path: Path) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    sim = subprocess.Popen(
        [PROXIMA, "sim-drone", "--port", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    settings = Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        drones=[{"name": "main", "connection": f"udpin:127.0.0.1:{port}"}],
        server={"db_path": str(tmp_path / "c.db")},
        safety={"estop_confirm_s": 8.0},
    )
    runtime = build_runtime(settings, engine=False, view=False)
    try:
        assert runtime.links["main"].state == "ok", runtime.notes
        assert runtime.drones.safety.cfg is settings.safety  # the [safety] section itself
        with runtime.app.state.console.sessions() as db:
            create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
        with BackgroundServer(runtime.app) as server:

            def login(user: tuple[str, str]) -> dict[str, str]:
                r = httpx.post(
                    f"{server.url}/api/auth/login", json={"username": user[0], "password": user[1]}
                )
                return {"Authorization": f"Bearer {r.json()['token']}"}

            admin, viewer = login(ADMIN), login(VIEWER)
            base = f"{server.url}/api/drones/main/emergency-stop"
            step1 = httpx.post(base, headers=admin).json()
            assert step1["confirmed"] is False and step1["confirmation_id"]
            assert step1["expires_in_s"] == 8.0  # [safety] estop_confirm_s
            # A viewer cannot confirm, a wrong id changes nothing.
            body = {"confirmation_id": step1["confirmation_id"]}
            assert httpx.post(f"{base}/confirm", headers=viewer, json=body).status_code == 403
            bad = httpx.post(f"{base}/confirm", headers=admin, json={"confirmation_id": "nope"})
            assert bad.status_code == 409
            log = httpx.get(f"{server.url}/api/commands?drone=main", headers=admin).json()
            assert all(row["status"] != "sent" for row in log)
            r = httpx.post(f"{base}/confirm", headers=admin, json=body)
            assert r.status_code == 200, r.text
            assert r.json()["confirmed"] is True and r.json()["log_id"]
            # The id is single-use.
            assert httpx.post(f"{base}/confirm", headers=admin, json=body).status_code == 409
            time.sleep(0.2)
            log = httpx.get(f"{server.url}/api/commands?drone=main", headers=admin).json()
            assert any(r["command"] == "emergency_stop" and r["status"] == "sent" for r in log)
    finally:
        runtime.close()
        sim.terminate()
        sim.wait(10)
