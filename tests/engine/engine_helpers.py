"""Helpers for the engine tests: run the real engine on replayed streams and keep its
events (every event but poses, as dicts)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from proxima.control import ControlSettings
from proxima.engine import Engine, StreamSpec
from proxima.events import EventBus


def collect(engine_args: dict[str, Any], specs: list[StreamSpec]) -> tuple[list[dict], Engine]:
    """Run the engine (not paced unless `engine_args` says so); its events and itself."""
    bus = EventBus()
    events: list[dict] = []
    bus.add_listener(lambda e: events.append(e.to_dict()) if e.type != "pose" else None)
    engine = Engine(specs, bus, **{"realtime": False, **engine_args})
    engine.run()
    return events, engine


def replay(csv: Path, classifier: Any, **control: Any) -> list[dict]:
    """The events of one replayed stream, `control` over the default `ControlSettings`."""
    spec = StreamSpec(name="main", uri=f"replay:{csv}")
    return collect({"control": ControlSettings(**control), "classifier": classifier}, [spec])[0]


def commands(events: list[dict]) -> list[str]:
    return [e["command"] for e in events if e["type"] == "command"]
