"""The audit log: each supervisor action through the API leaves one row (who, what, to
what, the outcome, from where), supervisors read them with filters and pages, viewers
cannot; and the schema of the audit table comes from its Alembic revision."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from api_helpers import ADMIN, VIEWER, laser_clip, login, make_settings
from fastapi.testclient import TestClient
from runner_double import NoTrainingRunner

from proxima.api import create_app
from proxima.api.app import open_database
from proxima.drone.controller import DroneController, EmergencyStopService
from proxima.drone.memory import MemoryLink
from proxima.events import EventBus
from proxima.ingest import read_landmark_csv
from proxima.store import migrations
from proxima.store.audit import AuditLog
from proxima.store.base import make_engine, make_sessionmaker
from proxima.store.command_log import CommandLog
from proxima.store.samples import add_sample
from proxima.store.users import Role, authenticate, create_user


@pytest.fixture
def console(tmp_path: Path):  # type: ignore[no-untyped-def]
    settings = make_settings(tmp_path, server={
        "db_path": str(tmp_path / "console.db"),
        "viser_enabled": False,
        "models_dir": str(tmp_path / "models"),
    })  # fmt: skip
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "broken.pt").write_bytes(b"not a checkpoint")
    bus = EventBus()
    db = open_database(settings)
    links = {d.name: MemoryLink(d.name) for d in settings.drones}
    for link in links.values():
        link.connect()
    controller = DroneController(links, safety=settings.safety, log=CommandLog(db), bus=bus)
    estop = EmergencyStopService(controller)
    runner = NoTrainingRunner([d.name for d in settings.drones])

    class RefusingPromoter:  # the engine's own check, for a file that is no checkpoint
        def promote(self, checkpoint_path: str) -> dict:
            raise ValueError(f"{checkpoint_path}: not a gesture checkpoint")

        def active_checkpoint(self) -> str | None:
            return None

    app = create_app(
        settings, bus, training=runner, estop=estop, promoter=RefusingPromoter(), db_engine=db
    )
    with app.state.console.sessions() as db:
        create_user(db, VIEWER[0], VIEWER[1], Role.VIEWER)
        track = read_landmark_csv(laser_clip("hover_f"))
        add_sample(
            db, stream="front", drone="main", xyz=track.xyz[:30],
            visibility=track.visibility[:30], times=np.arange(30) / 30.0, created_by="chief",
        )  # fmt: skip
    with TestClient(app) as client:
        yield client


def test_every_supervisor_action_is_recorded(console: TestClient) -> None:
    c = console
    t0 = time.time()
    admin = login(c, ADMIN)
    c.post("/api/users", headers=admin,
           json={"username": "eve", "password": "a-long-passphrase", "role": "viewer"})  # fmt: skip
    c.post("/api/users/eve/disable", headers=admin)
    step = c.post("/api/drones/main/emergency-stop", headers=admin).json()
    c.post("/api/drones/main/emergency-stop/confirm", headers=admin,
           json={"confirmation_id": "not-the-id"})  # fmt: skip
    stopped = c.post("/api/drones/main/emergency-stop/confirm", headers=admin,
                     json={"confirmation_id": step["confirmation_id"]})  # fmt: skip
    assert stopped.status_code == 200, stopped.text
    run = c.post("/api/training/runs", headers=admin, json={"rounds": 2}).json()["id"]
    assert c.post("/api/training/runs", headers=admin, json={}).status_code == 409
    assert c.post(f"/api/training/runs/{run}/cancel", headers=admin).status_code == 202
    assert c.post(f"/api/training/runs/{run}/cancel", headers=admin).status_code == 409
    assert c.post("/api/models/broken.pt/promote", headers=admin).status_code == 409
    c.patch("/api/samples/1", headers=admin, json={"status": "kept", "label": "hover"})
    c.patch("/api/samples/1", headers=admin, json={"status": "deleted"})
    c.post("/api/auth/logout", headers=admin)

    admin = login(c, ADMIN)
    page = c.get("/api/audit?limit=500", headers=admin).json()
    rows = [(e["actor"], e["action"], e["target"], e["outcome"]) for e in page["entries"]]
    assert list(reversed(rows)) == [
        ("chief", "auth.login", "chief", "ok"),
        ("chief", "user.create", "eve", "ok"),
        ("chief", "user.disable", "eve", "ok"),
        ("chief", "drone.stop_request", "main", "ok"),
        ("chief", "drone.stop", "main", "refused"),
        ("chief", "drone.stop", "main", "ok"),
        ("chief", "training.start", run, "ok"),
        ("chief", "training.start", "", "refused"),
        ("chief", "training.cancel", run, "ok"),
        ("chief", "training.cancel", run, "refused"),
        ("chief", "model.promote", "broken.pt", "refused"),
        ("chief", "sample.keep", "1", "ok"),
        ("chief", "sample.delete", "1", "ok"),
        ("chief", "auth.logout", "chief", "ok"),
        ("chief", "auth.login", "chief", "ok"),
    ]
    entries = {(e["action"], e["outcome"]): e for e in page["entries"]}
    assert all(e["client"] == "testclient" and e["ts"] >= t0 for e in page["entries"])
    assert entries[("training.start", "ok")]["detail"]["params"] == {"rounds": 2}
    assert "in progress" in entries[("training.start", "refused")]["detail"]["reason"]
    assert entries[("drone.stop", "ok")]["detail"]["log_id"]
    assert entries[("sample.keep", "ok")]["detail"] == {"drone": "main", "label": "hover"}
    assert "not a readable checkpoint" in entries[("model.promote", "refused")]["detail"]["reason"]
    assert page["next_before_id"] is None


def test_filters_and_pages(console: TestClient) -> None:
    c = console
    admin = login(c, ADMIN)
    login(c, VIEWER)
    c.post("/api/auth/login", json={"username": "chief", "password": "wrong"})
    for name in ("ann", "bob", "cid"):
        body = {"username": name, "password": "a-long-passphrase", "role": "viewer"}
        c.post("/api/users", headers=admin, json=body)

    def get(query: str) -> dict:
        r = c.get(f"/api/audit?{query}", headers=admin)
        assert r.status_code == 200, r.text
        return r.json()

    assert [e["target"] for e in get("action=user")["entries"]] == ["cid", "bob", "ann"]
    assert [e["actor"] for e in get("action=auth.login")["entries"]] == ["watcher", "chief"]
    assert [e["action"] for e in get("outcome=refused")["entries"]] == ["auth.login_failed"]
    assert get("actor=watcher&action=user")["entries"] == []
    assert len(get("target=bob")["entries"]) == 1
    everything = get("limit=500")["entries"]
    middle = everything[3]["ts"]
    assert {e["id"] for e in get(f"until={middle}")["entries"]} == {
        e["id"] for e in everything if e["ts"] <= middle
    }
    assert {e["id"] for e in get(f"since={middle}")["entries"]} == {
        e["id"] for e in everything if e["ts"] >= middle
    }
    # Pages of two, newest first, end to end.
    seen, before = [], None
    while True:
        page = get("limit=2" + (f"&before_id={before}" if before else ""))
        seen += [e["id"] for e in page["entries"]]
        if page["next_before_id"] is None:
            break
        before = page["next_before_id"]
    assert seen == [e["id"] for e in everything] and len(seen) == 6
    r = c.get("/api/audit?action=DROP%20TABLE", headers=admin)
    assert r.status_code == 422 and r.json()["errors"][0]["loc"] == ["query", "action"]


def test_only_supervisors_read_it(console: TestClient) -> None:
    r = console.get("/api/audit", headers=login(console, VIEWER))
    assert r.status_code == 403 and "viewer" in r.json()["detail"]
    assert console.get("/api/audit").status_code == 401


def test_the_revision_creates_the_table_and_rows_survive_an_upgrade(tmp_path: Path) -> None:
    engine = make_engine(tmp_path / "old.db")
    migrations.upgrade(engine, "0003")  # before the audit log
    with make_sessionmaker(engine)() as db:
        create_user(db, "chief", "correct-horse-battery", "supervisor")
    migrations.upgrade(engine)
    assert migrations.current_revision(engine) == "0004"
    with make_sessionmaker(engine)() as db:
        assert authenticate(db, "chief", "correct-horse-battery") is not None
    log = AuditLog(engine)
    # A hostile user name longer than the column is cut, not a failed write.
    first = log.record(actor="x" * 500, action="auth.login_failed", outcome="refused")
    got = log.query()[0]
    assert got.id == first and got.actor == "x" * 64 and got.outcome == "refused"
