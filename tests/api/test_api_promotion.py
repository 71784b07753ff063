"""Guarded promotion: a candidate's figures beside the model in use's on the held-out
synthetic set, a worse one refused unless overridden with a reason, the history from the
audit log, rollback, and the promoted model kept over a restart."""

from __future__ import annotations

import shutil
from pathlib import Path

import httpx
from api_helpers import ADMIN, laser_clip

from proxima.api.runtime import build_runtime
from proxima.api.server import BackgroundServer
from proxima.settings import Settings


def _settings(tmp_path: Path, models: Path) -> Settings:
    return Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        streams=[{"name": "front", "uri": f"replay:{laser_clip('hover_f')}@30", "drone": "main"}],
        engine={"checkpoint": str(models / "gesture-default.pt")},
        server={"db_path": str(tmp_path / "c.db"), "models_dir": str(models)},
    )


def _login(url: str) -> dict[str, str]:
    r = httpx.post(f"{url}/api/auth/login", json={"username": ADMIN[0], "password": ADMIN[1]})
    return {"Authorization": f"Bearer {r.json()['token']}"}


def test_guarded_promotion_history_rollback_and_restart(
    tmp_path: Path, checkpoint_path: Path, degraded_checkpoint: Path
) -> None:
    models = tmp_path / "models"
    (models / "runs").mkdir(parents=True)
    shutil.copy(checkpoint_path, models / "gesture-default.pt")
    shutil.copy(checkpoint_path, models / "runs" / "same.pt")
    shutil.copy(degraded_checkpoint, models / "runs" / "worse.pt")
    settings = _settings(tmp_path, models)
    runtime = build_runtime(settings, engine=True, drones=False, view=False)
    assert runtime.engine is not None, runtime.notes
    t = 120.0
    try:
        with BackgroundServer(runtime.app) as server:
            h = _login(server.url)
            get = lambda p: httpx.get(f"{server.url}/api{p}", headers=h, timeout=t)  # noqa: E731
            post = lambda p, **kw: httpx.post(f"{server.url}/api{p}", headers=h, timeout=t, **kw)  # noqa: E731

            r = get("/models/runs/worse.pt/evaluation")
            assert r.status_code == 200, r.text
            cmp = r.json()
            assert (
                cmp["set"] == "synthetic" and "no model here trained on" in cmp["set_description"]
            )
            cand, act = cmp["candidate"]["figures"], cmp["active"]["figures"]
            assert cmp["active"]["name"] == "gesture-default.pt"
            assert cand["accuracy"] < act["accuracy"] - 0.1, (cand, act)
            assert cand["abort_recall"] < act["abort_recall"]
            assert any("wave_off" in c for c in cmp["concerns"])
            # The table shows figures once evaluated.
            listed = {m["name"]: m for m in get("/models").json()["models"]}
            assert listed["runs/worse.pt"]["figures"]["accuracy"] == cand["accuracy"]

            before = runtime.engine.pipelines["front"].classifier
            r = post("/models/runs/worse.pt/promote")
            assert r.status_code == 409, r.text
            assert "override reason" in r.json()["detail"] and "below" in r.json()["detail"]
            assert runtime.engine.pipelines["front"].classifier is before
            r = post("/models/runs/worse.pt/promote", json={"override_reason": "  "})
            assert r.status_code == 409

            r = post("/models/runs/worse.pt/promote", json={"override_reason": "field test"})
            assert r.status_code == 200, r.text
            assert r.json()["previous"] == "gesture-default.pt"
            assert runtime.engine.pipelines["front"].classifier is not before
            active = get("/models/active").json()
            assert active["name"] == "runs/worse.pt" and active["by"] == ADMIN[0]
            assert active["rollback_to"] == "gesture-default.pt"
            assert active["figures"]["accuracy"] == cand["accuracy"]
            hist = get("/models/history").json()["history"]
            assert [x["checkpoint"] for x in hist] == ["runs/worse.pt"]
            assert hist[0]["override_reason"] == "field test"
            assert hist[0]["previous_figures"]["accuracy"] == act["accuracy"]

            r = post("/models/rollback")
            assert r.status_code == 200, r.text
            assert r.json()["promoted"] == "gesture-default.pt"
            assert get("/models/active").json()["name"] == "gesture-default.pt"

            # An equal model needs no override.
            r = post("/models/runs/same.pt/promote")
            assert r.status_code == 200, r.text
            audit = get("/audit?action=model").json()["entries"]
            assert [(e["action"], e["outcome"]) for e in audit] == [
                ("model.promote", "ok"),
                ("model.rollback", "ok"),
                ("model.promote", "ok"),
                ("model.promote", "refused"),
                ("model.promote", "refused"),
            ]
    finally:
        runtime.close()

    # A restart keeps the promoted model.
    runtime = build_runtime(settings, engine=True, drones=False, view=False)
    try:
        assert runtime.promoter is not None
        assert Path(runtime.promoter.active_checkpoint() or "").name == "same.pt"
        assert any("runs/same.pt" in n for n in runtime.notes), runtime.notes
    finally:
        runtime.close()
