"""The command log: every command decided for a drone, newest first."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from proxima.api.deps import ConsoleDep, CurrentUser

router = APIRouter(prefix="/commands", tags=["commands"])


@router.get("")
def list_commands(
    _: CurrentUser,
    console: ConsoleDep,
    drone: str | None = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> list[dict[str, Any]]:
    rows = console.live.commands()
    if drone is not None:
        rows = [r for r in rows if r.get("drone") == drone]
    return rows[:limit]
