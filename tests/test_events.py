from __future__ import annotations

import ast
import json
import threading
import time
from dataclasses import fields
from pathlib import Path

import pytest

import proxima
from proxima.events import EVENT_TYPES, CommandEvent, EventBus, GestureEvent, PoseEvent
from proxima.types import Event


def test_subscribers_get_their_types_in_order() -> None:
    bus = EventBus()
    commands = bus.subscribe(types=["command"])
    everything = bus.subscribe()
    bus.publish(GestureEvent(t=0.5, stream="front", gesture="hover", confidence=0.9, probs=[]))
    bus.publish(CommandEvent(t=1.0, stream="front", command="hover", drone="main"))
    assert [e.type for e in everything.drain()] == ["gesture", "command"]
    got = commands.get(timeout=1)
    assert isinstance(got, CommandEvent) and got.drone == "main"
    assert commands.get(timeout=0.01) is None


def test_a_slow_subscriber_never_blocks_the_publisher() -> None:
    bus = EventBus()
    slow = bus.subscribe(maxsize=10)  # never read while publishing
    t0 = time.perf_counter()
    for i in range(10_000):
        bus.publish(PoseEvent(t=i / 30, stream="s", xyz=[], visibility=[], sight="full"))
    assert time.perf_counter() - t0 < 5  # generous: the point is it returns at all
    kept = slow.drain()
    assert len(kept) == 10 and slow.dropped == 9_990
    assert kept[-1].t == 9_999 / 30  # the newest survive


def test_get_wakes_on_publish_and_on_close() -> None:
    bus = EventBus()
    sub = bus.subscribe()
    got = []
    reader = threading.Thread(target=lambda: got.append(sub.get(timeout=5)))
    reader.start()
    bus.publish(CommandEvent(t=2.0, command="land", drone="main"))
    reader.join(2)
    assert got and got[0].command == "land"
    sub.close()
    assert sub.get(timeout=5) is None  # returns at once once closed
    bus.publish(CommandEvent(t=3.0, command="land", drone="main"))
    assert sub.drain() == []  # unsubscribed


def test_events_serialise_to_json_with_type_and_time() -> None:
    d = CommandEvent(t=1.25, stream="left", command="move_to_left", drone="main").to_dict()
    assert json.loads(json.dumps(d)) == {
        "type": "command", "t": 1.25, "stream": "left", "command": "move_to_left",
        "drone": "main",
    }  # fmt: skip


def _source() -> list[ast.AST]:
    return [
        ast.parse(path.read_text(encoding="utf-8"))
        for path in Path(proxima.__file__).parent.rglob("*.py")
    ]


def test_one_registry_lists_every_event_type() -> None:
    bases = {"Event", *(cls.__name__ for cls in EVENT_TYPES.values())}
    defined = {
        node.name
        for tree in _source()
        for node in ast.walk(tree)
        if isinstance(node, ast.ClassDef)
        and any(isinstance(b, ast.Name) and b.id in bases for b in node.bases)
    }
    assert defined == {cls.__name__ for cls in EVENT_TYPES.values()}
    for name, cls in EVENT_TYPES.items():
        assert issubclass(cls, Event) and cls.type == name
        assert "type" not in {f.name for f in fields(cls) if f.init}  # fixed per class


def test_subscribing_to_a_type_nobody_publishes_is_refused() -> None:
    bus = EventBus()
    with pytest.raises(ValueError, match="no event type 'fl_round'"):
        bus.subscribe(types=["training_round", "fl_round"])
    bus.subscribe(types=["training_round"]).close()


def test_every_event_type_has_a_publisher() -> None:
    made = {
        node.func.id
        for tree in _source()
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
    }
    assert {cls.__name__ for cls in EVENT_TYPES.values()} <= made
