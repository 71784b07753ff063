"""The WebSocket hub: bus events and the console's live state to browsers, newest-wins
per key.

The bus publishes on engine threads; the hub lives in the server's asyncio loop. The
bus listener only stores the event in a dict under a lock and, if no hand-over is
pending, schedules one with `call_soon_threadsafe`; recognition never waits on a
browser. The events a stream's state is reduced from (`live.STATE_ONLY_TYPES`) are not
forwarded: when `LiveState` reports a stream changed, the hub sends that stream's
`stream_live` message instead, read from `LiveState` when it is encoded, so it is always
the newest. In the loop each message is encoded once and offered to every client. A
client holds one pending message per key (a stream's pose or state, a drone's
telemetry, ...), so a slow browser gets the newest value of each key instead of a
growing backlog; messages without a key (commands, command results, alarms, training
rounds) queue in order, bounded, oldest dropped and counted.

Every message type is in `MESSAGE_TYPES`; the browser's types are generated from them
(`proxima.api.typegen`).
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import json
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np
from starlette.websockets import WebSocket, WebSocketDisconnect

from proxima.api.events import RecordingEvent, ThumbnailEvent
from proxima.api.live import STATE_ONLY_TYPES, LiveState, StreamLiveMessage
from proxima.drone.events import DroneStateEvent
from proxima.events import EVENT_TYPES, EventBus, PoseEvent
from proxima.types import Event

# Every `type` a browser can receive: the hub's own messages and the forwarded events.
MESSAGE_TYPES: tuple[str, ...] = (
    "hello",
    StreamLiveMessage.type,
    *(name for name in EVENT_TYPES if name not in STATE_ONLY_TYPES),
)

Key = tuple[Any, ...]


def coalesce_key(event: Event) -> Key | None:
    """The key under which newer events replace older ones, or None to keep them all."""
    match event:
        case PoseEvent() | ThumbnailEvent():
            return (event.type, event.stream)
        case DroneStateEvent():
            return (event.type, event.drone or event.stream)
        case RecordingEvent():
            return (event.type, event.recording)
    return None


def _json_default(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, bytes):
        return base64.b64encode(value).decode()
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def encode_event(event: Event, published: float) -> str:
    """One event as the JSON text a browser gets; `ts` is the wall time it was published
    (for latency), pose coordinates are rounded to 4 decimals to keep frames small."""
    msg = event.to_dict()
    if isinstance(event, PoseEvent):
        msg["xyz"] = np.round(np.asarray(event.xyz, dtype=np.float64), 4).tolist()
        msg["visibility"] = np.round(np.asarray(event.visibility, dtype=np.float64), 3).tolist()
    msg["ts"] = published
    return json.dumps(msg, default=_json_default, separators=(",", ":"))


def encode_state(message: StreamLiveMessage, published: float) -> str:
    """A stream's `stream_live` message as JSON text, `ts` as for events."""
    return json.dumps({**asdict(message), "ts": published}, separators=(",", ":"))


@dataclass(eq=False)
class _Client:
    websocket: WebSocket
    user: str
    max_unkeyed: int
    pending: OrderedDict[Key, str] = field(default_factory=OrderedDict)
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    unkeyed: int = 0
    sent: int = 0
    coalesced: int = 0
    dropped: int = 0

    def offer(self, key: Key, keyed: bool, text: str) -> None:
        if key in self.pending:
            del self.pending[key]
            self.coalesced += 1
        self.pending[key] = text
        if not keyed:
            self.unkeyed += 1
            while self.unkeyed > self.max_unkeyed:
                for k in self.pending:
                    if k[0] == "#":
                        del self.pending[k]
                        self.unkeyed -= 1
                        self.dropped += 1
                        break
        self.wake.set()

    def take(self) -> tuple[Key, str] | None:
        if not self.pending:
            return None
        key, text = self.pending.popitem(last=False)
        if key[0] == "#":
            self.unkeyed -= 1
        return key, text


