"""The WebSocket hub over real sockets: handshake auth, events from a replayed LASER clip,
a stream's state as the console's own reducer made it, newest-wins per key for a slow
browser, and a bus that never waits on a browser."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import pytest
from api_helpers import ADMIN, laser_clip, make_settings
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from proxima.api import create_app
from proxima.api.hub import MESSAGE_TYPES, coalesce_key
from proxima.api.live import STATE_ONLY_TYPES, LiveState, StreamLive
from proxima.api.server import BackgroundServer
from proxima.drone.events import DroneStateEvent
from proxima.events import (
    ArmingEvent,
    CommandEvent,
    EventBus,
    GestureEvent,
    HandoverEvent,
    PoseEvent,
    StreamEvent,
)
from proxima.ingest import read_landmark_csv


@dataclass
class Live:
    bus: EventBus
    ws_url: str
    token: str
    state: LiveState


@pytest.fixture
def live(tmp_path: Path) -> Iterator[Live]:
    bus = EventBus()
    app = create_app(make_settings(tmp_path), bus)
    with BackgroundServer(app) as server:
        import httpx

        r = httpx.post(
            f"{server.url}/api/auth/login", json={"username": ADMIN[0], "password": ADMIN[1]}
        )
        url = f"ws://127.0.0.1:{server.port}/api/ws"
        yield Live(bus, url, r.json()["token"], app.state.console.live)


def _poses(clip: str, stream: str) -> list[PoseEvent]:
    track = read_landmark_csv(laser_clip(clip))
    return [
        PoseEvent(
            t=(int(f) - 1) / 30,
            stream=stream,
            xyz=xyz.tolist(),
            visibility=vis.tolist(),
            sight="full",
        )
        for f, xyz, vis in zip(track.frames, track.xyz, track.visibility, strict=True)
    ]


def _recv_until(ws, pred, timeout: float = 5.0) -> list[dict]:  # type: ignore[no-untyped-def]
    got = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            msg = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        except TimeoutError:
            break
        got.append(msg)
        if pred(msg):
            return got
    raise AssertionError(f"condition not met; received {[m['type'] for m in got][-10:]}")


def test_handshake_needs_a_session(live: Live) -> None:
    with pytest.raises(InvalidStatus) as err:
        connect(live.ws_url, open_timeout=5)
    assert err.value.response.status_code == 403
    with pytest.raises(InvalidStatus):
        connect(live.ws_url, subprotocols=["proxima", "forged-token"], open_timeout=5)


def test_events_reach_the_browser(live: Live) -> None:
    poses = _poses("move_to_left_f", "front")[:90]
    with connect(live.ws_url, subprotocols=["proxima", live.token]) as ws:
        assert ws.subprotocol == "proxima"
        hello = json.loads(ws.recv(timeout=5))
        assert hello["type"] == "hello" and hello["user"]["username"] == ADMIN[0]
        assert [s["name"] for s in hello["streams"]] == ["front", "left"]
        got = []
        for pose in poses:  # at the replay's pace: a fast browser gets every one
            live.bus.publish(pose)
            got += _recv_until(ws, lambda m: m["type"] == "pose")
            time.sleep(0.005)
        received = [m for m in got if m["type"] == "pose"]
        assert len(received) == len(poses)
        first = received[0]
        assert first["stream"] == "front" and len(first["xyz"]) == 33
        assert first["xyz"][0] == pytest.approx(poses[0].xyz[0], abs=1e-4)
        assert time.time() - first["ts"] < 5


def test_a_stream_state_arrives_as_the_consoles_own(live: Live) -> None:
    pose = _poses("hover_f", "front")[0]
    with connect(live.ws_url, subprotocols=["proxima", live.token]) as ws:
        hello = json.loads(ws.recv(timeout=5))
        assert hello["streams"][0]["live"] == json.loads(json.dumps(asdict(StreamLive())))
        live.bus.publish(StreamEvent(t=0.0, stream="front", state="live"))
        thumb = ["all_clear", "not_clear"]
        live.bus.publish(GestureEvent(t=2.0, stream="front", gesture="all_clear",
                                      confidence=0.9, probs=[], withheld=thumb))  # fmt: skip
        live.bus.publish(ArmingEvent(t=2.0, stream="front", armed=True, reason="have_command"))
        live.bus.publish(
            HandoverEvent(t=2.0, stream="front", from_stream="", to_stream="front", reason="x")
        )
        got = _recv_until(
            ws, lambda m: m["type"] == "stream_live" and m["driving"] and m["live"]["armed"]
        )
        state = got[-1]
        assert state["stream"] == "front"
        assert state["live"] == json.loads(json.dumps(asdict(live.state.streams()["front"])))
        assert state["live"]["gesture"] == "all_clear" and state["live"]["withheld"] == thumb
        # A first pose changes the state (the sight); a later one with the same sight only
        # the pose time, so it sends the pose alone.
        for t in (3.0, 3.1):
            live.bus.publish(PoseEvent(t=t, stream="front", xyz=pose.xyz,
                                       visibility=pose.visibility, sight="partial"))  # fmt: skip
        posed = _recv_until(ws, lambda m: m["type"] == "pose" and m["t"] == 3.1)
        assert [m["live"]["sight"] for m in posed if m["type"] == "stream_live"] == ["partial"]
        live.bus.publish(
            HandoverEvent(t=4.0, stream="", from_stream="front", to_stream="", reason="ended")
        )
        got += posed + _recv_until(ws, lambda m: m["type"] == "stream_live" and not m["driving"])
    kinds = {m["type"] for m in got}
    assert kinds <= set(MESSAGE_TYPES) and not kinds & STATE_ONLY_TYPES


def test_slow_browser_gets_newest_per_key_and_never_stalls_the_bus(live: Live) -> None:
    front = _poses("move_to_left_f", "front")
    left = _poses("move_to_left_l", "left")
    n = min(len(front), len(left))
    with connect(live.ws_url, subprotocols=["proxima", live.token], max_queue=4) as ws:
        json.loads(ws.recv(timeout=5))  # hello; then the browser stops reading
        worst = 0.0
        start = time.perf_counter()
        for i in range(n):
            for event in (front[i], left[i]):
                t0 = time.perf_counter()
                live.bus.publish(event)
                worst = max(worst, time.perf_counter() - t0)
            if i % 50 == 0:
                live.bus.publish(
                    CommandEvent(t=front[i].t, stream="front", command=f"c{i}", drone="main")
                )
                live.bus.publish(
                    DroneStateEvent(
                        t=float(i), drone="main", link="ok", position=[float(i), 0.0, -2.0]
                    )
                )
        elapsed = time.perf_counter() - start
        # Publishing 2 x ~800 poses never waited for the browser.
        assert worst < 0.05, f"a publish took {worst * 1000:.1f} ms"
        assert elapsed / (2 * n) < 0.002
        # Now the browser reads everything that is left.
        last_front = front[n - 1].t
        got = _recv_until(
            ws,
            lambda m: m["type"] == "pose" and m["stream"] == "front" and m["t"] == last_front,
            timeout=10,
        )
        poses_in = [m for m in got if m["type"] == "pose"]
        commands = [m["command"] for m in got if m["type"] == "command"]
        # Far fewer poses than published (coalesced), every command, in order.
        assert len(poses_in) < n
        assert commands == [f"c{i}" for i in range(0, n, 50)]
        states = [m for m in got if m["type"] == "drone_state"]
        assert states[-1]["position"][0] == float((n - 1) // 50 * 50)


def test_coalescing_keys() -> None:
    assert coalesce_key(PoseEvent(t=0, stream="a", xyz=[], visibility=[], sight="full")) == (
        "pose",
        "a",
    )
    assert coalesce_key(DroneStateEvent(t=0, drone="d1", link="ok")) == ("drone_state", "d1")
    assert coalesce_key(CommandEvent(t=0, stream="a", command="land", drone="d1")) is None
