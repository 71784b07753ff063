"""The 3D view through the console: a real viser server on 127.0.0.1 behind the
console's `/viser/` proxy (its page and its WebSocket), reachable only with a console
session carried by the `proxima_view` cookie; the browser is never told viser's port."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
import viser
import websockets
from api_helpers import ADMIN, make_settings
from websockets.asyncio.client import connect

from proxima.api.routers import view as view_router
from proxima.api.runtime import ConsoleRuntime, build_runtime
from proxima.api.server import BackgroundServer

SUBPROTOCOL = websockets.Subprotocol(f"viser-v{viser.__version__}")


@pytest.fixture
def console(tmp_path: Path) -> Iterator[tuple[ConsoleRuntime, BackgroundServer]]:
    settings = make_settings(tmp_path, server={
        "db_path": str(tmp_path / "console.db"),
        "viser_enabled": True,
        "viser_port": 0,
    })  # fmt: skip
    runtime = build_runtime(settings, engine=False, drones=False, training=False)
    assert runtime.view is not None, runtime.notes
    server = BackgroundServer(runtime.app).start()
    try:
        yield runtime, server
    finally:
        server.stop()
        runtime.close()


def _login(client: httpx.Client) -> tuple[str, httpx.Response]:
    r = client.post("/api/auth/login", json={"username": ADMIN[0], "password": ADMIN[1]})
    assert r.status_code == 200, r.text
    return r.json()["token"], r


def test_the_page_needs_a_session_and_the_browser_never_learns_the_port(console) -> None:  # type: ignore[no-untyped-def]
    runtime, server = console
    assert runtime.view.host == "127.0.0.1"
    with httpx.Client(base_url=server.url, timeout=10) as c:
        r = c.get("/viser/")
        assert r.status_code == 401 and "log in" in r.json()["detail"]
        token, login = _login(c)
        cookie = login.headers["set-cookie"]
        for attribute in ("proxima_view=", "HttpOnly", "Path=/viser", "SameSite=strict"):
            assert attribute.lower() in cookie.lower(), cookie
        page = c.get("/viser/")
        assert page.status_code == 200 and "<html" in page.text.lower()
        assert page.headers["cache-control"] == "no-store"
        direct = httpx.get(f"http://127.0.0.1:{runtime.view.port}/", timeout=10)
        assert page.content == direct.content  # viser's own page, through the console
        assert c.get("/viser", follow_redirects=False).headers["location"] == "/viser/"
        # The cookie opens the view only: the API stays bearer-only.
        assert c.get("/api/streams").status_code == 401
        config = c.get("/api/config", headers={"Authorization": f"Bearer {token}"}).json()
        assert config["view_url"] == "/viser/"
        assert str(runtime.view.port) not in json.dumps(config)
        # Logging out ends the cookie's session too.
        c.post("/api/auth/logout", headers={"Authorization": f"Bearer {token}"})
        stale = httpx.get(f"{server.url}/viser/", cookies={"proxima_view": token}, timeout=10)
        assert stale.status_code == 401


async def _first_message(url: str, **kwargs: object) -> bytes | str:
    async with connect(url, subprotocols=[SUBPROTOCOL], open_timeout=5, **kwargs) as ws:  # type: ignore[arg-type]
        assert ws.subprotocol == SUBPROTOCOL
        return await asyncio.wait_for(ws.recv(), timeout=10)


def test_the_websocket_is_proxied_for_a_session_of_this_origin_only(console) -> None:  # type: ignore[no-untyped-def]
    _, server = console
    ws_url = server.url.replace("http://", "ws://") + "/viser"
    with httpx.Client(base_url=server.url, timeout=10) as c:
        token, _ = _login(c)
    cookie = {"Cookie": f"proxima_view={token}"}
    # viser's scene arrives through the console (msgpack frames, as viser sends them).
    message = asyncio.run(_first_message(ws_url, additional_headers=cookie))
    assert isinstance(message, bytes) and message
    for headers in ({}, {"Cookie": "proxima_view=not-a-session"},
                    {**cookie, "Origin": "http://evil.example"}):  # fmt: skip
        with pytest.raises(websockets.InvalidStatus) as refused:
            asyncio.run(_first_message(ws_url, additional_headers=headers))
        assert refused.value.response.status_code == 403
    same_origin = {**cookie, "Origin": server.url}
    assert asyncio.run(_first_message(ws_url, additional_headers=same_origin))


def test_an_open_view_closes_when_its_session_ends(console, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    _, server = console
    monkeypatch.setattr(view_router, "SESSION_CHECK_S", 0.3)
    ws_url = server.url.replace("http://", "ws://") + "/viser"
    with httpx.Client(base_url=server.url, timeout=10) as c:
        token, _ = _login(c)

        async def watch() -> float:
            headers = {"Cookie": f"proxima_view={token}"}
            async with connect(
                ws_url, subprotocols=[SUBPROTOCOL], additional_headers=headers
            ) as ws:
                await asyncio.wait_for(ws.recv(), timeout=10)
                await asyncio.to_thread(
                    c.post, "/api/auth/logout", headers={"Authorization": f"Bearer {token}"}
                )
                loop = asyncio.get_running_loop()
                start = loop.time()
                with pytest.raises(websockets.ConnectionClosed):
                    while True:
                        await asyncio.wait_for(ws.recv(), timeout=5)
                return loop.time() - start

        assert asyncio.run(watch()) < 3.0
