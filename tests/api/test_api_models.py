"""Models: checkpoints listed with their cards, and promotion into the running engine."""

from __future__ import annotations

import shutil
from pathlib import Path

import httpx
from api_helpers import ADMIN, laser_clip

from proxima.api.runtime import build_runtime
from proxima.api.server import BackgroundServer
from proxima.settings import Settings


def test_list_and_promote_into_the_live_engine(tmp_path: Path, checkpoint_path: Path) -> None:
    checkpoint = checkpoint_path
    models = tmp_path / "models"
    (models / "runs").mkdir(parents=True)
    shutil.copy(checkpoint, models / "gesture-default.pt")
    shutil.copy(checkpoint, models / "runs" / "fedavg-r5.pt")
    (models / "runs" / "fedavg-r5.md").write_text("# FedAvg, 5 rounds\naccuracy 0.5\n")
    (models / "broken.pt").write_bytes(b"not a checkpoint")
    settings = Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        streams=[{"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30", "drone": "main"}],
        engine={"checkpoint": str(models / "gesture-default.pt")},
        server={"db_path": str(tmp_path / "c.db"), "models_dir": str(models)},
    )
    runtime = build_runtime(settings, engine=True, drones=False, view=False)
    assert runtime.engine is not None, runtime.notes
    try:
        with BackgroundServer(runtime.app) as server:
            r = httpx.post(
                f"{server.url}/api/auth/login", json={"username": ADMIN[0], "password": ADMIN[1]}
            )
            h = {"Authorization": f"Bearer {r.json()['token']}"}
            listed = httpx.get(f"{server.url}/api/models", headers=h).json()
            assert listed["promotion_available"] is True
            by_name = {m["name"]: m for m in listed["models"]}
            assert set(by_name) == {"gesture-default.pt", "runs/fedavg-r5.pt", "broken.pt"}
            assert by_name["gesture-default.pt"]["active"] is True
            assert by_name["runs/fedavg-r5.pt"]["card"]["content"].startswith("# FedAvg")
            before = runtime.engine.pipelines["front"].classifier

            r = httpx.post(
                f"{server.url}/api/models/runs/fedavg-r5.pt/promote", headers=h, timeout=120
            )
            assert r.status_code == 200, r.text
            assert r.json()["streams"] == ["front"] and r.json()["pending"] == []
            after = runtime.engine.pipelines["front"].classifier
            assert after is not before and after.window == before.window
            listed = httpx.get(f"{server.url}/api/models", headers=h).json()
            active = [m["name"] for m in listed["models"] if m["active"]]
            assert active == ["runs/fedavg-r5.pt"]

            # Not a checkpoint the engine can run: refused by its state (409), not the schema.
            r = httpx.post(f"{server.url}/api/models/broken.pt/promote", headers=h, timeout=120)
            assert r.status_code == 409 and "broken.pt" in r.json()["detail"]
            assert runtime.engine.pipelines["front"].classifier is after
            r = httpx.post(f"{server.url}/api/models/..%2Fc.db/promote", headers=h, timeout=120)
            assert r.status_code == 404
    finally:
        runtime.close()
