"""The 3D view through the console: `/viser/` (its page) and the WebSocket viser's client
opens at `/viser`, both proxied to the viser server, which listens on
`server.viser_host` (127.0.0.1) on a port no browser is told.

Both need a console session, carried by the `proxima_view` cookie (see
`proxima.api.auth`): viser's client can send neither a header nor our subprotocol, and
drops the query string from its WebSocket URL. A WebSocket from another origin is
refused, and an open one is closed once its session ends (logout, expiry, account
disabled). Not part of the API schema: these are a page and a socket, not JSON.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

import httpx
import websockets
from fastapi import APIRouter, HTTPException, Request, WebSocket, status
from fastapi.responses import RedirectResponse, Response
from starlette.requests import HTTPConnection
from websockets.asyncio.client import ClientConnection, connect

from proxima.api.auth import VIEW_COOKIE, VIEW_PATH
from proxima.store.users import user_for_token

router = APIRouter(include_in_schema=False)
log = logging.getLogger(__name__)

SESSION_CHECK_S = 15.0  # how often an open 3D view's session is checked again
MAX_MESSAGE = 64 * 1024 * 1024  # viser sends whole meshes in one message
# Headers of viser's answers that the browser gets; hop-by-hop and length ones are ours.
PASSED_HEADERS = ("content-type", "content-encoding", "cache-control", "last-modified", "etag")


def _session_valid(conn: HTTPConnection) -> bool:
    """Whether the request's view cookie holds a live session of an enabled user whose
    password is their own."""
    token = conn.cookies.get(VIEW_COOKIE)
    if not token:
        return False
    with conn.app.state.console.sessions() as db:
        user = user_for_token(db, token)
        return user is not None and not user.must_change_password


def _same_origin(conn: HTTPConnection) -> bool:
    """A request without Origin (not a browser) or from the console's own origin."""
    origin = conn.headers.get("origin")
    if origin is None:
        return True
    host = conn.headers.get("host", "")
    return origin.split("://", 1)[-1].rstrip("/") == host


def _upstream(conn: HTTPConnection) -> tuple[str, int] | None:
    console = conn.app.state.console
    if console.viz_port is None:
        return None
    return console.settings.server.viser_host, console.viz_port


@router.get(VIEW_PATH)
def view_root() -> RedirectResponse:
    return RedirectResponse(f"{VIEW_PATH}/", status_code=status.HTTP_307_TEMPORARY_REDIRECT)


@router.api_route(f"{VIEW_PATH}/{{path:path}}", methods=["GET", "HEAD"])
async def view_page(path: str, request: Request) -> Response:
    """viser's page and files, for a logged-in browser."""
    if not _session_valid(request):
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED, "log in to the console to open the 3D view"
        )
    upstream = _upstream(request)
    if upstream is None:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE, "the 3D view does not run in this server"
        )
    host, port = upstream
    # The body is passed on as viser encoded it (gzip when the browser accepts it).
    encoding = request.headers.get("accept-encoding", "identity")
    async with httpx.AsyncClient(trust_env=False, timeout=10.0) as client:
        try:
            async with client.stream(
                request.method,
                f"http://{host}:{port}/{path}",
                params=request.query_params,
                headers={"accept-encoding": encoding},
            ) as answer:
                body = b"".join([chunk async for chunk in answer.aiter_raw()])
        except httpx.HTTPError as exc:
            raise HTTPException(
                status.HTTP_503_SERVICE_UNAVAILABLE, f"the 3D view does not answer: {exc}"
            ) from None
    headers = {k: v for k, v in answer.headers.items() if k.lower() in PASSED_HEADERS}
    headers["cache-control"] = "no-store"  # behind a login: never in a shared cache
    headers["content-security-policy"] = "frame-ancestors 'self'"  # only the console frames it
    return Response(body, status_code=answer.status_code, headers=headers)


async def _pump_to_viser(websocket: WebSocket, upstream: ClientConnection) -> None:
    while True:
        message = await websocket.receive()
        if message["type"] == "websocket.disconnect":
            return
        data = message.get("bytes")
        await upstream.send(data if data is not None else message.get("text", ""))


async def _pump_to_browser(websocket: WebSocket, upstream: ClientConnection) -> None:
    async for data in upstream:
        if isinstance(data, bytes):
            await websocket.send_bytes(data)
        else:
            await websocket.send_text(data)


async def _watch_session(websocket: WebSocket) -> None:
    while True:
        await asyncio.sleep(SESSION_CHECK_S)
        if not await asyncio.to_thread(_session_valid, websocket):
            return


@router.websocket(VIEW_PATH)
@router.websocket(f"{VIEW_PATH}/{{path:path}}")
async def view_socket(websocket: WebSocket, path: str = "") -> None:
    """viser's WebSocket, for a logged-in browser of the console's own origin; refused
    during the handshake (HTTP 403) otherwise."""
    upstream_at = _upstream(websocket)
    if upstream_at is None or not _same_origin(websocket) or not _session_valid(websocket):
        await websocket.close(code=status.WS_1008_POLICY_VIOLATION)
        return
    offered = [p.strip() for p in websocket.headers.get("sec-websocket-protocol", "").split(",")]
    host, port = upstream_at
    try:
        upstream = await connect(
            f"ws://{host}:{port}/",
            subprotocols=[websockets.Subprotocol(p) for p in offered if p] or None,
            compression=None,
            max_size=MAX_MESSAGE,
            proxy=None,
            open_timeout=5,
        )
    except (OSError, TimeoutError, websockets.WebSocketException) as exc:
        log.warning("3D view: cannot reach viser at %s:%d: %s", host, port, exc)
        await websocket.close(code=status.WS_1011_INTERNAL_ERROR)
        return
    async with upstream:
        await websocket.accept(subprotocol=upstream.subprotocol)
        tasks = [
            asyncio.create_task(_pump_to_viser(websocket, upstream)),
            asyncio.create_task(_pump_to_browser(websocket, upstream)),
            asyncio.create_task(_watch_session(websocket)),
        ]
        try:
            await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
        finally:
            for task in tasks:
                task.cancel()
            # The other side's end (a closed socket, a disconnect) is how pumps stop.
            await asyncio.gather(*tasks, return_exceptions=True)
    with contextlib.suppress(RuntimeError):  # already closed by the browser
        await websocket.close()
