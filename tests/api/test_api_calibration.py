"""Guided calibration through the API: takes recorded from a replayed LASER stream by the
live engine, the model's reading of each, a redo, the fine-tuning in the background,
before/after figures on the held-out parts, promotion for that stream only (guarded,
audited) and kept over a restart; and the refusals, each with a reason."""

from __future__ import annotations

import time
from pathlib import Path

import httpx
import numpy as np
import pytest
from api_helpers import ADMIN, Api, laser_clip, login, make_settings
from fastapi.testclient import TestClient

from proxima.api import create_app
from proxima.api.feed import ReplayPoseFeed
from proxima.api.runtime import build_runtime
from proxima.api.server import BackgroundServer
from proxima.events import EventBus
from proxima.gesture.ensemble import load_checkpoint, members_of
from proxima.ingest import read_landmark_csv
from proxima.ingest.landmark_csv import write_landmark_csv
from proxima.settings import Settings
from proxima.store.samples import Sample, kept_samples


def long_replay(path: Path, names: list[str]) -> Path:
    """LASER clips one after the other as one replay file (real landmarks, longer than
    one clip, so a stream keeps a person in sight for several takes)."""
    tracks = [read_landmark_csv(laser_clip(n)) for n in names]
    frames, offset = [], 0
    for t in tracks:
        frames.append(t.frames - t.frames[0] + 1 + offset)
        offset = int(frames[-1][-1]) + 15  # half a second without a person between clips
    write_landmark_csv(
        path,
        np.concatenate(frames),
        np.concatenate([t.xyz for t in tracks]),
        np.concatenate([t.visibility for t in tracks]),
    )
    return path


def _wait(get, pred, timeout: float, what: str) -> dict:  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        body = get()
        if pred(body):
            return body
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}: {body}")


