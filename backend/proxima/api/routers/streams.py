"""Camera streams: configuration merged with their newest live state."""

from __future__ import annotations

import re

from fastapi import APIRouter, HTTPException, status

from proxima.api.deps import ConsoleDep, CurrentUser
from proxima.api.live import StreamLive
from proxima.api.schemas import StreamOut
from proxima.api.services import Console

router = APIRouter(prefix="/streams", tags=["streams"])

_CREDENTIALS = re.compile(r"^(\w+://)[^/@]*@")


def public_uri(uri: str) -> str:
    """The URI with any user:password@ part hidden."""
    return _CREDENTIALS.sub(r"\1***@", uri)


def stream_list(console: Console) -> list[StreamOut]:
    live = console.live.streams()
    driving = console.live.driving_stream
    out = []
    for s in sorted(console.settings.streams, key=lambda s: (s.priority, s.name)):
        out.append(
            StreamOut(
                name=s.name,
                uri=public_uri(s.uri),
                kind=s.kind,
                drone=s.drone,
                priority=s.priority,
                configured=True,
                driving=driving == s.name,
                handover_reason=console.live.handover_reason,
                live=live.pop(s.name, StreamLive()),
            )
        )
    for name, state in sorted(live.items()):  # streams seen on the bus only
        out.append(
            StreamOut(
                name=name,
                uri="",
                kind="unknown",
                drone="",
                priority=len(out),
                configured=False,
                driving=driving == name,
                handover_reason=console.live.handover_reason,
                live=state,
            )
        )
    return out


@router.get("")
def list_streams(_: CurrentUser, console: ConsoleDep) -> list[StreamOut]:
    return stream_list(console)


@router.get("/{name}")
def get_stream(name: str, _: CurrentUser, console: ConsoleDep) -> StreamOut:
    for s in stream_list(console):
        if s.name == name:
            return s
    raise HTTPException(status.HTTP_404_NOT_FOUND, f"no stream {name!r}")
