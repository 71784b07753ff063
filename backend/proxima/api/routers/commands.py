"""The command log. `GET /commands`: the durable log every drone command is written to
(with its acknowledgement and outcome); `GET /commands/live`: the commands the engine
decided since this server started, as seen on the bus (also when no drone is linked)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from proxima.api.deps import ConsoleDep, CurrentUser
from proxima.api.live import LiveCommand

router = APIRouter(prefix="/commands", tags=["commands"])


@router.get("")
def command_log(
    _: CurrentUser,
    console: ConsoleDep,
    drone: str | None = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> list[dict[str, Any]]:
    return console.command_log.recent(limit=limit, drone=drone)


@router.get("/live")
def live_commands(
    _: CurrentUser,
    console: ConsoleDep,
    drone: str | None = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> list[LiveCommand]:
    rows = console.live.commands()
    if drone is not None:
        rows = [r for r in rows if r.drone == drone]
    return rows[:limit]