class WebSocketHub:
    """Fans bus events and `live`'s stream states out to connected browsers; start it
    inside the server's loop."""

    def __init__(self, bus: EventBus, live: LiveState, max_unkeyed: int = 500) -> None:
        self.bus = bus
        self.live = live
        self.max_unkeyed = max_unkeyed
        self._lock = threading.Lock()
        # A key's newest event, or the name of a stream whose state changed.
        self._incoming: OrderedDict[Key, tuple[Event | str, float]] = OrderedDict()
        self._seq = itertools.count()
        self._scheduled = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._clients: set[_Client] = set()
        self._listening = False
        self.events_in = 0
        self.events_coalesced = 0

    # -- bus side (any thread) -------------------------------------------------
    def _on_event(self, event: Event) -> None:
        if event.type in STATE_ONLY_TYPES:
            return
        key = coalesce_key(event)
        self._enqueue(("#", next(self._seq)) if key is None else key, event)

    def _on_stream_change(self, stream: str) -> None:
        self._enqueue((StreamLiveMessage.type, stream), stream)

    def _enqueue(self, key: Key, item: Event | str) -> None:
        loop = self._loop
        if loop is None or not self._clients:
            return
        now = time.time()
        with self._lock:
            self.events_in += 1
            if key in self._incoming:
                del self._incoming[key]
                self.events_coalesced += 1
            self._incoming[key] = (item, now)
            if self._scheduled:
                return
            self._scheduled = True
        with contextlib.suppress(RuntimeError):  # loop closed during shutdown
            loop.call_soon_threadsafe(self._flush)

    # -- loop side -------------------------------------------------------------
    def start(self) -> None:
        """Bind to the running loop and listen to the bus (idempotent)."""
        self._loop = asyncio.get_running_loop()
        if not self._listening:
            self.bus.add_listener(self._on_event)
            self.live.watch(self._on_stream_change)
            self._listening = True

    def stop(self) -> None:
        self._loop = None
        for client in list(self._clients):
            client.wake.set()

    def _flush(self) -> None:
        with self._lock:
            batch = self._incoming
            self._incoming = OrderedDict()
            self._scheduled = False
        for key, (item, published) in batch.items():
            if isinstance(item, str):
                text = encode_state(self.live.stream_message(item), published)
            else:
                text = encode_event(item, published)
            keyed = key[0] != "#"
            for client in self._clients:
                client.offer(key, keyed, text)

    def stats(self) -> dict[str, Any]:
        return {
            "clients": [
                {
                    "user": c.user,
                    "sent": c.sent,
                    "coalesced": c.coalesced,
                    "dropped": c.dropped,
                    "pending": len(c.pending),
                }
                for c in self._clients
            ],
            "events_in": self.events_in,
            "events_coalesced_before_loop": self.events_coalesced,
        }

    async def serve(
        self, websocket: WebSocket, user: str, hello: Callable[[], dict[str, Any]]
    ) -> None:
        """Run one accepted browser connection until it closes. `hello()` makes the first
        message; it is called once the client is registered, so no change after it is
        missed (one just before it may come again after it: newest wins)."""
        client = _Client(websocket=websocket, user=user, max_unkeyed=self.max_unkeyed)
        self._clients.add(client)
        receiver = asyncio.create_task(self._receive(client))
        try:
            await websocket.send_text(json.dumps(hello(), default=_json_default))
            while not receiver.done() and self._loop is not None:
                item = client.take()
                if item is None:
                    client.wake.clear()
                    waiter = asyncio.create_task(client.wake.wait())
                    await asyncio.wait({waiter, receiver}, return_when=asyncio.FIRST_COMPLETED)
                    waiter.cancel()
                    continue
                await websocket.send_text(item[1])
                client.sent += 1
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass
        finally:
            self._clients.discard(client)
            receiver.cancel()
            with contextlib.suppress(Exception):
                await websocket.close()

    async def _receive(self, client: _Client) -> None:
        """Read until the browser closes (it sends nothing the hub answers)."""
        while True:
            msg = await client.websocket.receive()
            if msg["type"] == "websocket.disconnect":
                return