@pytest.mark.slow
def test_calibrate_a_stream_and_promote_for_it_only(tmp_path: Path, checkpoint_path: Path) -> None:
    replay = long_replay(tmp_path / "front.csv", ["move_downward_f", "hover_f", "all_clear_f"])
    models = tmp_path / "models"
    settings = Settings.load(
        config=None,
        admin_user=ADMIN[0],
        admin_password=ADMIN[1],
        streams=[
            {"name": "front", "uri": f"replay:{replay}@30", "drone": "main"},
            {"name": "left", "uri": f"replay:{laser_clip('hover_l')}@30", "drone": "second"},
        ],
        engine={"checkpoint": str(checkpoint_path)},
        server={"db_path": str(tmp_path / "c.db"), "models_dir": str(models)},
    )
    runtime = build_runtime(settings, engine=True, drones=False, view=False)
    assert runtime.engine is not None, runtime.notes
    # federated runs train models of the live model's window length by default
    assert runtime.training is not None, runtime.notes
    assert runtime.training.defaults.window == runtime.engine.classifier("front").window
    console = runtime.app.state.console
    try:
        with BackgroundServer(runtime.app) as server:
            r = httpx.post(
                f"{server.url}/api/auth/login", json={"username": ADMIN[0], "password": ADMIN[1]}
            )
            h = {"Authorization": f"Bearer {r.json()['token']}"}
            get = lambda p: httpx.get(f"{server.url}/api{p}", headers=h, timeout=60)  # noqa: E731
            post = lambda p, **kw: httpx.post(f"{server.url}/api{p}", headers=h, timeout=60, **kw)  # noqa: E731

            r = post(
                "/calibration",
                json={
                    "stream": "front",
                    "gestures": ["wave_off", "move_downward"],
                    "frames": 180,
                    "countdown_s": 0.3,
                    "epochs": 3,
                },
            )
            assert r.status_code == 201, r.text
            s = r.json()
            sid = s["id"]
            # the classifier's order, a prompt for each, nothing recorded yet
            assert [t["gesture"] for t in s["takes"]] == ["move_downward", "wave_off"]
            assert all(t["description"] and t["state"] == "todo" for t in s["takes"])
            assert s["model"] == str(checkpoint_path) and s["done"] == 0
            r = post(f"/calibration/{sid}/train")
            assert r.status_code == 409 and "record a take of" in r.json()["detail"]

            def take(gesture: str) -> dict:
                r = post(f"/calibration/{sid}/takes", json={"gesture": gesture})
                assert r.status_code == 202, r.text
                assert (
                    post(f"/calibration/{sid}/takes", json={"gesture": gesture}).status_code == 409
                )
                body = _wait(
                    lambda: get(f"/calibration/{sid}").json(),
                    lambda b: all(t["state"] != "recording" for t in b["takes"]),
                    30,
                    f"the take of {gesture}",
                )
                return next(t for t in body["takes"] if t["gesture"] == gesture)

            down = take("move_downward")
            assert down["state"] == "done" and down["frames"] == 180, down
            # the stream performs move_downward: the model's reading says so, no warning
            assert down["reading"]["gesture"] == "move_downward" and not down["warn"], down
            # a wrong prompt on purpose: the model disagrees and the take is flagged
            wave = take("wave_off")
            assert wave["warn"] and wave["reading"]["gesture"] != "wave_off", wave
            first = wave["sample_id"]
            wave = take("wave_off")  # redo: the earlier sample is marked deleted, not lost
            assert wave["replaced"] == [first] and wave["sample_id"] != first
            with console.sessions() as db:
                assert db.get(Sample, first).status == "deleted"
                kept = kept_samples(db, "main")
            assert sorted(k.label for k in kept) == ["move_downward", "wave_off"]

            r = post(f"/calibration/{sid}/train")
            assert r.status_code == 202, r.text
            s = _wait(
                lambda: get(f"/calibration/{sid}").json(),
                lambda b: b["state"] in ("trained", "failed"),
                120,
                "training",
            )
            assert s["state"] == "trained", s
            assert s["epoch"] == 3 and s["candidate"].startswith("calibration/front-")
            shipped = members_of(load_checkpoint(None))  # the shipped ensemble, member by member
            assert s["member"] == s["members"] == len(shipped) > 1
            for fig in (s["before"], s["after"]):
                assert set(fig["per_gesture"]) == {"move_downward", "wave_off"}
                assert fig["windows"] > 0 and 0 <= fig["accuracy"] <= 1
            assert (models / s["candidate"]).is_file()
            card = get("/models").json()["models"]
            assert any(m["name"] == s["candidate"] and m["card"]["format"] == "json" for m in card)

            left_before = runtime.engine.pipelines["left"].classifier
            front_before = runtime.engine.pipelines["front"].classifier
            body = {"override_reason": "calibration test"} if s["concerns"] else None
            r = post(f"/calibration/{sid}/promote", json=body)
            assert r.status_code == 200, r.text
            assert r.json()["streams"] == ["front"] and r.json()["stream"] == "front"
            assert runtime.engine.pipelines["front"].classifier is not front_before
            assert runtime.engine.pipelines["left"].classifier is left_before
            active = get("/models/active").json()
            assert active["streams"] == {"front": s["candidate"]}
            assert active["name"] == str(checkpoint_path)  # the other streams' model
            audit = get("/audit?action=model.promote_stream").json()["entries"]
            assert audit[0]["target"] == s["candidate"] and audit[0]["detail"]["stream"] == "front"
            assert get(f"/calibration/{sid}").json()["state"] == "promoted"
            # The demo's engine restart keeps the stream's own model (and the others' common one).
            engine = runtime.restart_engine()
            split = lambda name: engine.pipelines[name].classifier.metadata.get("split")  # noqa: E731
            _wait(lambda: split("front"), lambda v: v == "console-calibration", 15, "front's model")
            assert split("left") != "console-calibration"
    finally:
        runtime.close()

    # A restart puts the stream's own model back; the other stream keeps the common one.
    again = build_runtime(settings, engine=True, drones=False, view=False)
    try:
        assert again.promoter is not None
        assert Path(again.promoter.active_checkpoint("front")).name == Path(s["candidate"]).name
        assert again.promoter.active_checkpoint("left") == str(checkpoint_path)
        assert any("stream front" in n for n in again.notes), again.notes
    finally:
        again.close()


