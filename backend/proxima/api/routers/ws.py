"""`/api/ws`: the one WebSocket; authenticated at the handshake, then the hub pushes."""

from __future__ import annotations

import time
from typing import Any

from fastapi import APIRouter, WebSocket, status

from proxima.api.auth import WS_SUBPROTOCOL, token_from
from proxima.api.routers.drones import drone_list
from proxima.api.routers.streams import stream_list
from proxima.api.schemas import CommandLogRow, Hello, UserOut
from proxima.store.users import user_for_token

router = APIRouter(tags=["ws"])


@router.websocket("/ws")
async def websocket_endpoint(websocket: WebSocket) -> None:
    console = websocket.app.state.console
    token = token_from(websocket)
    user = None
    if token is not None:
        with console.sessions() as db:
            user = user_for_token(db, token)
    if user is None or user.must_change_password:
        # Refused during the handshake: the browser sees a failed connection (403).
        await websocket.close(code=status.WS_1008_POLICY_VIOLATION)
        return
    offered = [p.strip() for p in websocket.headers.get("sec-websocket-protocol", "").split(",")]
    await websocket.accept(subprotocol=WS_SUBPROTOCOL if WS_SUBPROTOCOL in offered else None)
    me = UserOut(
        username=user.username, role=user.role, must_change_password=user.must_change_password
    )

    def hello() -> dict[str, Any]:
        return Hello(
            ts=time.time(),
            user=me,
            streams=stream_list(console),
            drones=drone_list(console),
            commands=console.live.commands()[:50],
            alarms=console.alarms.recent() if console.alarms else [],
            command_log=[
                CommandLogRow.model_validate(r) for r in console.command_log.recent(limit=200)
            ],
        ).model_dump(mode="json")

    console.hub.start()
    await console.hub.serve(websocket, user.username, hello)
