"""Logins, roles and the rule that only /api/health is open."""

from __future__ import annotations

import re
from pathlib import Path

from api_helpers import ADMIN, VIEWER, Api, login
from fastapi.testclient import TestClient
from sqlalchemy import select

from proxima.api import create_app
from proxima.events import EventBus
from proxima.settings import Settings
from proxima.store.users import User


def _concrete(path: str) -> str:
    return re.sub(r"\{[^}]+\}", "1", path)


def test_health_is_the_only_open_route(api: Api) -> None:
    c = api.client
    assert c.get("/api/health").json()["status"] == "ok"
    schema = c.get("/api/openapi.json", headers=api.admin).json()
    checked = 0
    for path, methods in schema["paths"].items():
        if path in ("/api/health", "/api/auth/login"):
            continue
        for method in methods:
            r = c.request(method.upper(), _concrete(path))
            assert r.status_code == 401, f"{method} {path} answered {r.status_code}"
            checked += 1
    assert checked >= 20
    assert c.get("/api/openapi.json").status_code == 401
    # A made-up token is no better than none.
    r = c.get("/api/streams", headers={"Authorization": "Bearer not-a-real-token"})
    assert r.status_code == 401


def test_login_logout(api: Api) -> None:
    c = api.client
    assert (
        c.post("/api/auth/login", json={"username": ADMIN[0], "password": "wrong"}).status_code
        == 401
    )
    assert (
        c.post("/api/auth/login", json={"username": "nobody", "password": "x"}).status_code == 401
    )
    headers = login(c, ADMIN)
    me = c.get("/api/auth/me", headers=headers).json()
    assert me == {
        "username": ADMIN[0],
        "role": "supervisor",
        "must_change_password": False,
        "disabled": False,
    }
    assert c.post("/api/auth/logout", headers=headers).status_code == 200
    assert c.get("/api/auth/me", headers=headers).status_code == 401


def test_passwords_are_hashed_with_argon2(api: Api) -> None:
    with api.console.sessions() as db:
        for user in db.scalars(select(User)):
            assert user.password_hash.startswith("$argon2id$")
            assert ADMIN[1] not in user.password_hash and VIEWER[1] not in user.password_hash


def test_viewer_is_read_only(api: Api) -> None:
    c = api.client
    assert c.get("/api/streams", headers=api.viewer).status_code == 200
    assert c.get("/api/samples", headers=api.viewer).status_code == 200
    forbidden = [
        ("POST", "/api/training/runs", {"rounds": 2}),
        ("POST", "/api/samples/recordings", {"stream": "front", "frames": 5}),
        ("PATCH", "/api/samples/1", {"status": "kept", "label": "hover"}),
        ("POST", "/api/models/gesture-default.pt/promote", None),
        ("POST", "/api/drones/main/emergency-stop", None),
        ("POST", "/api/drones/main/emergency-stop/confirm", {"confirmation_id": "x"}),
        ("POST", "/api/users", {"username": "eve", "password": "long-enough-pw", "role": "viewer"}),
    ]
    for method, path, body in forbidden:
        r = c.request(method, path, json=body, headers=api.viewer)
        assert r.status_code == 403, f"{method} {path}: {r.status_code} {r.text}"
        assert "viewer" in r.json()["detail"]


def test_supervisor_manages_users(api: Api) -> None:
    c = api.client
    r = c.post(
        "/api/users",
        json={"username": "eve", "password": "qz7Xw", "role": "viewer"},
        headers=api.admin,
    )
    assert r.status_code == 422 and "at least 10 characters" in r.json()["detail"]
    assert "qz7Xw" not in r.text  # the password itself is never echoed
    r = c.post(
        "/api/users",
        json={"username": "eve", "password": "Administrator", "role": "viewer"},
        headers=api.admin,
    )
    assert r.status_code == 422 and "well-known" in r.json()["detail"]
    r = c.post(
        "/api/users",
        json={"username": "eve", "password": "a-long-passphrase", "role": "viewer"},
        headers=api.admin,
    )
    assert r.status_code == 201
    r = c.post(
        "/api/users",
        json={"username": "eve", "password": "another-passphrase", "role": "viewer"},
        headers=api.admin,
    )
    assert r.status_code == 409 and "already exists" in r.json()["detail"]
    names = [u["username"] for u in c.get("/api/users", headers=api.viewer).json()]
    assert names == [ADMIN[0], VIEWER[0], "eve"]
    assert c.post("/api/users/eve/disable", headers=api.admin).status_code == 200
    r = c.post("/api/auth/login", json={"username": "eve", "password": "a-long-passphrase"})
    assert r.status_code == 401


def test_first_start_without_env_prints_one_time_password(tmp_path: Path) -> None:
    announced: list[tuple[str, str]] = []
    settings = Settings.load(config=None, server={"db_path": str(tmp_path / "c.db")})
    app = create_app(settings, EventBus(), announce=lambda u, p: announced.append((u, p)))
    assert len(announced) == 1
    user, one_time = announced[0]
    with TestClient(app) as c:
        headers = login(c, (user, one_time))
        me = c.get("/api/auth/me", headers=headers).json()
        assert me["must_change_password"] is True
        # Nothing else works until the password is changed.
        assert c.get("/api/streams", headers=headers).status_code == 403
        r = c.post(
            "/api/auth/password",
            headers=headers,
            json={"old_password": one_time, "new_password": "admin"},
        )
        assert r.status_code == 422
        new = {"old_password": one_time, "new_password": "my-own-passphrase"}
        r = c.post("/api/auth/password", headers=headers, json=new)
        assert r.status_code == 200
        assert c.get("/api/streams", headers=headers).status_code == 200
        login(c, (user, "my-own-passphrase"))
    # A second start creates nobody and prints nothing.
    create_app(settings, EventBus(), announce=lambda u, p: announced.append((u, p)))
    assert len(announced) == 1
