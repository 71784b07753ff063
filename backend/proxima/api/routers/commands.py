"""The command log. `GET /commands`: the durable log every drone command is written to
(with its acknowledgement and outcome); `GET /commands/live`: the commands the engine
decided since this server started, as seen on the bus (also when no drone is linked)."""

from __future__ import annotations

import csv
import io
from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.responses import Response

from proxima.api.deps import ConsoleDep, CurrentUser
from proxima.api.live import LiveCommand

router = APIRouter(prefix="/commands", tags=["commands"])


@router.get("")
def command_log(
    _: CurrentUser,
    console: ConsoleDep,
    drone: str | None = None,
    status: str | None = None,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
) -> list[dict[str, Any]]:
    return console.command_log.recent(limit=limit, drone=drone, status=status)


CSV_COLUMNS = (
    "id", "created_at", "drone", "source", "command", "stream", "gesture_t", "confidence",
    "action", "status", "ack", "outcome", "reason", "attempts", "ack_latency_ms", "sent_at",
    "acked_at", "completed_at",
)  # fmt: skip


@router.get(
    "/export.csv",
    response_class=Response,
    responses={200: {"content": {"text/csv": {"schema": {"type": "string"}}}}},
)
def export_csv(
    _: CurrentUser,
    console: ConsoleDep,
    drone: str | None = None,
    status: str | None = None,
    limit: Annotated[int, Query(ge=1, le=100000)] = 10000,
) -> Response:
    """The durable command log as CSV (newest first), filtered like `GET /commands`."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, extrasaction="ignore")
    writer.writeheader()
    for row in console.command_log.recent(limit=limit, drone=drone, status=status):
        writer.writerow(row)
    return Response(
        buf.getvalue(),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="command-log.csv"'},
    )


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