def test_calibration_refusals(api: Api) -> None:
    c, h = api.client, api.admin
    r = c.post("/api/calibration", headers=h, json={"stream": "nowhere"})
    assert r.status_code == 404 and "nowhere" in r.json()["detail"]
    r = c.post("/api/calibration", headers=h, json={"stream": "front", "frames": 100})
    assert r.status_code == 422 and r.json()["errors"][0]["loc"] == ["body", "frames"]
    r = c.post("/api/calibration", headers=h, json={"stream": "front", "gestures": ["fly"]})
    assert r.status_code == 422
    r = c.post("/api/calibration", headers=api.viewer, json={"stream": "front"})
    assert r.status_code == 403
    # the page's bounds are the request schema's
    form = c.get("/api/config", headers=api.viewer).json()["calibration_form"]
    assert form["frames"]["minimum"] == 180 and form["epochs"]["maximum"] == 40

    r = c.post(
        "/api/calibration",
        headers=h,
        json={"stream": "front", "gestures": ["hover"], "frames": 180, "countdown_s": 0},
    )
    assert r.status_code == 201
    s = r.json()
    assert len(s["takes"]) == 1 and not s["promotion_available"]
    sid = s["id"]
    r = c.post(f"/api/calibration/{sid}/takes", headers=h, json={"gesture": "land"})
    assert r.status_code == 409 and "not one of this calibration's gestures" in r.json()["detail"]
    # no person before the camera (nothing on the stream): the take fails, saying why
    api.console.recorder.pose_timeout_s = 0.5
    assert (
        c.post(f"/api/calibration/{sid}/takes", headers=h, json={"gesture": "hover"}).status_code
        == 202
    )
    body = _wait(
        lambda: c.get(f"/api/calibration/{sid}", headers=api.viewer).json(),
        lambda b: b["takes"][0]["state"] != "recording",
        10,
        "the take",
    )
    assert body["takes"][0]["state"] == "failed"
    assert "no pose from stream 'front'" in body["takes"][0]["detail"]
    r = c.post(f"/api/calibration/{sid}/train", headers=h)
    assert r.status_code == 409 and "record a take of hover" in r.json()["detail"]
    r = c.post(f"/api/calibration/{sid}/promote", headers=h)
    assert r.status_code == 409 and "train the calibration first" in r.json()["detail"]
    assert c.get("/api/calibration/nope", headers=h).status_code == 404
    assert [x["id"] for x in c.get("/api/calibration", headers=api.viewer).json()] == [sid]


@pytest.mark.slow
def test_a_training_failure_is_shown_and_keeps_the_takes(tmp_path: Path) -> None:
    blocker = tmp_path / "models"
    blocker.write_text("a file where the models folder should be")
    settings = make_settings(
        tmp_path,
        server={
            "db_path": str(tmp_path / "c.db"),
            "viser_enabled": False,
            "models_dir": str(blocker),
        },
    )
    bus = EventBus()
    app = create_app(settings, bus)
    with TestClient(app) as c, ReplayPoseFeed(bus, {"front": settings.stream("front").uri}):
        h = login(c, ADMIN)
        s = c.post(
            "/api/calibration",
            headers=h,
            json={
                "stream": "front",
                "gestures": ["hover"],
                "frames": 180,
                "countdown_s": 0,
                "epochs": 1,
            },
        ).json()
        assert (
            c.post(
                f"/api/calibration/{s['id']}/takes", headers=h, json={"gesture": "hover"}
            ).status_code
            == 202
        )
        get = lambda: c.get(f"/api/calibration/{s['id']}", headers=h).json()  # noqa: E731
        body = _wait(get, lambda b: b["takes"][0]["state"] != "recording", 20, "the take")
        assert body["takes"][0]["state"] == "done", body
        assert body["takes"][0]["reading"]["gesture"] == "hover"  # the shipped model's reading
        assert c.post(f"/api/calibration/{s['id']}/train", headers=h).status_code == 202
        body = _wait(get, lambda b: b["state"] != "training", 60, "training")
        assert body["state"] == "failed" and str(blocker) in body["detail"], body
        with app.state.console.sessions() as db:
            assert [k.label for k in kept_samples(db, "main")] == ["hover"]
        # the page may train again once the cause is fixed: the session still holds the take
        assert body["done"] == 1 and body["takes"][0]["sample_id"] is not None
