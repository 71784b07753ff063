"""Recording and labelling samples from a replayed LASER stream, through the API."""

from __future__ import annotations

import time

import numpy as np
from api_helpers import Api, laser_clip

from proxima.api.feed import ReplayPoseFeed
from proxima.ingest import read_landmark_csv
from proxima.store.samples import kept_samples


def _wait_recording(api: Api, rec_id: str, timeout: float = 20.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        rec = api.client.get(f"/api/samples/recordings/{rec_id}", headers=api.viewer).json()
        if rec["state"] in ("done", "failed"):
            return rec
        time.sleep(0.05)
    raise AssertionError(f"recording {rec_id} still {rec['state']}")


def test_record_review_keep_and_list(api: Api) -> None:
    c = api.client
    uri = api.settings.stream("front").uri
    with ReplayPoseFeed(api.bus, {"front": uri}, loop=False):
        r = c.post(
            "/api/samples/recordings",
            headers=api.admin,
            json={"stream": "front", "frames": 30, "countdown_s": 0.5},
        )
        assert r.status_code == 202, r.text
        rec = _wait_recording(api, r.json()["id"])
    assert rec["state"] == "done", rec
    assert rec["frames_done"] == 30 and rec["drone"] == "main"
    sample_id = rec["sample_id"]

    detail = c.get(f"/api/samples/{sample_id}", headers=api.viewer).json()
    assert detail["status"] == "pending" and detail["label"] is None
    assert len(detail["xyz"]) == 30 and len(detail["xyz"][0]) == 33
    # The recorded landmarks are the clip's own, in order (30 consecutive frames).
    track = read_landmark_csv(laser_clip("hover_f"))
    xyz = np.asarray(detail["xyz"])
    first = round(detail["times"][0] * 30)
    k = int(np.searchsorted(track.frames, first + 1))
    np.testing.assert_allclose(xyz, track.xyz[k : k + 30], atol=2e-4)
    assert np.all(np.diff(detail["times"]) > 0)

    # Keeping a sample that has no label is refused by its state (409); an unknown
    # gesture by the schema (422, naming the field).
    r = c.patch(f"/api/samples/{sample_id}", headers=api.admin, json={"status": "kept"})
    assert r.status_code == 409 and "label" in r.json()["detail"]
    r = c.patch(
        f"/api/samples/{sample_id}",
        headers=api.admin,
        json={"status": "kept", "label": "not_a_gesture"},
    )
    assert r.status_code == 422 and r.json()["errors"][0]["loc"] == ["body", "label"]
    r = c.patch(
        f"/api/samples/{sample_id}", headers=api.admin, json={"status": "kept", "label": "hover"}
    )
    assert r.status_code == 200 and r.json()["status"] == "kept"

    listed = c.get("/api/samples?drone=main&status=kept", headers=api.viewer).json()
    assert [s["id"] for s in listed] == [sample_id] and listed[0]["label"] == "hover"
    assert c.get("/api/samples?drone=second", headers=api.viewer).json() == []
    with api.console.sessions() as db:
        kept = kept_samples(db, "main")
    assert len(kept) == 1 and kept[0].label == "hover" and kept[0].xyz.shape == (30, 33, 3)

    r = c.patch(f"/api/samples/{sample_id}", headers=api.admin, json={"status": "deleted"})
    assert r.json()["status"] == "deleted"
    with api.console.sessions() as db:
        assert kept_samples(db, "main") == []
    assert c.get("/api/samples?status=deleted", headers=api.viewer).json()[0]["id"] == sample_id


def test_recording_without_poses_fails_clearly(api: Api) -> None:
    api.console.recorder.pose_timeout_s = 0.5
    r = api.client.post(
        "/api/samples/recordings",
        headers=api.admin,
        json={"stream": "left", "frames": 10, "countdown_s": 0},
    )
    rec = _wait_recording(api, r.json()["id"])
    assert rec["state"] == "failed"
    assert "no pose from stream 'left'" in rec["detail"] and "0 of 10" in rec["detail"]


def test_bad_recording_requests(api: Api) -> None:
    c = api.client
    r = c.post("/api/samples/recordings", headers=api.admin, json={"stream": "nope"})
    assert r.status_code == 404
    r = c.post("/api/samples/recordings", headers=api.admin, json={"stream": "front", "frames": 0})
    assert r.status_code == 422
    r = c.post(
        "/api/samples/recordings", headers=api.admin, json={"stream": "front", "label": "dance"}
    )
    assert r.status_code == 422
    api.console.recorder.pose_timeout_s = 0.5
    r = c.post(
        "/api/samples/recordings",
        headers=api.admin,
        json={"stream": "front", "frames": 5, "countdown_s": 1},
    )
    assert r.status_code == 202
    again = c.post("/api/samples/recordings", headers=api.admin, json={"stream": "front"})
    assert again.status_code == 409 and "already running" in again.json()["detail"]
    assert c.get("/api/samples/999", headers=api.viewer).status_code == 404
