from __future__ import annotations

import json
import threading
import time

from proxima.events import CommandEvent, EventBus, GestureEvent, PoseEvent


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
